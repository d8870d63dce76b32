"""The time step rules of the engine chain (dem.TIME_STEP_RULES, docs/time-step.md): which bound
and factor a chain takes, the cap that follows the factor, and a packing stepped by the per-axis rule
that keeps its energy."""
import os

import numpy as np
import pytest

from trueaniso import dem, engines, specimen_file

HERE = os.path.dirname(os.path.abspath(__file__))
DIMERS = os.path.join(os.path.dirname(os.path.dirname(HERE)), "tests", "data", "clump1-200-s4.npz")


def test_a_chain_takes_the_rule_and_its_cap(specimen_150):
    s, _ = specimen_file.load(str(specimen_150))
    plain = dem.Chain(s)
    assert (plain.timestep.per_axis, plain.timestep.safety) == (False, 0.5)
    assert plain.timestep.max_dt == dem.reference_time_step(s, safety=0.5)
    fast = dem.Chain(s, rule="per-axis")
    per_axis, safety = dem.TIME_STEP_RULES["per-axis"]
    assert per_axis and fast.timestep.per_axis and fast.timestep.safety == safety
    # The cap is a bound of the same kind: it takes the rule's factor (the same formula otherwise).
    assert fast.timestep.max_dt == pytest.approx(plain.timestep.max_dt * safety / 0.5, rel=1e-15)
    with pytest.raises(ValueError, match="unknown time step rule"):
        dem.Chain(s, rule="largest")


def test_the_module_rule_is_what_a_chain_takes_when_not_told(specimen_150, monkeypatch):
    s, _ = specimen_file.load(str(specimen_150))
    monkeypatch.setattr(dem, "time_step_rule", "per-axis")
    assert dem.Chain(s).timestep.per_axis
    assert dem.reference_time_step(s) == dem.reference_time_step(s, safety=dem.TIME_STEP_RULES["per-axis"][1])


def test_for_spheres_the_per_axis_bound_is_never_below_the_smallest_inertia_one(specimen_150):
    """Per sphere, lambda_max(K_t) <= sum k_n and lambda_max(K_r) <= sum k_s l^2 with a shorter arm
    (to mid-overlap, against radius): the per-axis bound is the larger, for every packing."""
    s, _ = specimen_file.load(str(specimen_150))
    dem.refresh(s)
    assert engines.TimeStepper.per_axis_bound(s) >= engines.TimeStepper.stiffness_bound(s)


@pytest.mark.parametrize("path", ["specimen_150", DIMERS])
def test_a_packing_stepped_by_the_per_axis_rule_keeps_its_energy(path, request):
    """Undamped, held cell, no sliding (probe friction), shaken with 1e-4 of its elastic energy,
    the stepper choosing dt every 10 steps by the per-axis rule, uncapped (max_dt 1 s: the step is
    the rule's own). Measured over 3000 steps, in initial kinetic energies K0: 150 spheres -0.03,
    200 dimers -0.36 (the clumps' O(dt^2) loss, docs/time-step.md); at 1.95 x the bound both blow up
    (1e33 K0, or a step refused as the contacts stiffen). Bounds: no rise above 1 K0, no loss
    beyond 5 K0."""
    if path == "specimen_150":
        path = str(request.getfixturevalue("specimen_150"))
    s, _ = specimen_file.load(path)
    s.velocity_gradient = np.zeros((3, 3))
    s.friction = engines.PROBE_FRICTION
    dem.refresh(s)
    rng = np.random.default_rng(2)
    m = np.array(s.masses)
    v = rng.standard_normal((s.num_bodies, 3))
    v -= (m[:, None] * v).sum(axis=0) / m.sum()
    e = engines.mechanical_energy(s)
    v *= np.sqrt(2e-4 * (e["normal"] + e["tangential"]) / (m[:, None] * v * v).sum())
    s.velocities = v
    chain = dem.Chain(s, damping=0.0, rule="per-axis", max_dt=1.0)
    chain.run(10)  # past the first increment of the springs (bench_stability.py says why)
    assert s.dt == pytest.approx(chain.timestep.safety * engines.TimeStepper.per_axis_bound(s), rel=0.01)
    k0 = 0.5 * (m[:, None] * v * v).sum()
    e0 = engines.mechanical_energy(s)["total"]
    chain.run(3000)
    e1 = engines.mechanical_energy(s)["total"]
    assert np.isfinite(e1) and -5 * k0 < e1 - e0 < k0


def test_a_study_on_a_per_axis_specimen_says_its_states_take_the_default_rule(specimen_150, tmp_path):
    """The rule is the preparation's option only (docs/time-step.md): a study's states run with the
    default rule, and a specimen prepared with the other one is named in a note, not taken silently."""
    from conftest import run_script
    scene, meta = specimen_file.load(str(specimen_150))
    per_axis = tmp_path / "per-axis.npz"
    specimen_file.save(str(per_axis), scene, seed=meta.get("seed"),
                       parameters=dict(meta.get("parameters") or {}, time_step="per-axis"), summary=meta.get("summary"))
    proc = run_script("run_states.py", "--specimen", per_axis, "--ids", "1", "--probes", "z", "--threads", "1",
                      "--out", tmp_path / "study")
    assert proc.returncode == 0, proc.stderr[-2000:]
    notes = [x for x in proc.stdout.splitlines() if x.startswith("note:")]
    assert len(notes) == 1 and "per-axis" in notes[0] and "smallest-inertia" in notes[0], proc.stdout
    state, _ = specimen_file.load(str(tmp_path / "study" / "states" / "1.npz"))
    cap = dem.reference_time_step(state)  # the default rule's cap, which binds for spheres at 100 kPa
    assert state.dt <= cap * (1 + 1e-12)
