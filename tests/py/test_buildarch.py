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
    env.pop(buildarch.LEVEL_ENV, None)  # the suite's baseline (conftest.py): this fake build has one level only
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


def _modules(tmp_path, *levels):
    """A fake build: a first module folder of the first level, the others in LEVELS_DIR."""
    first = tmp_path / "python"
    first.mkdir(parents=True)
    for k, level in enumerate(levels):
        folder = first if k == 0 else first / buildarch.LEVELS_DIR / level
        folder.mkdir(parents=True, exist_ok=True)
        (folder / "_trueaniso.cpython-311-x86_64-linux-gnu.so").write_text("")
        (folder / buildarch.ARCH_FILE).write_text(level + "\n")
    return first


def test_dispatch_loads_the_fastest_level_the_processor_runs_and_no_other(tmp_path):
    """A default build's two modules: v3 where the processor has every v3 feature, the baseline where
    it lacks one (avx2, fma, or any other of the level's), and the baseline where the flags cannot
    be read; never a level the processor lacks, asked or not."""
    first = _modules(tmp_path, buildarch.BASELINE, "x86-64-v3")
    v3 = str(first / buildarch.LEVELS_DIR / "x86-64-v3")
    assert buildarch.choose(str(first), V3) == v3
    assert buildarch.choose(str(first), V3 | {"avx512f"}) == v3  # no v4 module: v3 is the fastest there is
    for lacking in sorted(V3):
        assert buildarch.choose(str(first), V3 - {lacking}) == str(first), lacking
    assert buildarch.choose(str(first), None) == str(first)
    assert buildarch.choose(str(first), V3, asked="x86-64") == str(first)
    assert buildarch.choose(str(first), V3, asked=" X86-64-V3") == v3
    with pytest.raises(ImportError, match="TRUEANISO_LEVEL=x86-64-v3, and this processor lacks fma"):
        buildarch.choose(str(first), V3 - {"fma"}, asked="x86-64-v3")
    with pytest.raises(ImportError, match=r"TRUEANISO_LEVEL=x86-64-v4, but this build has x86-64, x86-64-v3"):
        buildarch.choose(str(first), V3, asked="x86-64-v4")
    assert buildarch.first_folder(v3) == str(first) and buildarch.first_folder(str(first)) == str(first)
    single = _modules(tmp_path / "single", "x86-64-v3")  # a build for one level: that level or a refusal
    assert buildarch.choose(str(single), set()) == str(single)
    with pytest.raises(ImportError, match="but this build has x86-64-v3"):
        buildarch.choose(str(single), V3, asked="x86-64")


def test_the_module_loaded_is_one_this_processor_runs_and_the_fastest_the_build_has():
    """The module a process runs when TRUEANISO_LEVEL is unset, as a user's does (the suite sets it,
    conftest.py): none of its level's features is missing from the processor, and no faster level of
    the build runs here."""
    env = {k: v for k, v in os.environ.items() if k != buildarch.LEVEL_ENV}
    out = subprocess.run([sys.executable, "-c", "from trueaniso import engines; print(engines.build_arch())"],
                         capture_output=True, text=True, env=dict(env, PYTHONPATH=os.path.join(REPO, "pyscripts")))
    assert out.returncode == 0, out.stderr
    loaded = out.stdout.strip()
    flags = buildarch.cpu_flags()
    assert buildarch.missing_features(loaded, flags) == []
    found = buildarch.levels_beside(buildarch.first_folder(os.path.dirname(engines.__file__)))
    runnable = [lv for lv in found if lv == buildarch.BASELINE or (flags and not buildarch.missing_features(lv, flags))]
    assert loaded == min(runnable, key=buildarch.FASTEST_FIRST.index)


@pytest.mark.parametrize("level", [buildarch.BASELINE, "x86-64-v3"])
def test_trueaniso_level_loads_that_level(level):
    """TRUEANISO_LEVEL picks the module in a fresh interpreter: the baseline on any processor (its
    bits are the committed fixtures'), v3 where the build has it and the processor runs it; and
    metadata records the level loaded (provenance.versions()['build'])."""
    found = buildarch.levels_beside(buildarch.first_folder(os.path.dirname(engines.__file__)))
    if level not in found or buildarch.missing_features(level, buildarch.cpu_flags()):
        pytest.skip("this build or processor has no %s" % level)
    code = "from trueaniso import engines, provenance; print(engines.build_arch(), provenance.versions()['build'])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         env=dict(os.environ, TRUEANISO_LEVEL=level, PYTHONPATH=os.path.join(REPO, "pyscripts")))
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == [level, level]


# Steps a clump packing and a sphere packing under the servo, then probes the spheres, and prints
# what came out: run once per level, in a process of its own (TRUEANISO_LEVEL).
ACROSS_LEVELS = r"""
import json, sys
from trueaniso import dem, engines, specimen, specimen_file, triaxial
out = dict(level=engines.build_arch())
for name in ("clump1-200-s4.npz", "spheres-150-s4.npz"):
    s, _ = specimen_file.load(sys.argv[1] + "/" + name)
    servo = engines.TrueTriaxialServo()
    servo.set_goal(0.5, 140e3, 100e3)
    chain = dem.Chain(s, damping=0.4, controllers=[servo], rule="per-axis")
    servo.start(s)
    chain.run(300)
    out[name] = dict(positions=s.positions.ravel().tolist(), cell=s.cell.ravel().tolist(),
                     stress=[float(specimen.state(s)[k]) for k in ("sigma_x", "sigma_y", "sigma_z")])
s, _ = specimen_file.load(sys.argv[1] + "/spheres-150-s4.npz")
out["E"] = triaxial.probe(s, triaxial.stress_as_held(s), "z")["E"]
print(json.dumps(out))
"""


def test_the_levels_of_a_build_run_the_same_physics():
    """Every level the build has and this processor runs, each in a process of its own, steps clumps
    and spheres under the servo and probes: the same numbers but for rounding. The hot loops of the
    v3 module share the Scene and its quaternions with code built at the baseline, so a layout that
    differed between the levels would crash or corrupt here (EIGEN_MAX_ALIGN_BYTES, CMakeLists.txt).
    Tolerances: positions within 1e-10 of the cell and stresses within 1e-6 relative after 300 steps
    (a fused multiply-add rounds once: 1e-16 a step, grown by the packing's chaos), E within 1e-6
    (docs/howto/build-options.md: about 1e-6 after a servo and a probe; the probe's own error is 6e-4)."""
    import json
    import numpy as np
    found = buildarch.levels_beside(buildarch.first_folder(os.path.dirname(engines.__file__)))
    levels = [lv for lv in sorted(found) if not buildarch.missing_features(lv, buildarch.cpu_flags())]
    if len(levels) < 2:
        pytest.skip("this build or processor runs one level only: %s" % levels)
    runs = {}
    for level in levels:
        out = subprocess.run([sys.executable, "-c", ACROSS_LEVELS, os.path.join(REPO, "tests", "data")],
                             capture_output=True, text=True, timeout=600,
                             env=dict(os.environ, TRUEANISO_LEVEL=level, OMP_NUM_THREADS="1",
                                      PYTHONPATH=os.path.join(REPO, "pyscripts")))
        assert out.returncode == 0, (level, out.returncode, out.stderr[-2000:])
        runs[level] = json.loads(out.stdout.splitlines()[-1])
        assert runs[level]["level"] == level
    base = runs.pop(buildarch.BASELINE)
    for level, run in runs.items():
        for name in ("clump1-200-s4.npz", "spheres-150-s4.npz"):
            a, b = base[name], run[name]
            side = max(abs(x) for x in a["cell"])
            assert np.allclose(b["positions"], a["positions"], rtol=0, atol=1e-10 * side), (level, name)
            assert np.allclose(b["stress"], a["stress"], rtol=1e-6, atol=1e-6 * max(map(abs, a["stress"]))), (level, name)
        assert abs(run["E"] / base["E"] - 1) < 1e-6, (level, run["E"], base["E"])


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
    assert 'TRUEANISO_ARCH="%s" is not a level this build knows: give one of x86-64, x86-64-v2, x86-64-v3' % level in said
    assert "This build directory keeps the baseline and x86-64-v3 chosen at load." in said


def _cache(build, key):
    for line in (build / "CMakeCache.txt").read_text().splitlines():
        if line.startswith(key + ":"):
            return line.split("=", 1)[1]
    return None


def test_a_build_for_one_level_leaves_no_module_of_another_to_load(tmp_path):
    """A build directory of the default (both levels) configured again for one level alone: the
    second level's module goes, so that the package cannot load it instead of the level asked for."""
    build = tmp_path / "b"
    configure = ["cmake", "-S", REPO, "-B", str(build)]
    subprocess.run(configure, check=True, capture_output=True)
    stale = build / "python" / buildarch.LEVELS_DIR / "x86-64-v3"
    stale.mkdir(parents=True, exist_ok=True)
    (stale / "_trueaniso.cpython-311-x86_64-linux-gnu.so").write_text("")
    subprocess.run(configure + ["-DTRUEANISO_ARCH=x86-64"], check=True, capture_output=True)
    assert not (build / "python" / buildarch.LEVELS_DIR).exists()


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
    this build: refused as another code version, and the refusal names both levels and how to
    continue it (TRUEANISO_LEVEL where this build has the level, else a build for it; the sources
    may be the same)."""
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
    directory = os.path.dirname(engines.__file__)
    if other in buildarch.levels_beside(buildarch.first_folder(directory)) and \
            not buildarch.missing_features(other, buildarch.cpu_flags()):
        assert "continue it at %s: TRUEANISO_LEVEL=%s before the command" % (other, other) in said
    else:
        assert "continue it at %s: a build for %s (TRUEANISO_ARCH=%s ./setup.sh" % (
            other, other, "" if other == buildarch.BASELINE else other) in said
    # the same level: only the code version is named, as before
    study_dir.write_metadata(str(tmp_path / "same"), there, [(1, 0.0, 100e3)], ["z"],
                             dict(versions=dict(code="src-aaaa", build=engines.build_arch())))
    with pytest.raises(study_dir.StudyMismatch) as refused:
        study_dir.check(str(tmp_path / "same"), dict(there, code="src-bbbb"), [(1, 0.0, 100e3)])
    assert "this run's for" not in str(refused.value) and "continue it at" not in str(refused.value)
