"""./main.sh on a small study: run twice in a row, then again with a state
added, then killed and resumed; a rerun asking for another specimen refuses; the contrast zeta in
the summary is checked against an independent route; progress lines reach the job's log.

One engine thread (--threads 1): these tests check the orchestration, not parallel speed."""
import csv
import json
import os
import shutil
import signal
import subprocess

import numpy as np
import pytest
from conftest import REPO, SCRIPTS, one_line_error

from trueaniso import specimen_file, zeta

ARGS = ("--n", "100", "--seed", "2", "--threads", "1", "--progress-every", "0")


def main_job(out, *args, timeout=900):
    return subprocess.run([os.path.join(REPO, "main.sh"), *ARGS, "--out", str(out), *args], capture_output=True,
                          text=True, timeout=timeout, cwd=REPO)


def rows(out):
    with open(out / "probes.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def first(tmp_path_factory):
    out = tmp_path_factory.mktemp("main") / "W"
    proc = main_job(out, "--ids", "1,5")
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return out, proc


def test_first_run_writes_everything_and_reports_progress(first):
    out, proc = first
    for name in ("specimen.npz", "probes.csv", "metadata.json", "summary.json", "statics_isotropic.json",
                 "figures/E_vs_sigma.png"):  # K and G against Zm need three states
        assert (out / name).exists(), name
    # Progress lines of the preparation, of a state and of a probe, in the job's own output.
    for label in ("specimen: step", "state 5: step", "state 5 probe z: step"):
        assert label in proc.stdout, label
    line = next(x for x in proc.stdout.splitlines() if x.startswith("state 5: step"))
    assert "stress error" in line and "unbalanced" in line and "|shear|" in line
    # specimen_state.json reports the whole stress: the principal values of its
    # six components (numpy here) and the largest off-diagonal, within 0.5 kPa of 100 kPa and of 0
    st = json.loads((out / "specimen_state.json").read_text())
    s = np.array([[st["sigma_x"], st["sigma_xy"], st["sigma_xz"]], [st["sigma_xy"], st["sigma_y"], st["sigma_yz"]],
                  [st["sigma_xz"], st["sigma_yz"], st["sigma_z"]]])
    principal = np.sort(np.linalg.eigvalsh(s))[::-1]
    np.testing.assert_allclose([st["sigma_1"], st["sigma_2"], st["sigma_3"]], principal, rtol=1e-12)
    np.testing.assert_allclose(principal, 100e3, atol=500.0)
    assert st["tau_max"] == np.abs([st["sigma_yz"], st["sigma_xz"], st["sigma_xy"]]).max() < 500.0
    # The contrast zeta of two states is weakly fixed: its line gives the standard errors, and says
    # when the search stopped at a bound, so that 0.000 (the bound) does not read as a calibration.
    contrast = json.loads((out / "summary.json").read_text())["zeta_contrast"]
    line = next(x for x in proc.stdout.splitlines() if x.startswith("zeta calibrated"))
    assert "zeta_h = %.3f +/- %.3f" % (contrast["zeta_h"], contrast["se_h"]) in line, line
    assert ("at a bound of the search" in line) == contrast["at_bound"], line


def test_rerun_in_a_row_does_nothing_new(first, tmp_path):
    out = tmp_path / "W"
    shutil.copytree(first[0], out)
    before = (out / "probes.csv").read_bytes()
    proc = main_job(out, "--ids", "1,5")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "probe z  E" not in proc.stdout and "specimen: kept" in proc.stdout
    assert (out / "probes.csv").read_bytes() == before


@pytest.fixture(scope="module")
def added_21(first, tmp_path_factory):
    """The first study continued with state 21 (--ids 1,5,21): its directory and run. A test that
    changes it works on a copy."""
    out = tmp_path_factory.mktemp("main21") / "W"
    shutil.copytree(first[0], out)
    return out, main_job(out, "--ids", "1,5,21")


def test_adding_states_continues_the_study(first, added_21):
    """States named by numbers and by text in one study: contrast_zeta orders them (no TypeError)."""
    out, proc = added_21
    before = (first[0] / "probes.csv").read_bytes()
    assert not (first[0] / "statics_state-21.json").exists()
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (out / "probes.csv").read_bytes().startswith(before)
    # what it kept is said before it goes on (a resumed run began at its next state without a word)
    assert "continuing the study; 2 of the 3 states asked for already have their rows (1, 5)" in proc.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["states"] == 3 and summary["probes"] == 9 and (out / "figures" / "K_G_vs_Zm.png").exists()
    # state 21 is Table B1's second state: its static solve is kept beside the isotropic one, and shown
    assert (out / "statics_state-21.json").exists() and "| 21 (b = 0.5" in (out / "report" / "report.md").read_text()
    # ... and its result line, as the isotropic state's
    record = json.loads((out / "statics_state-21.json").read_text())
    assert "statics (state 21): E_free = %s MPa" % [round(e / 1e6, 1) for e in record["E_free"]] in proc.stdout
    assert "statics (isotropic state): E_free" in proc.stdout and "this run took" in proc.stdout
    check_contrast_against_checkpoints(out, summary["zeta_contrast"])


def test_the_readme_says_what_the_main_job_prints_and_writes(first, added_21):
    """README.md's first screen: every file and folder it says ./main.sh writes into its results
    directory is there after a study with state 21, and every line it quotes begins as a line the
    job prints."""
    import re
    with open(os.path.join(REPO, "README.md")) as f:
        readme = f.read()
    writes = readme[readme.index("and writes `results/default/`"):]
    writes = writes[:writes.index("\n\n")]
    names = re.findall(r"`([\w./-]+)`", writes)[1:]
    assert {"specimen.npz", "probes.csv", "states/", "report/report.md"} <= set(names), names
    out, proc = added_21
    for name in names:
        assert (out / name).exists(), "README: ./main.sh writes %s" % name
    printed = readme[readme.index("```text", readme.index("./main.sh` prints")):]
    printed = printed[len("```text\n"):printed.index("```", 8)].strip().split("\n")
    said = first[1].stdout + proc.stdout
    for line in printed:
        head = re.split(r"[-\d]|results/", line, maxsplit=1)[0]  # the words before a number or the path
        assert len(head) > 5 and any(x.startswith(head) for x in said.splitlines()), line


def test_a_lost_checkpoint_of_state_21_is_reached_again(added_21, tmp_path):
    """With state 21's rows done, a removed states/21.npz (the advice for a damaged one) does not
    leave the study stuck ('specimen file not found' at each rerun): the state is reached again
    along its path and its static solve gives the same numbers
    (a resume reproduces a checkpoint's arrays bit for bit; 1e-9 covers the solver's last
    digits, which depend only on those arrays)."""
    assert added_21[1].returncode == 0, added_21[1].stderr[-3000:]
    out = tmp_path / "W"
    shutil.copytree(added_21[0], out)
    record = json.loads((out / "statics_state-21.json").read_text())
    before = (out / "probes.csv").read_bytes()
    (out / "states" / "21.npz").write_bytes(b"not a zip")  # damaged: a clear refusal naming the checkpoint
    proc = main_job(out, "--ids", "1,5,21")
    assert proc.returncode == 0  # the record exists: the checkpoint is not needed
    (out / "statics_state-21.json").unlink()
    proc = main_job(out, "--ids", "1,5,21")
    one_line_error(proc, "checkpoint of state 21", "remove it and rerun", yade=True)
    (out / "states" / "21.npz").unlink()
    proc = main_job(out, "--ids", "1,5,21")
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "state 21: reached" in proc.stdout and "probe z  E" not in proc.stdout
    assert (out / "probes.csv").read_bytes() == before
    again = json.loads((out / "statics_state-21.json").read_text())
    for k in ("E_free", "E_blocked"):
        np.testing.assert_allclose(again[k], record[k], rtol=1e-9)


def check_contrast_against_checkpoints(out, got):
    """The summary's zeta (fitted from the probe table's columns: pyscripts/trueaniso/analysis/zeta_contrast.py) must
    equal a fit whose stiffness parts come from the held-state checkpoints themselves (B and M of
    the scene, all 81 M components) and whose E_i come from the rows: the two routes share only
    fit_contrast. 1e-6: the fit converges to 1e-15; the columns hold every digit (repr)."""
    E, A_n, A_s = [], [], []
    by_state = {}
    for r in rows(out):
        by_state.setdefault(r["state"], {})[r["probe"]] = float(r["E"])
    for sid in got["states"]:
        scene, _ = specimen_file.load(str(out / "states" / ("%s.npz" % sid)))
        a_n, a_s = zeta.parts_from_scene(scene)
        E.append([by_state[sid][a] for a in "xyz"])
        A_n.append(a_n)
        A_s.append(a_s)
    assert sorted(got["states"]) == sorted(by_state) and got["n_states"] == len(by_state)
    ref = zeta.fit_contrast(np.array(E), np.array(A_n), np.array(A_s))
    for k in ("zeta_h", "zeta_v", "zeta"):
        assert abs(got[k] - ref[k]) < 1e-6, (k, got[k], ref[k])
    for k in ("rms", "rms_at_1", "rms_at_paper"):
        assert abs(got[k] - ref[k]) < 1e-9, (k, got[k], ref[k])


def test_other_specimen_recipe_is_refused_before_preparing(first, tmp_path):
    """--n 300 --seed 9 into the same --out is refused, not answered with the 100-sphere specimen."""
    out = tmp_path / "W"
    shutil.copytree(first[0], out)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".lock"}
    proc = subprocess.run([os.path.join(REPO, "main.sh"), "--n", "300", "--seed", "9", "--out", str(out)],
                          capture_output=True, text=True, timeout=300, cwd=REPO)
    one_line_error(proc, "another study", "--n 100 --seed 2", "--n 300 --seed 9", "--force-new", yade=True)
    assert "preparing" not in proc.stdout
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".lock"} == before
    # Same specimen, other loading friction: refused before the summary or anything else is touched.
    proc = subprocess.run(["/usr/bin/python3", os.path.join(SCRIPTS, "run_study.py"), *ARGS, "--out", str(out),
                           "--ids", "1,5,9", "--mu", "0.3"], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    one_line_error(proc, "another study", "state.friction")
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".lock"} == before
    # Same --n and --seed, another assembly: the assembly is part of the study's recipe.
    proc = subprocess.run(["/usr/bin/python3", os.path.join(SCRIPTS, "run_study.py"), *ARGS, "--out", str(out),
                           "--ids", "1,5", "--assembly", "clump2"], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    one_line_error(proc, "another study", "--assembly sphere --n 100", "--assembly clump2 --n 100")
    assert "preparing" not in proc.stdout
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".lock"} == before
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["fingerprint"]["assembly"] == "sphere" and meta["fingerprint"]["recipe"]["assembly"] == "sphere"


def test_a_path_rate_too_slow_is_refused_before_preparing(tmp_path):
    """run_study.py refuses --path-rate 1e-9 before it prepares the specimen (minutes at 4000
    spheres), not after, and leaves nothing behind."""
    out = tmp_path / "W"
    proc = subprocess.run(["/usr/bin/python3", os.path.join(SCRIPTS, "run_study.py"), *ARGS, "--out", str(out),
                           "--ids", "1,5", "--path-rate", "1e-9"], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    one_line_error(proc, "--path-rate 1e-09: state 1 is up to 100 Pa from the specimen's stress",
                   "known to within 100 Pa before it is prepared")
    assert "preparing" not in proc.stdout and not out.exists()


def test_kill_9_leaves_no_stale_summary_and_the_rerun_completes(first, tmp_path):
    """After a kill -9 among the states, no summary of the earlier run stays beside the new rows."""
    out = tmp_path / "W"
    shutil.copytree(first[0], out)
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.Popen(["/usr/bin/python3", os.path.join(SCRIPTS, "run_study.py"), *ARGS, "--out", str(out),
                          "--ids", "1,5,9,13"], env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    for line in p.stdout:  # kill as soon as the new work starts
        if line.startswith("state 9: b ="):
            break
    p.send_signal(signal.SIGKILL)
    p.wait()
    assert not (out / "summary.json").exists()
    proc = main_job(out, "--ids", "1,5,9,13")
    assert proc.returncode == 0, proc.stderr[-3000:]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["states"] == 4 and summary["probes"] == 12 == len(rows(out))


def test_killed_while_preparing_resumes_to_the_same_specimen(first, tmp_path):
    """A kill while the specimen is prepared loses only the work since the last checkpoint (the whole
    preparation is 82 min for clump1 at 4000 clumps): the rerun resumes from it, to the same bits."""
    out = tmp_path / "W"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    p = subprocess.Popen(["/usr/bin/python3", os.path.join(SCRIPTS, "run_study.py"), *ARGS, "--out", str(out),
                          "--ids", "1,5"], env=env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    for line in p.stdout:  # kill just after the first checkpoint of the preparation
        if line.startswith("checkpoint:"):
            break
    p.send_signal(signal.SIGKILL)
    p.wait()
    assert not (out / "specimen.npz").exists() and (out / ".specimen.npz.checkpoint").exists()
    proc = main_job(out, "--ids", "1,5")
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "resuming the preparation from" in proc.stdout
    assert not (out / ".specimen.npz.checkpoint").exists()
    a = specimen_file.scene_arrays(specimen_file.load(str(first[0] / "specimen.npz"))[0])
    b = specimen_file.scene_arrays(specimen_file.load(str(out / "specimen.npz"))[0])
    assert all(np.array_equal(a[k], b[k]) for k in a)
    assert [r["E"] for r in rows(out)] == [r["E"] for r in rows(first[0])]


def test_two_studies_cannot_share_a_directory(tmp_path):
    """Two run_study.py runs on one --out: the second is refused, so no study mixes two seeds' specimens."""
    from trueaniso import lock
    out = tmp_path / "W"
    with lock.held(str(out)):
        proc = subprocess.run(["/usr/bin/python3", os.path.join(SCRIPTS, "run_study.py"), "--n", "100", "--seed", "9",
                               "--out", str(out)], capture_output=True, text=True, timeout=300)
    one_line_error(proc, "in use by another run", "--wait")
    assert sorted(p.name for p in out.iterdir()) == [".lock"]


def test_run_states_on_a_study_of_run_study_says_whose_it_is(first, tmp_path):
    """A difference is said by the option the user set, not 'recipe.assembly is "sphere" there, absent in this run'."""
    out = tmp_path / "W"
    shutil.copytree(first[0], out)
    proc = subprocess.run(["/usr/bin/python3", os.path.join(SCRIPTS, "run_states.py"), "--specimen",
                           str(out / "specimen.npz"), "--out", str(out), "--ids", "1", "--threads", "1"],
                          capture_output=True, text=True, timeout=300, env=dict(os.environ, OMP_NUM_THREADS="1"))
    one_line_error(proc, "a study made by run_study.py", "recipe.assembly", "continue it with run_study.py")
