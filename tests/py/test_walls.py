"""The walled specimen of pyscripts/bench/zm_walls.py (rigid walls: boundary/RigidWalls.hpp): its
Zm count against the engines' own, its placement (no sphere starts on a wall), and its refusals."""
import os
import sys

import numpy as np

from conftest import REPO, SCRIPTS, one_line_error, run_script

sys.path.insert(0, os.path.join(SCRIPTS, "bench"))
import zm_walls  # noqa: E402

SPECIMEN = os.path.join(REPO, "tests", "data", "spheres-150-s4.npz")


def test_eq14_from_per_particle_counts_is_the_engines_zm():
    """The interior count sums the per-particle contacts of a subset; over every particle it must
    be Eq. 14 as the engines count it (Coordination.cpp, from the contact list)."""
    from trueaniso import engines, specimen_file
    scene, _ = specimen_file.load(SPECIMEN)
    zm, n0, n1 = zm_walls.mechanical(engines.contacts_per_body(scene))
    z = engines.coordination(scene)
    assert (n0, n1) == (z["Np0"], z["Np1"])
    assert abs(zm - z["Zm"]) < 1e-12 * z["Zm"]  # the same integers divided: rounding only


def test_walls_are_placed_touching_and_not_overlapping():
    from trueaniso import dem, engines, specimen_file
    periodic, _ = specimen_file.load(SPECIMEN)
    scene, walls = zm_walls.walled_scene(periodic, 0.015)
    assert scene.num_bodies == periodic.num_bodies
    x, r = np.asarray(scene.positions), np.asarray(scene.radii)
    lo, hi = np.asarray(walls.lower), np.asarray(walls.upper)
    # Each wall touches its outermost sphere (gap 0 to rounding of a 1e-3 m box, ~1e-18 m) and
    # none overlaps one by more than that rounding.
    assert np.allclose((x - r[:, None]).min(axis=0), lo, rtol=0, atol=1e-15)
    assert np.allclose((x + r[:, None]).max(axis=0), hi, rtol=0, atol=1e-15)
    dem.refresh(scene)
    walls.add_forces(scene)
    assert np.asarray(walls.force).max() < 1e-12  # N: an overlap of 1e-15 m gives ~1e-14 N
    # The pairs inside are the periodic specimen's minus those that crossed its boundary.
    assert 0 < engines.coordination(scene)["Nc"] < engines.coordination(periodic)["Nc"]
    walls.validate(scene)


def test_refusals(tmp_path):
    out = str(tmp_path / "z.json")
    for args, words in ((["--ids", "40"], "numbered 1-39"), (["--interior", "-1"], "distances >= 0"),
                        (["--gain", "0"], "--gain")):
        one_line_error(run_script("bench/zm_walls.py", "--specimen", SPECIMEN, "--out", out, *args), words)
    one_line_error(run_script("bench/zm_walls.py", "--specimen", str(tmp_path / "none.npz"), "--out", out),
                   "no such file")
    assert not os.path.exists(out)


def test_a_small_walled_specimen_reaches_state_5_and_is_probed(tmp_path):
    """The whole measurement on 150 spheres: the walls hold state 1 and state 5 to the servo's
    tolerance, wall contacts add to Zm, overlaps stay small at the reduced time step, and the probes
    see the stress-induced anisotropy of state 5 (E_z along sigma_z = 140 kPa stiffer than E_x
    along 80 kPa: 26 % on 300 spheres, 25 % on 4000, far beyond the probes' noise)."""
    import json
    out = tmp_path / "w.json"
    proc = run_script("bench/zm_walls.py", "--specimen", SPECIMEN, "--out", out, "--ids", "5", "--interior", "1",
                      "--probe-strain", "1e-5", "--chunk", "100000")
    assert proc.returncode == 0, proc.stderr[-3000:]
    d = json.loads(out.read_text())
    assert sorted(d["states"]) == ["1", "5"]
    for sid, goal in (("1", (100e3, 100e3, 100e3)), ("5", (80e3, 80e3, 140e3))):
        s = d["states"][sid]
        assert np.allclose(s["wall_stress"], goal, rtol=0, atol=100.0)  # the hold tolerance (Pa)
        assert s["Zm_with_walls"] > s["Zm"] and sum(s["wall_contacts"]) > 0
        assert s["max_wall_overlap_over_d50"] < 1e-2
        assert 0 < s["interior"]["1"]["n"] < s["n"]
        assert all(p["E"] > 0 for p in s["probes"].values())
    probes = d["states"]["5"]["probes"]
    assert probes["z"]["E"] > 1.1 * probes["x"]["E"]
