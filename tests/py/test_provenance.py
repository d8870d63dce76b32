"""The code version a study is bound to (provenance.code_version): the engines' hash compiled into
the module equals the one computed from the tree by a second implementation, a module built from
other sources is refused, and an installation reports the same version as the tree it came from."""
import os
import shutil
import subprocess

import pytest

from conftest import REPO
from trueaniso import engines, provenance

SCRIPT = os.path.join(REPO, "cmake", "EngineSourceHash.cmake")


def _cmake_hash(root, tmp_path):
    out = tmp_path / "hash.hpp"
    subprocess.run(["cmake", "-DROOT=%s" % root, "-DOUT=%s" % out, "-P", SCRIPT], check=True, capture_output=True)
    return out.read_text().split('"')[1]


def test_python_and_cmake_hash_a_tree_alike(tmp_path):
    tree = tmp_path / "src"
    (tree / "engines" / "sub").mkdir(parents=True)
    (tree / "engines" / "a.cpp").write_text("int a;\n")
    (tree / "engines" / "sub" / "b.hpp").write_text("// b\n")
    (tree / "engines" / "notes.md").write_text("not a source\n")  # left out by both
    first = provenance.manifest_hash(str(tree), "engines", provenance.ENGINE_SUFFIXES)
    assert first == _cmake_hash(tree, tmp_path)
    (tree / "engines" / "notes.md").write_text("edited\n")
    assert provenance.manifest_hash(str(tree), "engines", provenance.ENGINE_SUFFIXES) == first
    (tree / "engines" / "sub" / "b.hpp").write_text("// b edited\n")
    assert provenance.manifest_hash(str(tree), "engines", provenance.ENGINE_SUFFIXES) != first


def test_the_module_was_built_from_the_engines_beside_it():
    assert engines.source_hash() == provenance.manifest_hash(REPO, "engines", provenance.ENGINE_SUFFIXES)
    assert provenance.engine_source_hash() == engines.source_hash()


def test_a_module_older_than_its_sources_is_refused(tmp_path):
    shutil.copytree(os.path.join(REPO, "engines"), tmp_path / "engines")
    with open(tmp_path / "engines" / "core" / "Types.hpp", "a") as f:
        f.write("// an edit not yet built\n")
    with pytest.raises(provenance.StaleBuild, match="rebuild"):
        provenance.engine_source_hash(str(tmp_path))


def test_a_preparation_keeps_the_code_version_it_started_with(tmp_path, monkeypatch):
    """The version written into a specimen is taken before the preparation starts: sources edited
    while an hour-long preparation runs (here: a check that refuses once the work has begun) no
    longer make its save refuse and lose the run (a 16,000-sphere preparation was lost so)."""
    import importlib.util
    import sys
    from conftest import SCRIPTS
    from trueaniso import specimen
    spec = importlib.util.spec_from_file_location("prepare_specimen_script", os.path.join(SCRIPTS, "prepare_specimen.py"))
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    started = []
    real_hash, real_prepare = provenance.engine_source_hash, specimen.prepare_spheres

    def hash_until_started(root=provenance.REPO_ROOT):
        if started:
            raise provenance.StaleBuild("engine sources edited during the run")
        return real_hash(root)

    def prepare(*args, **kw):
        started.append(True)
        return real_prepare(*args, **kw)

    monkeypatch.setattr(provenance, "engine_source_hash", hash_until_started)
    monkeypatch.setattr(specimen, "prepare_spheres", prepare)
    provenance.code_version.cache_clear()
    out = tmp_path / "s.npz"
    monkeypatch.setattr(sys, "argv", ["prepare_specimen.py", "--n", "60", "--seed", "2", "--threads", "1", "--quiet",
                                      "--out", str(out)])
    try:
        script.main()
    finally:
        provenance.code_version.cache_clear()  # later tests compute it from the real check again
    assert started and out.exists()
