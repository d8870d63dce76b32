"""Rolling resistance through the Python module and the study scripts (docs/rolling.md):
the scene's parameters and their refusals, the specimen file's rolling moments, the static
solve's refusal, and run_states.py with --rolling-stiffness/--rolling-friction (the moments reach
the checkpoints, the settings enter the study's fingerprint, half-given settings are refused)."""
import csv
import json
import math
import os

import numpy as np
import pytest
from conftest import one_line_error, run_script

from trueaniso import dem, engines as E, specimen_file, statics, triaxial


def _rolled(specimen_100):
    """The 100-sphere specimen with rolling resistance on, run a little so moments build up."""
    s, _ = specimen_file.load(str(specimen_100))
    triaxial.set_rolling(s, 0.25, 0.1)
    s.angular_velocities = np.random.default_rng(1).normal(size=(s.num_bodies, 3)) * 50.0
    chain = dem.Chain(s)
    chain.run(50)
    dem.refresh(s)
    return s


def test_scene_parameters_and_refusals():
    s = E.Scene()
    assert (s.rolling_stiffness, s.rolling_friction) == (0.0, 0.0)  # off by default: the paper's law
    s.rolling_stiffness, s.rolling_friction = 0.25, 0.1
    for bad in (-0.1, math.nan, math.inf):
        with pytest.raises(ValueError, match="rolling stiffness factor beta"):
            s.rolling_stiffness = bad
        with pytest.raises(ValueError, match="rolling friction eta_r"):
            s.rolling_friction = bad
    assert (s.rolling_stiffness, s.rolling_friction) == (0.25, 0.1)  # a refused value changes nothing
    assert triaxial.rolling_problem(0.25, 0.0) and triaxial.rolling_problem(0.0, 0.1)  # half given
    assert "clumps" in triaxial.rolling_problem(0.25, 0.1, clumps=True)
    assert triaxial.rolling_problem(0.0, 0.0, clumps=True) is None


def test_specimen_file_keeps_the_rolling_moments(specimen_100, tmp_path):
    s = _rolled(specimen_100)
    c = s.contact_arrays()
    active = c["normal_force"] > 0
    assert np.abs(c["rolling_moment"][active]).max() > 0
    path = str(tmp_path / "rolled.npz")
    specimen_file.save(path, s)
    t, meta = specimen_file.load(path)
    assert meta["material"]["rolling_stiffness"] == 0.25 and meta["material"]["rolling_friction"] == 0.1
    assert (t.rolling_stiffness, t.rolling_friction) == (0.25, 0.1)
    d = t.contact_arrays()
    assert np.array_equal(d["rolling_moment"][d["normal_force"] > 0], c["rolling_moment"][active])
    # A file without rolling resistance is written as before (no rolling array, no rolling fields).
    u, _ = specimen_file.load(str(specimen_100))
    plain = str(tmp_path / "plain.npz")
    specimen_file.save(plain, u)
    with np.load(plain) as z:
        assert "c_rolling_moment" not in z.files
        assert "rolling_stiffness" not in json.loads(str(z["meta"]))["material"]
    # Rolling moments that the checksum does not cover (added to a file without rolling) are refused.
    with np.load(plain) as z:
        data = {k: z[k] for k in z.files}
    data["c_rolling_moment"] = np.zeros((data["c_member1"].shape[0], 3))
    forged = str(tmp_path / "forged.npz")
    np.savez(forged, **data)
    with pytest.raises(specimen_file.SpecimenFileError, match="rolling moments stored"):
        specimen_file.read(forged)


def test_static_solve_refuses_rolling_resistance(specimen_100):
    s, _ = specimen_file.load(str(specimen_100))
    s.rolling_stiffness, s.rolling_friction = 0.25, 0.1
    with pytest.raises(ValueError, match="does not model rolling resistance"):
        statics.static_stiffness(s)


def test_run_states_with_rolling_resistance(specimen_100, tmp_path):
    """One state and one probe with rolling on: the checkpoint holds the rolling material and
    moments, the row its Zm_gap1e-3; a rerun without the options, or with other values, refuses."""
    out = tmp_path / "roll"
    args = ["--specimen", specimen_100, "--out", out, "--ids", "1", "--probes", "z", "--threads", "1"]
    proc = run_script("run_states.py", *args, "--rolling-stiffness", "0.25", "--rolling-friction", "0.1")
    assert proc.returncode == 0, proc.stderr
    a, meta = specimen_file.read(str(out / "states" / "1.npz"))
    assert meta["material"]["rolling_stiffness"] == 0.25 and np.abs(a["c_rolling_moment"]).max() > 0
    fp = json.loads((out / "metadata.json").read_text())["fingerprint"]["state"]
    assert (fp["rolling_stiffness"], fp["rolling_friction"]) == (0.25, 0.1)
    with open(out / "probes.csv", newline="") as f:
        row = next(csv.DictReader(f))
    assert float(row["Zm_gap1e-3"]) >= float(row["Zm"]) > 0
    from trueaniso.analysis import path_fidelity  # the checkpoints recount the row's two columns exactly
    assert path_fidelity.gap_scan(str(out), [1e-3])["1"] == [float(row["Zm"]), float(row["Zm_gap1e-3"])]
    before = (out / "probes.csv").read_bytes()
    one_line_error(run_script("run_states.py", *args), "another study", "state.rolling_")
    one_line_error(run_script("run_states.py", *args, "--rolling-stiffness", "0.5", "--rolling-friction", "0.1"),
                   "another study", "state.rolling_stiffness")
    assert (out / "probes.csv").read_bytes() == before
    # Half-given settings: refused before any work, nothing written.
    fresh = tmp_path / "half"
    one_line_error(run_script("run_states.py", *args[:3], fresh, *args[4:], "--rolling-stiffness", "0.25"),
                   "rolling friction eta_r")
    assert not os.path.exists(fresh / "metadata.json")
    # Its checkpoint as the specimen of a study without the options: taken, and said that the law
    # of this run has no rolling resistance (it was run with rolling off without a word).
    proc = run_script("run_states.py", "--specimen", out / "states" / "1.npz", "--out", tmp_path / "from1",
                      "--ids", "1", "--probes", "z", "--threads", "1")
    assert proc.returncode == 0, proc.stderr
    assert "was made with rolling resistance (beta 0.25), which this run turns off" in proc.stdout
