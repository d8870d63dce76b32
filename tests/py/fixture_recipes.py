"""How the specimens committed in tests/data were made. The tests load those files (through
specimen_file.load, which checks their checksum and fields) instead of preparing them each run; a
test marked long runs the recipe itself where the recipe's outcome is part of what is checked.
Regenerate a file (by the baseline module, which this script loads unless TRUEANISO_LEVEL says
otherwise, one engine thread) by

    OMP_NUM_THREADS=1 /usr/bin/python3 tests/py/fixture_recipes.py NAME.npz

Thresholds of the tests that load a file belong to that packing: a regenerated file is another
packing, whose tests must be run and their measured values checked against the tolerances."""
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
DATA = os.path.join(REPO, "tests", "data")
sys.path.insert(0, os.path.join(REPO, "pyscripts"))
# The baseline module (trueaniso/buildarch.py): every file in tests/data is its (tests/data/README.md).
os.environ.setdefault("TRUEANISO_LEVEL", "x86-64")

from trueaniso import clump_recipes, clump_specimen, engines, specimen, specimen_file, triaxial  # noqa: E402


def one_thread(make):
    """`make` on one engine thread: the same packing on any machine and under any OMP_NUM_THREADS
    (the force sum's order changes the last bits, and a preparation amplifies them)."""
    threads = engines.threads()
    engines.set_threads(1)
    try:
        return make()
    finally:
        engines.set_threads(threads)


def spheres(n, seed, variant=None):
    """A sphere specimen by the default recipe (prepare_spheres), or its named variant,
    consolidated at 100 kPa. Returns (scene, log)."""
    settings = clump_recipes.variant("sphere", variant) if variant else {}
    return one_thread(lambda: specimen.prepare_spheres(n, seed=seed, **settings))


def clump1_200_s4():
    """A small clump specimen at 100 kPa in force and moment balance, made the quick way (nothing
    the clump tests check depends on the packing's history): dimers, rotations blocked through the
    whole expansion, frictionless, inertial number 0.05 instead of the recipes' 0.01, the friction
    switched at the target (no unloading: switch_fraction 1, as every recipe before it). 200 clumps:
    at 80 the packing is so fragile (9 rattlers, a hinge) that the +/- probe mean still moves by
    1.5e-4 between gamma = 1e-6 and 3e-7; at 200 it agrees with the static solve to 1e-5 at both.
    Returns (scene, log)."""
    return one_thread(lambda: clump_specimen.prepare_clumps(
        "clump1", 200, seed=4, inertial_number=5e-2, shape="dimer-1.5", orientation_weights=(1.0, 1.0, 3.0),
        stage1_pressure=100e3, mu_prep=0.0, switch_fraction=1.0))


def loose_150_at_state_21():
    """A loose packing (150 spheres consolidated with friction 1.0 throughout the expansion, Zm ~ 4.4)
    driven to state 21 of Table C1 (b = 0.5, sigma_z 140 kPa, loading friction 1.0). A loose packing
    at q/p = 0.69 is at the edge of failure: with mu = 1.0 while loading, three of seeds 5-8 carry
    the state (seed 5 creeps away from the path). Which seed carries it is chaos, not what the tests
    check: the first of seeds 6, 7, 8 that does is taken. The friction is switched at the target
    (no unloading: the recipe before it, which made the file). Returns (seed, scene, log)."""
    def make():
        for seed in (6, 7, 8):
            scene, log = specimen.prepare_spheres(150, seed=seed, mu_prep=1.0, switch_fraction=1.0)
            try:
                triaxial.reach_state(scene, 0.5, 140e3, max_strain=0.15, friction=1.0)  # a loose packing strains more
                return seed, scene, log
            except triaxial.StateNotReached:
                continue
        raise triaxial.StateNotReached("none of the loose packings (seeds 6, 7, 8) carried state 21")
    return one_thread(make)


def clump2_300_s4_state4():
    """A small clump2 packing held at state 4 of Table C1 (b = 0, sigma_z 130 kPa): the default
    recipe (300 clumps, seed 4), then the study's servo from the isotropic state. Its held state
    moves by itself with sliding suppressed, as the 2000-clump studies' do (bodies with one contact
    rolling on their neighbours): its one-sided probes' reciprocity error is 1.1 % where the
    static compliance's is 0.08 %. Of seeds 1-8 at states 4, 12 and 21, seeds 4 and 5 show it at
    state 4; seed 4 is taken. Returns (scene, log)."""
    def make():
        scene, log = clump_specimen.prepare_clumps("clump2", 300, seed=4)
        triaxial.reach_state(scene, 0.0, 130e3, friction=0.5, time_step="per-axis", inertial_number=1e-3)
        return scene, log
    return one_thread(make)


def save_spheres(n, seed, variant=None):
    def save(path):
        scene, log = spheres(n, seed, variant)
        specimen_file.save(path, scene, seed=seed, parameters=log, summary=specimen.state(scene))
    return save


def save_clump1_200_s4(path):
    scene, log = clump1_200_s4()
    specimen_file.save(path, scene, seed=4, parameters=log, summary=specimen.state(scene))


def save_clump2_300_s4_state4(path):
    scene, log = clump2_300_s4_state4()
    specimen_file.save(path, scene, seed=4, parameters=dict(log, state="4", b=0.0, sigma_z=130e3),
                       summary=specimen.state(scene))


def save_loose_150_at_state_21(path):
    seed, scene, log = loose_150_at_state_21()
    specimen_file.save(path, scene, seed=seed, parameters=dict(log, loaded_to="state 21 (b 0.5, sigma_z 140 kPa, "
                                                                               "loading friction 1.0)"))


# spheres-300-s3 and spheres-150-s4 are the recipe before the unloading (its variant grown-to-target,
# the same bits): the tests of probes, zeta and the YADE peers read the first, the docstrings' examples
# and the manual's the second (their printed numbers are its), none of them the recipe.
MAKERS = {"spheres-300-s3.npz": save_spheres(300, 3, "grown-to-target"), "spheres-150-s5.npz": save_spheres(150, 5),
          "spheres-150-s4.npz": save_spheres(150, 4, "grown-to-target"),
          "clump1-200-s4.npz": save_clump1_200_s4, "loose-150-state21.npz": save_loose_150_at_state_21,
          "clump2-300-s4-state4.npz": save_clump2_300_s4_state4}

if __name__ == "__main__":
    for name in sys.argv[1:]:
        MAKERS[name](os.path.join(DATA, name))
        print("wrote", os.path.join(DATA, name))
