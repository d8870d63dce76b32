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


def test_a_study_on_a_per_axis_specimen_says_its_states_take_another_rule(specimen_150, tmp_path):
    """A specimen's rule and a study's are two choices (docs/time-step.md): a specimen prepared with
    another rule than the study's states take is named in a note, not taken silently."""
    from conftest import run_script
    scene, meta = specimen_file.load(str(specimen_150))
    per_axis = tmp_path / "per-axis.npz"
    specimen_file.save(str(per_axis), scene, seed=meta.get("seed"),
                       parameters=dict(meta.get("parameters") or {}, time_step="per-axis"), summary=meta.get("summary"))
    proc = run_script("run_states.py", "--specimen", per_axis, "--ids", "1", "--probes", "z", "--threads", "1",
                      "--time-step", "smallest-inertia", "--out", tmp_path / "study")
    assert proc.returncode == 0, proc.stderr[-2000:]
    notes = [x for x in proc.stdout.splitlines() if x.startswith("note:")]
    assert len(notes) == 1 and "per-axis" in notes[0] and "smallest-inertia" in notes[0], proc.stdout
    state, _ = specimen_file.load(str(tmp_path / "study" / "states" / "1.npz"))
    cap = dem.reference_time_step(state, safety=0.5)  # smallest-inertia's cap, which binds for spheres at 100 kPa
    assert state.dt <= cap * (1 + 1e-12)


def _reach(path, monkeypatch, factor, b=0.5, sigma_z=120e3):
    from trueaniso import fabric, statics, triaxial
    monkeypatch.setitem(dem.TIME_STEP_RULES, "per-axis", (True, factor))
    scene, _ = specimen_file.load(str(path))
    info = triaxial.reach_state(scene, b, sigma_z, time_step="per-axis")
    return info, scene, fabric.fabric(scene)["Zm"], statics.static_stiffness(scene, rotations=True)["E"]


def test_a_longer_step_reaches_the_same_state_in_fewer_steps(specimen_150, monkeypatch):
    """The path rate, the gain and the step counts are per reference step (scene.reference_dt), so a
    step 20 % longer reaches a state in 1.2 times fewer steps, and the state is the same: on this
    fixture (b = 0.5, sigma_z = 120 kPa) the two differ by 1e-6 in E_i (measured), the history's
    floor (path rate 1.9 against 2) is 3e-7; the bound, 1e-4, is a sixth of the default probe's own
    error (6e-4). Per-step settings would take the same steps at both, and fail the first check."""
    a, sa, zm_a, e_a = _reach(specimen_150, monkeypatch, 0.8)
    b, sb, zm_b, e_b = _reach(specimen_150, monkeypatch, 0.8 / 1.2)
    assert sa.dt / sb.dt == pytest.approx(1.2, rel=0.01)
    assert sa.reference_dt == pytest.approx(sb.reference_dt, rel=1e-12)  # the unit does not move with the rule
    assert b["steps"] / a["steps"] == pytest.approx(1.2, abs=0.05)
    assert np.max(np.abs(np.asarray(e_a) / np.asarray(e_b) - 1)) < 1e-4
    assert zm_a == pytest.approx(zm_b, abs=0.01)


def test_the_default_study_takes_the_per_axis_rule_for_its_states_and_probes(specimen_150, tmp_path):
    """The default (docs/time-step.md): a study run without --time-step reaches its states and runs
    its probes with the per-axis step, and records both rules in its fingerprint."""
    from conftest import run_script
    from trueaniso import study_dir
    out = tmp_path / "study"
    proc = run_script("run_states.py", "--specimen", specimen_150, "--ids", "1", "--probes", "z", "--threads", "1",
                      "--out", out)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert "--time-step" not in proc.stdout, proc.stdout  # nothing to say: the default, asked by nobody
    meta = study_dir.read_metadata(str(out))
    fp = meta["fingerprint"]
    assert (fp["state"]["time_step"], fp["probe"]["time_step"]) == ("per-axis", "per-axis")
    assert meta["specimen"]["time_step"] == "smallest-inertia"  # the fixture's preparation (it records none)
    state, meta = specimen_file.load(str(out / "states" / "1.npz"))
    assert state.step_scale == pytest.approx(dem.TIME_STEP_RULES["per-axis"][1] / 0.5, rel=1e-9)  # the cap binds


def test_a_study_keeps_its_time_step_rule(specimen_150, tmp_path):
    """--time-step is part of a study's fingerprint: a rerun without it continues with the study's
    rule (and says so), one with the other rule is refused naming the option; the checkpoint holds
    the per-axis step and the reference step it was loaded with."""
    from conftest import run_script
    from trueaniso import study_dir
    out = tmp_path / "study"
    common = ("--specimen", specimen_150, "--probes", "z", "--threads", "1", "--out", out)
    proc = run_script("run_states.py", "--ids", "1", "--time-step", "smallest-inertia", *common)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert not [x for x in proc.stdout.splitlines() if x.startswith("note:")], proc.stdout
    fp = study_dir.read_metadata(str(out))["fingerprint"]
    assert (fp["state"]["time_step"], fp["probe"]["time_step"]) == ("smallest-inertia", "smallest-inertia")
    state, meta = specimen_file.load(str(out / "states" / "1.npz"))
    assert "reference_dt" not in meta and state.step_scale == 1.0
    again = run_script("run_states.py", "--ids", "1,2", *common)
    assert again.returncode == 0, again.stderr[-2000:]
    said = [x for x in again.stdout.splitlines() if "--time-step not given" in x]
    assert len(said) == 1 and "smallest-inertia" in said[0], again.stdout
    other = run_script("run_states.py", "--ids", "1,2", "--time-step", "per-axis", *common)
    assert other.returncode != 0 and "--time-step" in other.stderr, other.stderr[-2000:]
    assert len(other.stderr.strip().splitlines()) == 1, other.stderr


def test_a_study_that_records_no_rule_goes_on_with_smallest_inertia(specimen_150, tmp_path):
    """A study made before the rule was recorded (no state.time_step, no probe.time_step in its
    fingerprint) was made with smallest-inertia: a rerun without --time-step continues it with that
    rule, saying so in one line, and one that asks per-axis is refused in one line."""
    import json
    from conftest import run_script
    from trueaniso import study_dir
    out = tmp_path / "study"
    common = ("--specimen", specimen_150, "--probes", "z", "--threads", "1", "--out", out)
    proc = run_script("run_states.py", "--ids", "1", "--time-step", "smallest-inertia", *common)
    assert proc.returncode == 0, proc.stderr[-2000:]
    path = out / "metadata.json"
    meta = json.loads(path.read_text())
    del meta["fingerprint"]["state"]["time_step"], meta["fingerprint"]["probe"]["time_step"]
    path.write_text(json.dumps(meta))
    assert study_dir.time_step_rules_of(str(out)) == ("smallest-inertia", "smallest-inertia")
    again = run_script("run_states.py", "--ids", "1,2", *common)
    assert again.returncode == 0, again.stderr[-2000:]
    said = [x for x in again.stdout.splitlines() if "time step" in x or "--time-step" in x]
    assert len(said) == 1 and "smallest-inertia" in said[0], again.stdout
    fp = study_dir.read_metadata(str(out))["fingerprint"]
    assert (fp["state"]["time_step"], fp["probe"]["time_step"]) == ("smallest-inertia", "smallest-inertia")
    path.write_text(json.dumps(meta))  # the old fingerprint again
    other = run_script("run_states.py", "--ids", "1,2", "--time-step", "per-axis", *common)
    assert other.returncode != 0 and "--time-step" in other.stderr, other.stderr[-2000:]
    assert len(other.stderr.strip().splitlines()) == 1, other.stderr


def test_a_study_whose_probes_took_another_rule_goes_on_with_it(specimen_150, tmp_path):
    """A study whose states took per-axis and whose probes took smallest-inertia (made before the
    probes took the study's rule: no probe.time_step) continues so, said in one line, with or
    without --time-step per-axis."""
    import json
    from conftest import run_script
    from trueaniso import study_dir
    out = tmp_path / "study"
    common = ("--specimen", specimen_150, "--probes", "z", "--threads", "1", "--out", out)
    assert run_script("run_states.py", "--ids", "1", "--time-step", "smallest-inertia", *common).returncode == 0
    path = out / "metadata.json"
    meta = json.loads(path.read_text())
    meta["fingerprint"]["state"]["time_step"] = "per-axis"
    del meta["fingerprint"]["probe"]["time_step"]
    path.write_text(json.dumps(meta))
    (out / "states" / "1.npz").unlink()  # reached again under the study's states' rule
    for given in ((), ("--time-step", "per-axis")):
        again = run_script("run_states.py", "--ids", "1,2", *given, *common)
        assert again.returncode == 0, again.stderr[-2000:]
        assert "probed its states with the smallest-inertia" in again.stdout, again.stdout
        fp = study_dir.read_metadata(str(out))["fingerprint"]
        assert (fp["state"]["time_step"], fp["probe"]["time_step"]) == ("per-axis", "smallest-inertia")


@pytest.mark.parametrize("path", ["specimen_150", DIMERS])
def test_a_probe_at_the_per_axis_rule_gives_the_modulus_of_smallest_inertia(path, request):
    """The probe's gain and step counts are per reference step (StressProbe::stepScale), so under
    the per-axis rule it probes over the same time in fewer steps and gives the same E and nu:
    measured 150 spheres, z: dE/E 7.6e-6, dnu 3e-6, 960 -> 601 steps; the bounds are the default
    probe's own error (6e-4 in E, 1.1e-4 in nu, docs/speed-vs-error.md). Fewer steps by more than
    1.3: a probe that took the reference step (its settings per step of its own) would take as
    many."""
    from trueaniso import triaxial
    if path == "specimen_150":
        path = str(request.getfixturevalue("specimen_150"))
    r = {}
    for rule in ("smallest-inertia", "per-axis"):
        scene, _ = specimen_file.load(path)
        hold = triaxial.stress_as_held(scene)
        r[rule] = triaxial.probe(scene, hold, "z", time_step=rule)
    ref, fast = r["smallest-inertia"], r["per-axis"]
    assert fast["E"] == pytest.approx(ref["E"], rel=6e-4)
    assert abs(fast["nu_zx"] - ref["nu_zx"]) < 1.1e-4 and abs(fast["nu_zy"] - ref["nu_zy"]) < 1.1e-4
    assert ref["steps"] / fast["steps"] > 1.3, (ref["steps"], fast["steps"])


def test_a_specimen_file_keeps_a_reference_step_that_is_not_its_step(specimen_150, tmp_path):
    """Saved only where it differs from dt: a file made under the reference rule is the same bytes."""
    scene, meta = specimen_file.load(str(specimen_150))
    assert "reference_dt" not in meta and scene.reference_dt == scene.dt
    # The per-axis rule's step, as its chain sets it (dem.Chain): the reference step stays.
    _, safety = dem.TIME_STEP_RULES["per-axis"]
    scene.dt = min(dem.reference_time_step(scene, safety=safety), safety * engines.TimeStepper.per_axis_bound(scene))
    path = tmp_path / "s.npz"
    specimen_file.save(str(path), scene, seed=meta.get("seed"), parameters=meta.get("parameters"))
    again, meta2 = specimen_file.load(str(path))
    assert meta2["reference_dt"] == again.reference_dt == scene.reference_dt < again.dt
    assert again.step_scale == scene.dt / scene.reference_dt > 1.5


def test_the_yade_hosts_probe_counts_as_the_engines_probe():
    """--host yade gives the plugin's StressProbe (no step scale) its counts already scaled, as the
    engines' stepsFor does: the same time, at least one step, halves rounded away from zero (C's
    lround; Python's round would give 62 for 62.5)."""
    from trueaniso import yade_host
    assert yade_host.steps_for(300, 1.0) == 300
    assert yade_host.steps_for(300, 1.6) == 188  # 187.5
    assert yade_host.steps_for(100, 1.6) == 63  # 62.5
    assert yade_host.steps_for(2_000_000, 1.6) == 1_250_000
    assert yade_host.steps_for(1, 5.0) == 1
