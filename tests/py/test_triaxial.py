"""True-triaxial servo and stress probe: Table C1, the simple cubic closed form, linearity,
the hardest states, failure, and bad input."""
import math
import re

import numpy as np
import pytest

from trueaniso import dem, engines, specimen_file, triaxial


def test_equation_9_reproduces_table_c1():
    states = triaxial.table_c1_states()
    assert len(states) == 39
    for (i, sx, sy, sz, q), (_, b, szp) in zip(triaxial.TABLE_C1, states):
        s = engines.true_triaxial_stresses(b, szp)
        # Table C1 prints 0.1 kPa; b = 0.75 rows are rounded to 1 kPa (e.g. 58 for 58.0).
        assert s / 1e3 == pytest.approx([sx, sy, sz], abs=0.051), i
        assert np.mean(s) == pytest.approx(100e3, rel=1e-12)
        assert engines.deviatoric_q(b, szp) / 1e3 == pytest.approx(q, abs=0.051), i


def test_paths_cover_all_states_once():
    groups = triaxial.paths(triaxial.table_c1_states())
    ids = sorted(i for g in groups.values() for i, _, _ in g)
    assert ids == list(range(1, 40))
    assert len(groups) == 11  # isotropic, then b = 0..1 in compression (5) and extension (5)


@pytest.mark.parametrize("b,sz,msg", [(-0.1, 110e3, "outside [0, 1]"), (1.2, 110e3, "outside [0, 1]"),
                                      (0.0, 310e3, "must be > 0"), (1.0, 160e3, "must be > 0")])
def test_bad_states_are_refused(b, sz, msg):
    with pytest.raises(ValueError, match=re.escape(msg)):
        triaxial.validate_state(b, sz)
    servo = engines.TrueTriaxialServo()
    with pytest.raises(ValueError, match=re.escape(msg)):
        servo.set_goal(b, sz)


def simple_cubic(n=4, r=1e-4, sigma=100e3):
    """n^3 equal spheres on a cubic lattice whose contacts carry sigma a^2 (Hertz)."""
    s = engines.Scene()
    s.shear_modulus, s.poisson, s.density, s.friction = 18e9, 0.15, 2500.0, 0.5
    estar = s.shear_modulus / (1 - s.poisson)
    delta = 0.0
    for _ in range(50):  # a = 2r - delta and N(delta) = sigma a^2, by fixed point
        a = 2 * r - delta
        delta = (sigma * a * a / (4.0 / 3.0 * estar * math.sqrt(r / 2))) ** (2.0 / 3.0)
    a = 2 * r - delta
    g = (np.indices((n, n, n)).reshape(3, -1).T + 0.5) * a
    s.cell_size = s.cell_ref_size = [n * a] * 3
    s.add_spheres(g, np.full(len(g), r))
    s.dt = 0.0
    dem.refresh(s)
    s.dt = 0.5 * engines.TimeStepper.stiffness_bound(s)
    return s, estar


def test_simple_cubic_probe_gives_closed_form():
    """E = (12 E*^2 sigma)^(1/3)/2 (406.7 MPa) within 0.5 %, nu_ij = 0 within 1e-3."""
    s, estar = simple_cubic()
    sigma = engines.stress(s)
    assert np.diag(sigma) == pytest.approx([100e3] * 3, rel=1e-9)
    expected = (12 * estar ** 2 * 100e3) ** (1.0 / 3.0) / 2
    assert expected / 1e6 == pytest.approx(406.7, abs=0.05)
    for axis in (0, 1, 2):
        r = triaxial.probe(s, [100e3] * 3, axis, restrain_rotations=True)
        # 0.5 %: a = 2r - delta instead of 2r (3e-4) and the secant over the increment (1e-3)
        assert r["E"] == pytest.approx(expected, rel=5e-3)
        for k, v in r.items():
            if k.startswith("nu_"):
                assert abs(v) < 1e-3


def test_simple_cubic_micromechanics_equals_probe():
    """Eq. (40) with zeta = 1 on the simple cubic packing gives E = k_n / a (k_n/(2r) to
    O(delta/r)), the same as the stress probe measures with rotations restrained. The +/- probe
    mean removes the secant error of the finite increment; 4e-7 measured, 1e-5 allowed."""
    from trueaniso import fabric
    s, _ = simple_cubic()
    predicted = fabric.prediction(s, zeta=1.0)["E"]
    c = s.contact_arrays()
    kn = c["kn"][c["normal_force"] > 0]
    a = s.cell_size[0] / 4
    for axis in range(3):
        assert predicted[axis] == pytest.approx(kn.mean() / a, rel=1e-12)
        up = triaxial.probe(s, [100e3] * 3, axis, restrain_rotations=True)
        down = triaxial.probe(s, [100e3] * 3, axis, sign=-1, restrain_rotations=True)
        assert 0.5 * (up["E"] + down["E"]) == pytest.approx(predicted[axis], rel=1e-5)


@pytest.fixture(scope="module")
def specimen300(specimen_300):
    scene, _ = specimen_file.load(str(specimen_300))
    return scene


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_probe_is_linear(specimen300, axis):
    s = specimen300
    hold = [100e3] * 3
    up = triaxial.probe(s, hold, axis, sign=1)
    down = triaxial.probe(s, hold, axis, sign=-1)
    half = triaxial.probe(s, hold, axis, gamma=0.5e-6)
    assert up["gamma"] >= 1e-6 and half["gamma"] >= 0.5e-6
    assert down["E"] == pytest.approx(up["E"], rel=1e-2)
    assert half["E"] == pytest.approx(up["E"], rel=1e-2)
    # the five other stresses (two normal, three shear) were held: their increments are tiny
    # against the probe's
    ds = np.abs(up["d_stress"])
    others = [j for j in range(3) if j != axis]
    assert all(ds[j] < 5e-3 * ds[axis] for j in range(6) if j != axis), ds
    # Eq. (12) from the reported normal strain increments, written out here independently
    ex, ey, ez = up["d_strain"][:3]
    gamma12 = math.sqrt(((ex - ey) ** 2 + (ex - ez) ** 2 + (ey - ez) ** 2) / 2)
    assert up["gamma"] == pytest.approx(gamma12, rel=1e-12)
    # and Eqs. (10)-(11): E_i = d sigma_i / d eps_i, nu_ij = -d eps_j / d eps_i
    assert up["E"] == pytest.approx(up["d_stress"][axis] / up["d_strain"][axis], rel=1e-12)
    for j in others:
        name = "nu_%s%s" % ("xyz"[axis], "xyz"[j])
        assert up[name] == pytest.approx(-up["d_strain"][j] / up["d_strain"][axis], rel=1e-12)
    # the state is restored: same stress as before the probes
    np.testing.assert_allclose(np.diag(engines.stress(s)), hold, atol=200.0)


def test_probe_without_detection_matches(specimen300):
    hold = [100e3] * 3
    on = triaxial.probe(specimen300, hold, "x")
    off = triaxial.probe(specimen300, hold, "x", skip_detection=True)
    # The flag is honoured: detection ran every step with it on, never with it off ...
    assert on["detection_calls"] == on["steps"] and off["detection_calls"] == 0
    # ... and the answer is the same: the network cannot change over a 1e-6 strain without sliding.
    assert off["E"] == pytest.approx(on["E"], rel=1e-3)


def _state(scene):
    out = dict(positions=scene.positions, velocities=scene.velocities,
               angular_velocities=scene.angular_velocities, cell=np.array(scene.cell),
               velocity_gradient=np.array(scene.velocity_gradient), friction=scene.friction,
               block_rotations=scene.block_rotations)
    for k, v in scene.contact_arrays().items():
        out["contact_" + k] = np.asarray(v, dtype=float)
    return out


@pytest.mark.parametrize("restrain", [False, True])
def test_probe_restores_the_state(specimen300, restrain):
    """After a probe the scene is the held state again, bit for bit: positions, velocities, cell,
    friction (0.5, not the probe's 1e23), rotation option and every contact's forces, with no
    refresh of our own (the specimen and reach_state end with refreshed contacts). The x, y and z
    probes of a state therefore start from the same state, and probing twice changes nothing."""
    s = specimen300.copy()
    before = _state(s)
    r = triaxial.probe(s, [100e3] * 3, "y", restrain_rotations=restrain)
    assert r["steps"] > 100  # the probe did move the scene
    after = _state(s)
    assert np.abs(before["contact_shear_force"]).max() > 0  # tangential history is there to lose
    for k, v in before.items():
        np.testing.assert_array_equal(after[k], v, err_msg=k)


@pytest.mark.parametrize("axis,gamma,message", [
    ("w", 1e-6, "axis"), (True, 1e-6, "axis"), (6, 1e-6, "axis"), (1.0, 1e-6, "axis"), ("yy", 1e-6, "axis"),
    ("z", 0.0, "gamma"), ("z", -1e-6, "gamma"), ("z", float("nan"), "gamma"), ("z", float("inf"), "gamma"),
])
def test_probe_bad_input(specimen300, axis, gamma, message):
    with pytest.raises(ValueError, match=message):
        triaxial.probe(specimen300, [100e3] * 3, axis, gamma=gamma)


@pytest.mark.parametrize("feed_forward", [False, True])
@pytest.mark.parametrize("sid,b,sz", [(21, 0.5, 140e3), (25, 0.5, 60e3)])  # q = +69.3, -69.3 kPa
def test_hardest_states_reached_without_overshoot_or_oscillation(specimen300, sid, b, sz, feed_forward):
    """With the servo's feed-forward too (docs/triaxial.md): the same acceptance, and the goal
    never waits for the stresses (they keep pace with it)."""
    s = specimen300.copy()
    s.friction = 1e23  # as a probe leaves it unrestored: reach_state must load with 0.5
    goal = engines.true_triaxial_stresses(b, sz)
    held = []  # |sigma - goal| sampled every 200 steps once the servo holds the state

    def watch(servo):
        if servo.status in ("holding", "reached"):
            held.append(servo.stress_error)  # principal and shear stresses against the state
    info = triaxial.reach_state(s, b, sz, chunk=200, progress=watch, feed_forward=feed_forward)
    assert info["friction"] == 0.5 and s.friction == 0.5
    if feed_forward:
        assert info["waited_steps"] == 0
    # the held state's contacts belong to its positions: a refresh (as every probe and every
    # checkpoint load does) changes no force (it once moved the stress by ~0.1 Pa)
    held_state = _state(s)
    dem.refresh(s)
    for k, v in held_state.items():
        np.testing.assert_array_equal(_state(s)[k], v, err_msg=k)
    np.testing.assert_allclose(np.diag(engines.stress(s)), goal, atol=500.0)
    # the principal stresses are the goal's and the shear stresses zero, to the servo's 0.5 kPa
    # (principal values computed here by numpy, independently of the engines)
    sig = engines.stress(s)
    principal = np.sort(np.linalg.eigvalsh(0.5 * (sig + sig.T)))
    np.testing.assert_allclose(principal, np.sort(goal), atol=500.0)
    assert max(abs(sig[1, 2]), abs(sig[0, 2]), abs(sig[0, 1])) < 500.0
    assert info["principal_error"] < 500.0 and info["shear_error"] < 500.0
    assert max(info["overshoot"]) < 500.0  # never past the goal by more than the tolerance
    assert info["unbalanced"] < 1e-4
    # no oscillation: the goal stops at the state with the stresses up to ~1 kPa behind (the
    # follow tolerance); from then on they close in (state 21: 949 -> 90 Pa over 21 samples, one
    # 31 Pa bump from a rearrangement) and, once inside the 0.5 kPa band, never leave it
    assert held, sid
    inside = next(k for k, d in enumerate(held) if d < 500.0)
    assert max(held[inside:]) < 500.0, (sid, held)
    assert all(b < a + 100.0 for a, b in zip(held, held[1:])), (sid, held)


@pytest.mark.parametrize("feed_forward", [False, True])
def test_unreachable_state_fails_cleanly(specimen300, feed_forward):
    s = specimen300.copy()
    # sigma_x = sigma_y = 15 kPa against sigma_z = 270 kPa: far beyond the friction's capacity
    with pytest.raises(triaxial.StateNotReached, match="not reached"):
        triaxial.reach_state(s, 0.0, 270e3, stall_steps=20000, feed_forward=feed_forward)


def test_state_that_never_settles_is_reported(specimen300):
    """A hold criterion the dynamics cannot meet (unbalanced force below 1e-30) ends with a
    clear message after hold_steps, not after the 3M-step cap."""
    s = specimen300.copy()
    with pytest.raises(triaxial.StateNotReached, match="without settling"):
        triaxial.reach_state(s, 0.0, 100e3, unbalanced=1e-30, hold_steps=2000, chunk=500)


def test_shear_goal_on_a_path_that_fixes_the_shear_is_refused(specimen300):
    """Bad input: a shear stress goal on a path that holds the cell's shear
    strains (control_shear=False) is refused with one clear message before any step runs."""
    s = specimen300.copy()
    step = s.step
    with pytest.raises(ValueError, match="holds the cell's shear strains"):
        triaxial.reach_state(s, 0.5, 120e3, control_shear=False, shear=(0.0, 1e3, 0.0))
    assert s.step == step
    with pytest.raises(ValueError, match="shear probe needs the shear stresses under control"):
        triaxial.probe(s, [100e3] * 3, "yz", control_shear=False)


def test_measures_of_an_imported_scene_need_a_force_evaluation(specimen_100):
    """A scene whose contacts came in with forces only (yade_bridge.scene_from_yade's way) has no
    force evaluation to take branch vectors from: its stress and fabric are refused until
    dem.refresh (not a stress of zeros, p = 0 with Zm 4.8), after which the state is the specimen's
    own (1e-9: refresh recomputes the same forces)."""
    from trueaniso import dem, engines, specimen, specimen_file
    scene, _ = specimen_file.load(str(specimen_100))
    want = specimen.state(scene)
    d = scene.contact_arrays()
    scene.set_contact_history(d["member1"], d["member2"], d["shift"].astype(np.int32), d["normal"], d["normal_force"],
                              d["shear_force"])
    with pytest.raises(ValueError, match="dem.refresh"):
        specimen.state(scene)
    with pytest.raises(ValueError, match="no force evaluation has run at these positions"):
        engines.stress(scene)
    with pytest.raises(ValueError, match="force evaluation"):  # its list is not yet detected, either
        engines.fabric(scene)
    dem.refresh(scene)
    assert specimen.state(scene)["p"] == pytest.approx(want["p"], rel=1e-9)


def test_a_probe_refuses_stresses_the_scene_is_not_at(specimen_100):
    """A probe told to hold 100 kPa on a scene at another stress is refused: it would travel there
    and return that path's slope as E (63 MPa and nu 0.57 on a 579 kPa scene)."""
    from trueaniso import specimen_file
    scene, _ = specimen_file.load(str(specimen_100))
    with pytest.raises(ValueError, match="not at the stresses the probe is told to hold"):
        triaxial.probe(scene, [300e3, 300e3, 300e3], "z")
    with pytest.raises(ValueError, match="not at the stresses"):
        triaxial.probe(scene, [100e3, 100e3, 100e3, 5e3, 0, 0], "z")  # a shear stress it does not carry
