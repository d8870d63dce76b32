"""The x86-64 level a build is compiled for (CMake's TRUEANISO_ARCH, trueaniso/buildarch.py): CMake
refuses a level whose bits would depend on the compiling host, the module refuses to load on a
processor without its level (a message, not an illegal instruction), and a build for another
level is another code version, so that a study or specimen made by one is not continued by the
other. The speed of a v3 build and its agreement with the baseline: docs/benchmarks.md."""
import hashlib
import os
import subprocess
import sys

import pytest

from conftest import REPO
from trueaniso import buildarch, engines, provenance

V3 = set(buildarch.LEVEL_FLAGS["x86-64-v3"])


def test_each_level_asks_for_the_flags_of_the_levels_below_it():
    v2, v3, v4 = (set(buildarch.LEVEL_FLAGS[k]) for k in ("x86-64-v2", "x86-64-v3", "x86-64-v4"))
    assert v2 < v3 < v4 and {"fma", "avx2"} <= v3 and "avx512f" in v4 - v3


def test_missing_features_of_a_level():
    assert buildarch.missing_features("x86-64-v3", V3) == []
    assert buildarch.missing_features("x86-64-v3", V3 - {"fma", "avx2"}) == ["avx2", "fma"]
    assert buildarch.missing_features("x86-64-v4", V3) == ["avx512bw", "avx512cd", "avx512dq", "avx512f", "avx512vl"]
    assert buildarch.missing_features(buildarch.BASELINE, set()) == []
    assert buildarch.missing_features("x86-64-v3", None) == []  # flags unknown (not Linux): nothing refused


def test_cpu_flags_are_read_from_the_first_flags_line(tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nflags\t\t: fpu sse2 avx2 fma\n\nprocessor\t: 1\nflags\t\t: fpu\n")
    assert buildarch.cpu_flags(str(info)) == {"fpu", "sse2", "avx2", "fma"}
    assert buildarch.cpu_flags(str(tmp_path / "absent")) is None


def test_a_module_built_for_a_level_the_processor_lacks_is_refused_before_loading(tmp_path):
    (tmp_path / "_trueaniso.arch").write_text("x86-64-v3\n")
    with pytest.raises(ImportError, match=r"built for x86-64-v3 .* lacks avx2 fma; rebuild it here"):
        buildarch.refuse_unsupported(str(tmp_path), flags=V3 - {"fma", "avx2"})
    buildarch.refuse_unsupported(str(tmp_path), flags=V3)  # the level's own flags: loads
    os.remove(tmp_path / "_trueaniso.arch")  # a build from before the option: the baseline
    buildarch.refuse_unsupported(str(tmp_path), flags=set())


def test_the_package_checks_the_level_before_it_imports_the_module(tmp_path):
    """Through `trueaniso.engines`, in a fresh interpreter: the module of this build, beside a file
    saying x86-64-v3, on a processor reported without v3's flags, is refused with the message; the
    same with the processor's flags complete loads it."""
    build = tmp_path / "build" / "python"
    build.mkdir(parents=True)
    os.symlink(engines.__file__, build / os.path.basename(engines.__file__))
    (build / "_trueaniso.arch").write_text("x86-64-v3\n")
    env = dict(os.environ, TRUEANISO_BUILD=str(tmp_path / "build"), PYTHONPATH=os.path.join(REPO, "pyscripts"))
    probe = ("import trueaniso.buildarch as b; b.cpu_flags = lambda *a: %s; import trueaniso; "
             "print(trueaniso.engines.__file__)")
    lacking = subprocess.run([sys.executable, "-c", probe % "{'fpu'}"], env=env, capture_output=True, text=True)
    assert lacking.returncode != 0 and "built for x86-64-v3" in lacking.stderr and "lacks abm avx" in lacking.stderr
    whole = subprocess.run([sys.executable, "-c", probe % repr(V3)], env=env, capture_output=True, text=True)
    assert whole.returncode == 0 and whole.stdout.strip().startswith(str(build)), whole.stderr


def test_this_module_says_the_level_written_beside_it():
    assert engines.build_arch() == buildarch.module_level(os.path.dirname(engines.__file__))
    assert provenance.versions()["build"] == engines.build_arch()


def test_another_level_is_another_code_version(monkeypatch):
    package = provenance.manifest_hash(os.path.join(REPO, "pyscripts"), "trueaniso", (".py",))
    plain = "src-" + hashlib.sha256((engines.source_hash() + " " + package).encode()).hexdigest()[:16]
    monkeypatch.setattr(engines, "build_arch", lambda: buildarch.BASELINE)
    provenance.code_version.cache_clear()
    try:
        assert provenance.code_version() == plain  # the baseline: the versions of before the option
        monkeypatch.setattr(engines, "build_arch", lambda: "x86-64-v3")
        provenance.code_version.cache_clear()
        v3 = provenance.code_version()
        assert v3 != plain and v3.startswith("src-")
    finally:
        monkeypatch.undo()
        provenance.code_version.cache_clear()


@pytest.mark.parametrize("level", ["native", "znver3", "x86-64-v5"])
def test_cmake_refuses_a_level_that_is_not_a_named_x86_64_level(tmp_path, level):
    out = subprocess.run(["cmake", "-S", REPO, "-B", str(tmp_path / "b"), "-DTRUEANISO_ARCH=" + level],
                         capture_output=True, text=True)
    assert out.returncode != 0
    assert "TRUEANISO_ARCH=%s: one of x86-64-v2, x86-64-v3, x86-64-v4, or empty" % level in " ".join(out.stderr.split())


def test_a_study_of_another_level_says_which_and_how_to_continue_it(tmp_path):
    """A study made by a v3 build, rerun by this (baseline) build: refused as another code version,
    and the refusal names both levels and the build that continues it (the sources may be the same)."""
    from trueaniso import study_dir
    there = dict(code="src-aaaa", threads=1)
    study_dir.write_metadata(str(tmp_path), there, [(1, 0.0, 100e3)], ["z"],
                             dict(versions=dict(code="src-aaaa", build="x86-64-v3")))
    with pytest.raises(study_dir.StudyMismatch) as refused:
        study_dir.check(str(tmp_path), dict(there, code="src-bbbb"), [(1, 0.0, 100e3)])
    said = str(refused.value)
    assert "built for x86-64-v3, this run's for %s" % engines.build_arch() in said
    assert "continue it with a build for x86-64-v3 (TRUEANISO_ARCH=x86-64-v3 ./setup.sh" in said
    # the same level: only the code version is named, as before
    study_dir.write_metadata(str(tmp_path / "same"), there, [(1, 0.0, 100e3)], ["z"],
                             dict(versions=dict(code="src-aaaa", build=engines.build_arch())))
    with pytest.raises(study_dir.StudyMismatch) as refused:
        study_dir.check(str(tmp_path / "same"), dict(there, code="src-bbbb"), [(1, 0.0, 100e3)])
    assert "this run's for" not in str(refused.value) and "continue it with a build" not in str(refused.value)
