"""The committed specimens are made again to the bit whatever x86-64 processor runs the recipe.

Three libraries choose code by processor at run time: OpenBLAS its kernels (OPENBLAS_CORETYPE
overrides the choice), numpy its SIMD loops (NPY_DISABLE_CPU_FEATURES turns dispatched ones off;
its float64 power, exp and log differ in the last bits on AVX-512), and glibc's libm its FMA/AVX2
variants (GLIBC_TUNABLES=glibc.cpu.hwcaps=-...). Each variant here runs a fixture's recipe in a new
process as another processor would: kernels of an older one, every dispatched numpy loop off, libm's
baseline code. A preparation is chaotic, so any library call on its path whose last bit follows the
processor ends in another packing; equal bits under every variant is what docs/runs.md promises
("Across machines"). Only variants the processor can run are used (a SkylakeX kernel on a processor
without AVX-512 would die of an illegal instruction)."""
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import REPO

sys.path.insert(0, os.path.join(REPO, "pyscripts"))
from trueaniso import buildarch, specimen_file  # noqa: E402

DATA = os.path.join(REPO, "tests", "data")
ARRAYS = ("positions", "orientations", "radii", "cell", "velocities")
# OpenBLAS core types, oldest first, with the processor flags their kernels need.
OPENBLAS_CORES = (("Prescott", ()), ("Sandybridge", ("avx",)), ("Haswell", ("avx2", "fma")),
                  ("SkylakeX", ("avx512f", "avx512vl", "avx512bw", "avx512dq")))
LIBM_OFF = "glibc.cpu.hwcaps=-AVX512F,-AVX512VL,-AVX2,-FMA,-AVX"


def _numpy_dispatched():
    """numpy's dispatched SIMD targets that this processor runs (all of them can be turned off)."""
    from numpy.core._multiarray_umath import __cpu_dispatch__, __cpu_features__
    return " ".join(k for k in __cpu_dispatch__ if __cpu_features__.get(k))


def variants():
    flags = buildarch.cpu_flags() or set()
    cores = [name for name, need in OPENBLAS_CORES if all(f in flags for f in need)]
    out = {"openblas-%s" % c.lower(): dict(OPENBLAS_CORETYPE=c) for c in cores}
    out["numpy-baseline"] = dict(NPY_DISABLE_CPU_FEATURES=_numpy_dispatched())
    out["libm-baseline"] = dict(GLIBC_TUNABLES=LIBM_OFF)
    out["all-baseline"] = dict(OPENBLAS_CORETYPE="Prescott", NPY_DISABLE_CPU_FEATURES=_numpy_dispatched(),
                               GLIBC_TUNABLES=LIBM_OFF)
    return out


MAKE = """
import json, sys
sys.path.insert(0, %r)
import fixture_recipes
scene, log = getattr(fixture_recipes, sys.argv[1])(*map(int, sys.argv[2:]))
json.dump(dict(arrays={k: getattr(scene, k).tolist() for k in %r},
               steps=[log["steps_expansion"], log["steps_consolidation"]]), sys.stdout)
""" % (os.path.join(REPO, "tests", "py"), ARRAYS)


def remade(recipe, args, env):
    """The recipe's arrays and step counts, made in a new process under `env`, by the baseline's
    module (TRUEANISO_LEVEL): the committed specimens are the baseline's, the level every x86-64
    processor runs, whichever level this processor would load unasked."""
    proc = subprocess.run([sys.executable, "-c", MAKE, recipe] + [str(a) for a in args],
                          env=dict(os.environ, OMP_NUM_THREADS="1", **dict({buildarch.LEVEL_ENV: buildarch.BASELINE},
                                                                          **env)),
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout)


def assert_same_bits(made, committed_file):
    ref, meta = specimen_file.load(os.path.join(DATA, committed_file))
    for name in ARRAYS:
        # tolist() and back keeps every bit of a float64
        np.testing.assert_array_equal(np.array(made["arrays"][name], dtype=float), getattr(ref, name),
                                      err_msg=name)
    p = meta["parameters"]
    assert made["steps"] == [p["steps_expansion"], p["steps_consolidation"]]


def _baseline_build():
    """Skips where the build has no baseline module (one built for a single other level)."""
    from trueaniso import engines
    if buildarch.BASELINE not in buildarch.levels_beside(buildarch.first_folder(os.path.dirname(engines.__file__))):
        pytest.skip("the committed specimens are the baseline build's (docs/howto/build-options.md)")


def test_the_variants_differ_where_they_should():
    """The variants are not all the same environment: one turns numpy's dispatch off, one libm's,
    and each OpenBLAS kernel differs from the others (else the tests below could not fail)."""
    v = variants()
    assert "OPENBLAS_CORETYPE" in v["all-baseline"] and v["libm-baseline"]["GLIBC_TUNABLES"].startswith("glibc.")
    assert len({e.get("OPENBLAS_CORETYPE") for e in v.values()}) >= 2


@pytest.mark.parametrize("variant", ["all-baseline"])
def test_the_sphere_fixture_is_made_again_on_another_processor(variant):
    """spheres-150-s5.npz (the default sphere recipe, 150 spheres, seed 5) under the variant that
    changes the most at once; test_specimen pins it in this process too."""
    _baseline_build()
    assert_same_bits(remade("spheres", (150, 5), variants()[variant]), "spheres-150-s5.npz")


@pytest.mark.long
@pytest.mark.parametrize("variant", sorted(variants()))
def test_the_clump_fixture_is_made_again_on_another_processor(variant):
    """clump1-200-s4.npz (clump placement turns template offsets by rotation matrices: a matrix
    product, which BLAS would compute, is on its path) under every variant. Long: 10-15 s each."""
    _baseline_build()
    assert_same_bits(remade("clump1_200_s4", (), variants()[variant]), "clump1-200-s4.npz")


@pytest.mark.long
@pytest.mark.parametrize("variant", sorted(set(variants()) - {"all-baseline"}))
def test_the_sphere_fixture_is_made_again_under_each_variant(variant):
    _baseline_build()
    assert_same_bits(remade("spheres", (150, 5), variants()[variant]), "spheres-150-s5.npz")
