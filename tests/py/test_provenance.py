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
