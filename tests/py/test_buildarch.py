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


def test_a_level_file_that_names_no_known_level_or_not_the_modules_is_refused(tmp_path):
    (tmp_path / "_trueaniso.arch").write_text("x86-64-v5\n")
    with pytest.raises(ImportError, match=r"built for 'x86-64-v5', not a level this code knows"):
        buildarch.refuse_unsupported(str(tmp_path), flags=V3)

    class Module:  # a module built for the baseline beside a file left by a configure for v3
        @staticmethod
        def build_arch():
            return "x86-64"
    (tmp_path / "_trueaniso.arch").write_text("x86-64-v3\n")
    with pytest.raises(ImportError, match="was built for x86-64, but _trueaniso.arch beside it says x86-64-v3"):
        buildarch.refuse_mismatch(str(tmp_path), Module)
    (tmp_path / "_trueaniso.arch").write_text("x86-64\n")
    buildarch.refuse_mismatch(str(tmp_path), Module)


def test_a_module_built_for_a_level_the_processor_lacks_is_refused_before_loading(tmp_path):
    (tmp_path / "_trueaniso.arch").write_text("x86-64-v3\n")
    with pytest.raises(ImportError, match=r"built for x86-64-v3 .* lacks avx2 fma; rebuild it here"):
        buildarch.refuse_unsupported(str(tmp_path), flags=V3 - {"fma", "avx2"})
    buildarch.refuse_unsupported(str(tmp_path), flags=V3)  # the level's own flags: loads
    os.remove(tmp_path / "_trueaniso.arch")  # a build from before the option: the baseline
    buildarch.refuse_unsupported(str(tmp_path), flags=set())


def test_the_package_checks_the_level_before_it_imports_the_module(tmp_path):
    """Through `trueaniso.engines`, in a fresh interpreter: the module of this build, beside a file
    saying x86-64-v3, on a processor reported without v3's flags, is refused with the message before
    it loads; with the processor's flags complete it loads, and the module's own level is then
    found to differ from the file's (this build is the baseline's) and refused too; with the file
    saying the module's own level it loads."""
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
    if engines.build_arch() == "x86-64-v3":  # this build is v3 itself: the file is its own
        assert whole.returncode == 0 and whole.stdout.strip().startswith(str(build)), whole.stderr
    else:
        assert whole.returncode != 0 and "beside it says x86-64-v3" in whole.stderr
    (build / "_trueaniso.arch").write_text(engines.build_arch() + "\n")
    own = subprocess.run([sys.executable, "-c", probe % repr(V3)], env=env, capture_output=True, text=True)
    assert own.returncode == 0 and own.stdout.strip().startswith(str(build)), own.stderr


def test_this_module_says_the_level_written_beside_it():
    assert engines.build_arch() == buildarch.module_level(os.path.dirname(engines.__file__))
    assert provenance.versions()["build"] == engines.build_arch()


def test_another_level_is_another_code_version(monkeypatch):
    package = provenance.manifest_hash(os.path.join(REPO, "pyscripts"), "trueaniso", (".py",), skip=("analysis",))
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
    said = " ".join(out.stderr.split())
    assert 'TRUEANISO_ARCH="%s" is not a level this build knows: give one of x86-64-v2, x86-64-v3, x86-64-v4' % level in said
    assert "This build directory keeps the portable baseline." in said


def _cache(build, key):
    for line in (build / "CMakeCache.txt").read_text().splitlines():
        if line.startswith(key + ":"):
            return line.split("=", 1)[1]
    return None


def test_a_refused_level_leaves_the_build_at_its_level_and_a_plain_configure_works(tmp_path):
    """After TRUEANISO_ARCH=native is refused, the cache keeps the level the build had (here v3,
    given as ' X86-64-V3': spaces and case are forgiven), not the refused value, on which every
    later plain ./setup.sh would fail: a plain configure succeeds at it."""
    build = tmp_path / "b"
    configure = ["cmake", "-S", REPO, "-B", str(build)]
    subprocess.run(configure + ["-DTRUEANISO_ARCH= X86-64-V3"], check=True, capture_output=True)
    assert _cache(build, "TRUEANISO_ARCH_ACCEPTED") == "x86-64-v3"
    refused = subprocess.run(configure + ["-DTRUEANISO_ARCH=native"], capture_output=True, text=True)
    assert refused.returncode != 0 and "This build directory keeps x86-64-v3." in " ".join(refused.stderr.split())
    assert _cache(build, "TRUEANISO_ARCH") == "x86-64-v3"
    plain = subprocess.run(configure, capture_output=True, text=True)
    assert plain.returncode == 0, plain.stderr
    assert _cache(build, "TRUEANISO_ARCH_ACCEPTED") == "x86-64-v3"
    assert (build / "engines" / "python" / "generated" / "_trueaniso.arch").read_text() == "x86-64-v3\n"
    assert not (build / "python" / "_trueaniso.arch").exists()  # beside the module only once it is built


def test_a_study_of_another_level_says_which_and_how_to_continue_it(tmp_path):
    """A study made by a build for another level (v3, or the baseline when this build is v3), rerun by
    this build: refused as another code version, and the refusal names both levels and the build
    that continues it (the sources may be the same)."""
    from trueaniso import study_dir
    other = "x86-64-v3" if engines.build_arch() == buildarch.BASELINE else buildarch.BASELINE
    # a whole fingerprint (metadata.json is checked against its schema before it is compared)
    there = dict(specimen="a" * 64, assembly="sphere", code="src-aaaa", threads=1, path="true-triaxial", state={},
                 probe={})
    study_dir.write_metadata(str(tmp_path), there, [(1, 0.0, 100e3)], ["z"],
                             dict(versions=dict(code="src-aaaa", build=other)))
    with pytest.raises(study_dir.StudyMismatch) as refused:
        study_dir.check(str(tmp_path), dict(there, code="src-bbbb"), [(1, 0.0, 100e3)])
    said = str(refused.value)
    assert "built for %s, this run's for %s" % (other, engines.build_arch()) in said
    assert "continue it with a build for %s (TRUEANISO_ARCH=%s ./setup.sh" % (
        other, "" if other == buildarch.BASELINE else other) in said
    # the same level: only the code version is named, as before
    study_dir.write_metadata(str(tmp_path / "same"), there, [(1, 0.0, 100e3)], ["z"],
                             dict(versions=dict(code="src-aaaa", build=engines.build_arch())))
    with pytest.raises(study_dir.StudyMismatch) as refused:
        study_dir.check(str(tmp_path / "same"), dict(there, code="src-bbbb"), [(1, 0.0, 100e3)])
    assert "this run's for" not in str(refused.value) and "continue it with a build" not in str(refused.value)
