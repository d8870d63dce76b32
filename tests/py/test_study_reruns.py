"""A results directory is one study: reruns prove they continue it or refuse in one
line; a resumed run gives exactly the rows of an uninterrupted one; a torn row is redone; two runs
on one directory lose no row (a lock: refusal, or an orderly wait).

Every study here runs on the 100-sphere specimen with few states and probes; each test says
which wrong behaviour it catches."""
import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest
from conftest import SCRIPTS, one_line_error, run_script

from trueaniso import specimen_file, study_dir

WALL = {"probe_wall_time", "state_wall_time"}  # study.WALL_TIME_COLUMNS: the only columns a rerun may change


def states(spec, out, *args, **kw):
    return run_script("run_states.py", "--specimen", spec, "--out", out, *args, **kw)


def rows(out):
    with open(os.path.join(out, "probes.csv"), newline="") as f:
        return list(csv.DictReader(f))


def values(out):
    """Every cell but the wall times, in file order: what a rerun must reproduce exactly."""
    return [{k: v for k, v in r.items() if k not in WALL} for r in rows(out)]


@pytest.fixture(scope="module")
def base(specimen_100, tmp_path_factory):
    """States 1, 2 and 3 (3 is reached from 2), probes z and x, uninterrupted."""
    out = tmp_path_factory.mktemp("base") / "study"
    proc = states(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    return out


def copy(base, tmp_path):
    dst = tmp_path / "study"
    shutil.copytree(base, dst)
    return dst


def test_resume_from_checkpoints_is_bit_identical(base, specimen_100, tmp_path):
    """Rows after a resume equal those of the uninterrupted run cell for cell: probes from a
    reloaded checkpoint against probes of the scene in memory would differ by up to 1.9e-4, and
    state_steps must not read 0."""
    out = copy(base, tmp_path)
    text = (out / "probes.csv").read_text().splitlines(True)
    (out / "probes.csv").write_text("".join(text[:4]))  # header, state 1 z and x, state 2 z
    (out / "states" / "3.npz").unlink()
    proc = states(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("probe x  E") == 2 and "state 3: b =" in proc.stdout  # state 2 x, state 3 z and x redone
    # what it keeps is said: the rows, and a checkpoint an earlier run reached without its rows
    assert "continuing the study; 1 of the 3 states asked for already has its rows (1)" in proc.stdout
    assert "state 2: reached by an earlier run; probed from its checkpoint" in proc.stdout
    assert values(out) == values(base)  # every digit of every non-time column
    assert all(int(r["state_steps"]) > 0 for r in rows(out))
    assert {r["state"]: r["state_from"] for r in rows(out)} == {"1": "specimen", "2": "specimen", "3": "2"}


def test_states_added_later_start_from_the_study_s_checkpoints(base, specimen_100, tmp_path):
    """A state added by a later run is reached from the nearest state before it on its path that
    the study holds, so a study grown in path order has the rows of one run: --ids 1,2,3 then
    --ids 5 reaches 5 from 3, as --ids 1,2,3,5 does (from the specimen, 234 cells would differ,
    E_z by 3e-6). Serially and on an executor's worker processes, as under --mpi."""
    import concurrent.futures
    from trueaniso import study
    whole = tmp_path / "whole"
    assert states(specimen_100, whole, "--ids", "1,2,3,5", "--probes", "zx").returncode == 0
    added = copy(base, tmp_path)
    proc = states(specimen_100, added, "--ids", "5", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert "state 5: b = 0.00, sigma_z = 140.0 kPa, from state 3" in proc.stdout
    assert values(added) == values(whole)  # every digit of every non-time column, state_from 3 included
    # on worker processes (the job carries which states are probed: states 1-3 are starts only)
    pooled = tmp_path / "pooled"
    shutil.copytree(base, pooled)
    threads = study.engines.threads()
    study.engines.set_threads(1)  # the study's count, as run_script's OMP_NUM_THREADS=1
    try:
        with concurrent.futures.ProcessPoolExecutor(1) as pool:
            study.run_states(str(specimen_100), study.table_states([5]), str(pooled), probes="zx",
                             log=lambda m: None, executor=pool)
    finally:
        study.engines.set_threads(threads)
    assert values(pooled) == values(whole)
    # an earlier state's checkpoint removed (as a refusal of a damaged one advises): reached again
    # on the way, so state 5 still starts from 3, not from 2
    gone = copy(base, tmp_path / "gone")
    (gone / "states" / "3.npz").unlink()
    proc = states(specimen_100, gone, "--ids", "5", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert "state 3: b = 0.00, sigma_z = 120.0 kPa, from state 2" in proc.stdout and (gone / "states" / "3.npz").exists()
    assert values(gone) == values(whole)


def test_a_checkpoint_reached_again_starts_where_its_rows_came_from(specimen_100, tmp_path):
    """A study grown out of path order (--ids 1,3, then 2) reached 3 from the specimen; its
    checkpoint, lost and reached again for a later state, starts there again, not from 2, so it
    has the bytes its rows came from."""
    out = tmp_path / "study"
    for ids in ("1,3", "2"):
        assert states(specimen_100, out, "--ids", ids, "--probes", "z").returncode == 0
    first, _ = specimen_file.read(str(out / "states" / "3.npz"))
    (out / "states" / "3.npz").unlink()
    proc = states(specimen_100, out, "--ids", "4", "--probes", "z")
    assert proc.returncode == 0, proc.stderr
    assert "state 3: b = 0.00, sigma_z = 120.0 kPa, from the specimen" in proc.stdout
    again, _ = specimen_file.read(str(out / "states" / "3.npz"))
    assert all(np.array_equal(first[k], again[k]) for k in first)
    assert {r["state"]: r["state_from"] for r in rows(out)}["4"] == "3"


def test_a_checkpoint_of_another_study_is_refused(base, specimen_100, tmp_path):
    """A checkpoint records its study's key (the fingerprint without the probe options): one
    copied from a study at --mu 0.3 into this one is refused on load, naming the file, not taken
    up without a word to reach state 5 from it."""
    other = tmp_path / "mu"
    assert states(specimen_100, other, "--ids", "2,3", "--probes", "z", "--mu", "0.3").returncode == 0
    out = copy(base, tmp_path)
    shutil.copy(other / "states" / "3.npz", out / "states" / "3.npz")
    proc = states(specimen_100, out, "--ids", "5", "--probes", "zx")
    one_line_error(proc, "3.npz", "made by another study", "remove it and rerun")
    assert not (out / "states" / "5.npz").exists()


def running_until_first_row(spec, out, *args):
    """run_states.py started in the background on one thread, handed back once its first row is in
    probes.csv (or it has ended, or 300 s have passed); its stderr is a pipe for the caller."""
    p = subprocess.Popen([sys.executable, os.path.join(SCRIPTS, "run_states.py"), "--specimen", str(spec),
                          "--out", str(out), *args], env=dict(os.environ, OMP_NUM_THREADS="1"),
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 300
    while p.poll() is None and time.time() < deadline:
        if (out / "probes.csv").exists() and (out / "probes.csv").stat().st_size > 0:
            break
        time.sleep(0.01)
    return p


def test_kill_9_then_rerun_gives_the_uninterrupted_rows(base, specimen_100, tmp_path):
    """A real kill -9 at whatever moment the first row appears; the rerun repairs and completes."""
    out = tmp_path / "study"
    p = running_until_first_row(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    p.send_signal(signal.SIGKILL)
    p.communicate(timeout=120)
    proc = states(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert values(out) == values(base)


def test_sigterm_says_the_study_resumes_and_it_does(specimen_100, tmp_path):
    """SIGTERM (kill's default, a scheduler's time limit), whose default action ends Python with no
    word: one line says the same command resumes, exit 143 (128 + 15), and it does."""
    out = tmp_path / "study"
    ids = ("--ids", "1,2,3,4,5,6,7,8", "--probes", "z")
    p = running_until_first_row(specimen_100, out, *ids)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 143, "status %d (0: the study ended before the signal), stderr:\n%s" % (p.returncode, err)
    # The state or probe under way is redone from the last finished state (study.run_states).
    assert err.splitlines()[-1] == ("error: interrupted; the same command resumes from the finished states and probes; "
                                    "one cut short starts again from the last state finished before it on its path, "
                                    "or from the specimen"), err
    assert len(rows(out)) < 8
    proc = states(specimen_100, out, *ids)
    assert proc.returncode == 0, proc.stderr
    assert sorted(int(r["state"]) for r in rows(out)) == list(range(1, 9))  # each once, in the order of its path


def test_torn_row_is_redone_not_counted(base, specimen_100, tmp_path):
    """A row cut mid-line (kill -9 during a write, a full disk) is redone, not counted as done."""
    out = copy(base, tmp_path)
    text = (out / "probes.csv").read_text()
    lines = text.splitlines(True)
    (out / "probes.csv").write_text("".join(lines[:-1]) + lines[-1][:60])  # state 3 x cut after 60 characters
    proc = states(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert "cut short" in proc.stdout and proc.stdout.count("probe x  E") == 1
    assert (out / "probes.csv").read_text().endswith("\n")
    assert values(out) == values(base)


def test_stray_temporaries_of_dead_runs_are_removed(base, specimen_100, tmp_path):
    """.tmp-* files of killed runs are removed by the next run."""
    out = copy(base, tmp_path)
    for p in (out / ".tmp-abc-probes.csv", out / "states" / ".tmp-def-2.npz"):
        p.write_text("half")
    proc = states(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert not list(out.rglob(".tmp-*"))


def test_rerun_of_a_finished_study_does_nothing(base, specimen_100, tmp_path):
    out = copy(base, tmp_path)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".lock"}
    proc = states(specimen_100, out, "--ids", "1,2,3", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert ": probe " not in proc.stdout, proc.stdout  # no probe's line ('state 1: probe z  E = ...')
    assert "no state to run" in proc.stdout, proc.stdout  # said, beyond continuing the study
    # and changes nothing, as the manual says: metadata.json does not add the run to its runs
    after = {p: p.read_bytes() for p in out.rglob("*") if p.is_file() and p.name != ".lock"}
    assert sorted(after) == sorted(before) and [p for p in before if after[p] != before[p]] == []


@pytest.mark.parametrize("args,field", [
    (["--gamma", "2e-6"], ("--gamma; probe.gamma",)),
    (["--rotations", "restrained"], ("--rotations; probe.rotations",)),
    (["--mu", "0.3"], ("--mu; state.friction",)),  # the option named beside its field
    (["--damping", "0.3"], ("--damping", "damping")),
    (["--skip-detection"], ("--skip-detection; probe.detection",)),
    (["--rolling-stiffness", "0.25", "--rolling-friction", "0.1"], ("--rolling-", "state.rolling_")),
])
def test_other_settings_are_refused_in_one_line(base, specimen_100, tmp_path, args, field):
    """Rows made with other settings are refused, not appended (metadata would list only the
    last). The refusal names the option that sets what differs, beside its field in metadata.json."""
    out = copy(base, tmp_path)
    before = (out / "probes.csv").read_bytes(), (out / "metadata.json").read_bytes()
    proc = states(specimen_100, out, "--ids", "1,2,3,4", "--probes", "zx", *args)
    one_line_error(proc, "another study", *field, "--force-new", "new --out")
    assert ((out / "probes.csv").read_bytes(), (out / "metadata.json").read_bytes()) == before
    assert not (out / "states" / "4.npz").exists()


def test_a_rerun_without_threads_continues_at_the_study_s_count(base, specimen_100, tmp_path):
    """A rerun that does not give --threads adopts the study's count, not all cores (which would be
    refused: 'threads is 1 there, 2 in this run', for a count the user never chose); an explicit
    other count is refused (the last bits depend on it)."""
    out = copy(base, tmp_path)
    before = (out / "probes.csv").read_bytes()
    proc = states(specimen_100, out, "--ids", "1,2,3,4", "--probes", "zx", env=dict(OMP_NUM_THREADS="2"))
    assert proc.returncode == 0, proc.stderr
    assert "its study ran at 1 engine thread, so this run does too" in proc.stdout and "state 4: probe x" in proc.stdout
    assert (out / "probes.csv").read_bytes().startswith(before)
    assert json.loads((out / "metadata.json").read_text())["fingerprint"]["threads"] == 1
    proc = states(specimen_100, out, "--ids", "1,2,3,4", "--probes", "zx", "--threads", "2")
    one_line_error(proc, "another study", "thread count", "--threads 1")
    # --threads 0 is OpenMP's count, OMP_NUM_THREADS's when set: the refusal says where this run's
    # came from (0 reads 'all cores' in the help; '2 in this run' alone would not explain it)
    proc = states(specimen_100, out, "--ids", "1,2,3,4", "--probes", "zx", "--threads", "0",
                  env=dict(OMP_NUM_THREADS="2"))
    one_line_error(proc, "thread count (threads) is 1 there, 2 in this run (OMP_NUM_THREADS=2)", "--threads 1")
    # ... held to --threads' own limit (16 on 2 cores made a study no --threads could continue)
    fresh = tmp_path / "fresh"
    proc = states(specimen_100, fresh, "--ids", "1", "--probes", "z", "--threads", "0", env=dict(OMP_NUM_THREADS="64"))
    one_line_error(proc, "OMP_NUM_THREADS=64, the count --threads 0 takes, is above")
    assert not fresh.exists()


def test_other_specimen_is_refused(base, specimen_100, tmp_path):
    """Another --specimen is refused: state 3 would be computed from the old specimen's checkpoint."""
    scene, meta = specimen_file.load(str(specimen_100))
    other = tmp_path / "other.npz"
    specimen_file.save(str(other), scene, seed=99, parameters=meta["parameters"])  # same grains, another file
    out = copy(base, tmp_path)
    proc = states(other, out, "--ids", "2,3,4", "--probes", "zx")
    one_line_error(proc, "another study", "specimen", "--force-new")


def test_code_version_and_old_layout_are_refused(base, specimen_100, tmp_path):
    out = copy(base, tmp_path)
    meta = json.loads((out / "metadata.json").read_text())
    meta["fingerprint"]["code"] = "src-0000000000000000"
    (out / "metadata.json").write_text(json.dumps(meta))
    one_line_error(states(specimen_100, out, "--ids", "1", "--probes", "zx"), "code", "src-0000000000000000")
    del meta["layout"]
    (out / "metadata.json").write_text(json.dumps(meta))
    one_line_error(states(specimen_100, out, "--ids", "1", "--probes", "zx"), "older trueaniso", "--force-new")


def test_force_new_moves_the_old_study_aside(base, specimen_100, tmp_path):
    out = copy(base, tmp_path)
    old = (out / "probes.csv").read_bytes()
    proc = states(specimen_100, out, "--ids", "1", "--probes", "z", "--gamma", "2e-6", "--force-new")
    assert proc.returncode == 0, proc.stderr
    (kept,) = (out / "superseded").iterdir()
    assert (kept / "probes.csv").read_bytes() == old and (kept / "states" / "3.npz").exists()
    assert [(r["state"], r["probe"], float(r["gamma"]) >= 2e-6) for r in rows(out)] == [("1", "z", True)]


def test_states_ids_come_from_the_definition(specimen_100, tmp_path):
    """--states ids come from the state's definition, not its place in the list: --states 0:125e3
    then --states 0.5:85e3 are two states, not both 's1' (the second run would compute nothing)."""
    out = tmp_path / "study"
    assert states(specimen_100, out, "--states", "0:125e3", "--probes", "z").returncode == 0
    proc = states(specimen_100, out, "--states", "0.5:85e3,0.5:140e3", "--probes", "z")
    assert proc.returncode == 0, proc.stderr
    assert [r["state"] for r in rows(out)] == ["b0_sz125000", "b0.5_sz85000", "21"]  # 0.5:140e3 is Table C1's 21
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["states"]["b0_sz125000"] == dict(b=0.0, sigma_z=125e3)
    assert meta["states"]["b0.5_sz85000"] == dict(b=0.5, sigma_z=85e3)


def test_second_run_refuses_while_the_directory_is_locked(base, specimen_100, tmp_path):
    """A second run on a locked --out is refused: two runs on one directory would lose rows."""
    from trueaniso import lock
    out = copy(base, tmp_path)
    before = (out / "probes.csv").read_bytes()
    with lock.held(str(out)):
        proc = states(specimen_100, out, "--ids", "1,2,3,4", "--probes", "zx")
    one_line_error(proc, "in use by another run", "pid %d" % os.getpid(), "--wait")
    assert (out / "probes.csv").read_bytes() == before


def test_wait_queues_behind_the_holder(base, specimen_100, tmp_path):
    from trueaniso import lock
    out = copy(base, tmp_path)
    before = (out / "probes.csv").read_bytes()
    env = dict(os.environ, OMP_NUM_THREADS="1")
    with lock.held(str(out)):
        p = subprocess.Popen([sys.executable, os.path.join(SCRIPTS, "run_states.py"), "--specimen", str(specimen_100),
                              "--out", str(out), "--ids", "1,2,3,6", "--probes", "zx", "--wait"], env=env,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        first = p.stdout.readline()  # the waiting run says so, then blocks
        if "its study ran at 1 engine thread, so this run does too" in first:  # it took the study's thread count
            first = p.stdout.readline()
        assert first.startswith("waiting for the run that holds"), first
        assert p.poll() is None and (out / "probes.csv").read_bytes() == before
    stdout, stderr = p.communicate(timeout=300)
    assert p.returncode == 0, stderr
    assert len(rows(out)) == 8 and (out / "probes.csv").read_bytes().startswith(before)


def test_two_concurrent_runs_lose_no_row(specimen_100, tmp_path):
    out = tmp_path / "study"
    env = dict(os.environ, OMP_NUM_THREADS="1")
    procs = [subprocess.Popen([sys.executable, os.path.join(SCRIPTS, "run_states.py"), "--specimen",
                               str(specimen_100), "--out", str(out), "--ids", ids, "--probes", "zx", "--wait"],
                              env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for ids in ("1,2", "6,7")]
    for p in procs:
        _, err = p.communicate(timeout=600)
        assert p.returncode == 0, err
    assert sorted((r["state"], r["probe"]) for r in rows(out)) == sorted(
        (s, a) for s in ("1", "2", "6", "7") for a in "zx")


def _fail_at(monkeypatch, sigma_z):
    """reach_state raises for the state at sigma_z, as the servo does for a specimen near its
    strength (held without settling); the other states are reached for real."""
    from trueaniso import triaxial
    real = triaxial.reach_state

    def reach(scene, b, sz, *a, **kw):
        if sz == sigma_z:
            raise triaxial.StateNotReached("state b = %g, sigma_z = %g Pa not reached (test)" % (b, sz))
        return real(scene, b, sz, *a, **kw)
    monkeypatch.setattr(triaxial, "reach_state", reach)


def test_a_state_not_reached_ends_its_own_path_only(specimen_100, tmp_path, monkeypatch):
    """A state not reached ends its own path (the later state 7 starts from 6 and is left too),
    not the study: the other paths are run, and the run fails at the end naming the state."""
    from trueaniso import study, triaxial
    _fail_at(monkeypatch, 90e3)  # state 6 (b = 0, sigma_z = 90 kPa): the path 6, 7
    out = tmp_path / "study"
    log = []
    with pytest.raises(triaxial.StateNotReached) as err:
        study.run_states(str(specimen_100), study.table_states([1, 2, 6, 7]), str(out), probes="z", log=log.append)
    assert "1 loading path stopped" in str(err.value) and "sigma_z = 90000 Pa not reached" in str(err.value)
    assert "states left without probes on this path: 6, 7" in str(err.value)
    assert sorted(r["state"] for r in rows(out)) == ["1", "2"]
    assert any(m.startswith("error: ") and "the other paths go on" in m for m in log)


def test_a_worker_returns_its_rows_and_the_state_not_reached(specimen_100, tmp_path, monkeypatch):
    """The MPI worker's side, one state a task: a state hands back its rows (and its checkpoint
    is written for the next); a state not reached hands back the message instead of raising
    (which stopped the manager and, when a worker walked a whole path, lost the path's rows)."""
    from trueaniso import study
    _fail_at(monkeypatch, 80e3)  # state 7, after 6 on the path 6, 7
    out = tmp_path / "study"
    study.run_states(str(specimen_100), study.table_states([1]), str(out), probes="z", log=lambda m: None)
    run = study._Run(str(specimen_100), study.specimen_file.read(str(specimen_100))[1], str(out),
                     json.loads((out / "metadata.json").read_text())["fingerprint"], ["z"], None,
                     study.results_csv.Table(None, [], [], None), lambda m: None, 5.0, "true-triaxial",
                     dict(gamma=1e-6, restrain_rotations=False, skip_detection=False, damping=0.4),
                     dict(damping=0.4, friction=0.5))
    path = [(6, 0.0, 90e3), (7, 0.0, 80e3)]
    got, failure = study._state_worker(run.job(path, 0))
    assert [r["state"] for r, _ in got] == [6] and failure is None and (out / "states" / "6.npz").exists()
    got, failure = study._state_worker(run.job(path, 1))
    assert got == [] and "sigma_z = 80000 Pa not reached" in failure


def test_differences_are_named_one_way_for_studies_checkpoints_and_specimens():
    """study_dir.differences serves the study fingerprint, the preparation checkpoint and the
    specimen file's settings: nested fields flattened, a missing field named, numbers within
    rel_tol the same (a specimen stores d50 as the distribution computed it), text compared as text."""
    from trueaniso import study_dir
    there = dict(seed=3, d50=1e-3 * (1 + 1e-12), law=dict(mu=0.5), law_name="hertz")
    here = dict(seed=4, d50=1e-3, law=dict(mu=0.5, rolling=0.1), law_name="hertz")
    assert study_dir.said(study_dir.differences(there, here, rel_tol=1e-9)) == [
        "law.rolling: absent there, 0.1 here", "seed: 3 there, 4 here"]
    assert [k for k, _, _ in study_dir.differences(there, here)] == ["d50", "law.rolling", "seed"]
    assert study_dir.said(study_dir.differences(dict(a="clump1"), dict(a="clump2"), rel_tol=0.5)) == [
        'a: "clump1" there, "clump2" here']
    # A non-finite number as typed, whether a float (this run) or metadata's text: JSON's
    # 'Infinity' in a refusal line would not be what the user wrote.
    assert study_dir.said(study_dir.differences(dict(r="inf"), dict(r=2.0))) == ["r: inf there, 2.0 here"]
    assert study_dir.said(study_dir.differences(dict(r=2.0), dict(r=float("inf")))) == ["r: 2.0 there, inf here"]


def test_saved_work_is_a_row_or_a_state_checkpoint(tmp_path):
    """What decides whether an interrupted study promises a resume (cli.saves_work_in)."""
    out = tmp_path / "study"
    assert not study_dir.has_saved_work(str(out))  # not there yet
    (out / "states").mkdir(parents=True)
    (out / "states" / ".tmp-abc-1.npz").write_text("half")  # a torn write is nothing to resume from
    (out / "probes.csv").write_text("state,probe\n")  # a header alone neither
    assert not study_dir.has_saved_work(str(out))
    (out / "probes.csv").write_text("state,probe\n1,z\n")
    assert study_dir.has_saved_work(str(out))
    (out / "probes.csv").unlink()
    (out / "states" / "1.npz").write_text("x")
    assert study_dir.has_saved_work(str(out))


def test_the_path_rate_is_checked_from_where_each_state_starts():
    """A state is reached from the state before it on its loading path (triaxial.paths), so the
    path rate is checked over that distance: measured from the specimen, state 3 (sigma_z 120 kPa,
    after state 2 at 110 kPa) would be refused at rates that reach it from state 2's checkpoint,
    and a study holding state 2 could never be grown."""
    from trueaniso import study
    s2, s3 = study.table_states([2, 3])
    p = (100e3, 100e3, 100e3)
    # 10 kPa a state at 0.005 Pa per step: 2,000,000 steps each, within the servo's 3,000,000
    study.refuse_slow_paths([s2, s3], "true-triaxial", p, dict(path_rate=0.005))
    with pytest.raises(study.InputError) as refused:
        study.refuse_slow_paths([s3], "true-triaxial", p, dict(path_rate=0.005))  # alone, from the specimen
    said = str(refused.value)
    assert "state 3 is 20000 Pa from the specimen's stress, where its path starts: about 4e+06 steps" in said
    # the least rate, 20000 Pa over the 3,000,000 - 200 steps the ramp may take, rounded up (it said
    # 'at least' twice that); and, since a study's rate is fixed, the states that shorten the way
    assert "the least rate that fits is 0.00667 Pa per step" in said and said.endswith("(--ids 2,3)")
    study.refuse_slow_paths([s3], "true-triaxial", p, dict(path_rate=0.00667))
    s4, = study.table_states([4])  # sigma_z 130 kPa: 20 kPa beyond state 2
    with pytest.raises(study.InputError, match="state 4 is 20000 Pa from state 2's stress, the state before it"):
        study.refuse_slow_paths([s2, s4], "true-triaxial", p, dict(path_rate=0.005))
    # A ramp that ends within the servo's 200 settling steps of its limit cannot be reached (it
    # would run 3,000,000 steps at 0.0066629 for state 3, then say 'no equilibrium').
    with pytest.raises(study.InputError, match="less the 200 it holds a state"):
        study.refuse_slow_paths([s2], "true-triaxial", p, dict(path_rate=10e3 / 2_999_900))
    # Before the specimen exists its stress is known to within the preparation's tolerance: state 1
    # is 0 Pa from 100 kPa, but up to 100 Pa from a prepared specimen (run_study refused after preparing).
    s1, = study.table_states([1])
    study.refuse_slow_paths([s1], "true-triaxial", p, dict(path_rate=1e-6))
    with pytest.raises(study.InputError, match="known to within 100 Pa before it is prepared"):
        study.refuse_slow_paths([s1], "true-triaxial", p, dict(path_rate=1e-6), start_within=100.0)


def test_a_specimen_saved_without_summary_is_checked_too(specimen_100, tmp_path):
    """A specimen saved from a YADE scene (yade_bridge, then specimen_file.save) has no summary: the
    path-rate check measures its stresses on the file's scene, so --path-rate 1e-9 is refused
    before loading starts."""
    from trueaniso import specimen_file
    scene, meta = specimen_file.load(str(specimen_100))
    bare = tmp_path / "bare.npz"
    specimen_file.save(str(bare), scene, seed=meta["seed"])
    assert not specimen_file.read(str(bare))[1].get("summary")
    proc = states(bare, tmp_path / "study", "--ids", "5", "--probes", "z", "--path-rate", "1e-9")
    one_line_error(proc, "--path-rate 1e-09: state 5 is", "from the specimen's stress")
    assert not (tmp_path / "study" / "probes.csv").exists()
