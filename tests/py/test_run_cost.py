"""A run records what it cost (trueaniso/run_cost.py): a study's run in metadata.json however it
ends, a preparation over all its runs through its checkpoints, a static solve in its record; a run's
--threads holds numpy's BLAS too; and the cost tables (analysis/cost.py) are the data's."""
import csv
import json
import os
import time

import pytest
import threadpoolctl

from conftest import REPO
from trueaniso import cli, engines, prep_checkpoint, resources, run_cost, specimen, specimen_file, statics, study, validate
from trueaniso.analysis import cost

SPECIMEN = os.path.join(REPO, "tests", "data", "spheres-150-s4.npz")


def _burn(seconds):
    """CPU work of about `seconds` (a loop: time the meter must count)."""
    t = run_cost.cpu_seconds()
    x = 0
    while run_cost.cpu_seconds() - t < seconds:
        x += sum(range(1000))
    return x


def test_the_meter_counts_this_runs_work_on_top_of_what_earlier_runs_carried():
    # The wall time against what the test measures around the same work: a thread the process left
    # spinning (OpenBLAS, an OpenMP team) adds CPU time faster than the wall clock runs, so 0.2 s of
    # CPU can take less than 0.2 s of wall time.
    m = run_cost.Meter()
    wall0, cpu0 = time.monotonic(), run_cost.cpu_seconds()
    _burn(0.2)
    wall, cpu = time.monotonic() - wall0, run_cost.cpu_seconds() - cpu0
    s = m.spent()
    # 0.0015: the meter rounds to 1 ms
    assert 0.2 <= s["cpu_time"] < 5 and s["cpu_time"] >= cpu - 0.0015 and s["wall_time"] >= wall - 0.0015
    assert s["peak_memory_mb"] > 10
    carried = dict(wall_time=100.0, cpu_time=50.0, peak_memory_mb=1e6, load_min=0.0, load_max=1e3, runs=2)
    t = run_cost.Meter(carried).totals()
    assert t["runs"] == 3 and t["wall_time"] >= 100 and t["cpu_time"] >= 50
    assert t["peak_memory_mb"] == 1e6 and t["load_min"] == 0.0 and t["load_max"] == 1e3
    assert run_cost.Meter().record("interrupted", workers_elsewhere=True)["ended"] == "interrupted"


class _Stop(Exception):
    pass


def test_a_resumed_preparation_counts_the_cpu_of_both_runs(tmp_path):
    threads = engines.threads()
    engines.set_threads(1)
    try:
        path = str(tmp_path / "ck")
        seen = []

        def stop_at_second_checkpoint(label, scene, engine, steps):
            if os.path.exists(path):
                m = os.stat(path).st_mtime_ns
                if m not in seen:
                    seen.append(m)
                    if len(seen) == 2:
                        raise _Stop()
        with pytest.raises(_Stop):
            specimen.prepare_spheres(100, seed=7, checkpoints=prep_checkpoint.Checkpoints(path, {}, 20_000),
                                     progress=stop_at_second_checkpoint)
        before = run_cost.cpu_seconds()
        _, log = specimen.prepare_spheres(100, seed=7, checkpoints=prep_checkpoint.Checkpoints(path, {}, 20_000))
        second = run_cost.cpu_seconds() - before
    finally:
        engines.set_threads(threads)
    assert log["runs"] == 2
    # The first run's CPU up to its second checkpoint (40,000 steps of 100 spheres) is carried.
    assert log["cpu_time"] > second + 0.05
    assert log["peak_memory_mb"] > 10 and log["load_min"] <= log["load_max"]


def test_a_study_records_its_cost_complete_or_interrupted(tmp_path):
    out = str(tmp_path / "study")
    states = study.table_states([1, 2])

    def cut(message):
        if message.startswith("state 2"):
            raise KeyboardInterrupt()
    with pytest.raises(KeyboardInterrupt):
        study.run_states(SPECIMEN, states, out, probes="z", log=cut)
    study.run_states(SPECIMEN, states, out, probes="z", log=lambda m: None)
    meta = json.load(open(os.path.join(out, "metadata.json")))
    assert validate.problem(meta, "study") is None
    assert [r["cost"]["ended"] for r in meta["runs"]] == ["interrupted", "complete"]
    for r in meta["runs"]:
        assert r["cost"]["cpu_time"] > 0 and r["cost"]["peak_memory_mb"] > 10
    # A rerun with nothing to do adds no run, so no cost either.
    study.run_states(SPECIMEN, states, out, probes="z", log=lambda m: None)
    assert len(json.load(open(os.path.join(out, "metadata.json")))["runs"]) == 2


def _blas_threads():
    return {i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"}


def test_threads_hold_blas_to_the_same_count():
    import numpy as np
    np.dot(np.ones((200, 200)), np.ones((200, 200)))  # BLAS loaded
    if not _blas_threads():
        pytest.skip("numpy's BLAS is not one threadpoolctl controls")
    engine = engines.threads()
    original = threadpoolctl.threadpool_info()
    try:
        resources.use_threads(1)
        assert _blas_threads() == {1} and engines.threads() == 1
    finally:
        engines.set_threads(engine)
        threadpoolctl.threadpool_limits(limits={i["prefix"]: i["num_threads"] for i in original})


def test_a_static_solve_repeats_its_bits_at_a_blas_thread_count():
    """use_threads' docstring: the solves' last bits follow BLAS's thread count, and repeat at one."""
    scene, _ = specimen_file.load(os.path.join(REPO, "tests", "data", "spheres-300-s3.npz"))
    got = {}
    for n in (1, 2, 1, 2):
        with threadpoolctl.threadpool_limits(limits=n, user_api="blas"):
            rec = statics.state_record(scene)
        rec = {k: rec[k] for k in ("E_free", "E_blocked", "nu_free", "zeta_h", "zeta_v", "residual")}
        assert got.setdefault(n, rec) == rec


def test_a_static_record_says_what_its_solves_cost(tmp_path):
    scene, meta = specimen_file.load(SPECIMEN)
    rec = statics.cached_record(str(tmp_path), scene=scene, meta=meta, log=lambda m: None)
    assert rec["cost"]["wall_time"] >= 0 and rec["cost"]["peak_memory_mb"] > 10


def test_the_cluster_estimate_puts_the_longest_paths_first():
    assert cost.makespan([5, 4, 3, 3, 2, 1], 2) == 9  # 5+3+1 and 4+3+2
    assert cost.makespan([5, 4, 3], None) == 5
    assert cost.makespan([5, 4, 3], 1) == 12


def test_the_cost_table_of_a_committed_study_is_its_data():
    """The 53,004-sphere study: its paths' times are the sums of its rows' wall times by path,
    grouped here by hand (b, and the side of 100 kPa) from probes.csv and metadata.json."""
    d = os.path.join(REPO, "docs", "data", "spheres-53004-s1")
    c = cost.study_cost(d)
    rows = list(csv.DictReader(open(os.path.join(d, "probes.csv"))))
    states = json.load(open(os.path.join(d, "metadata.json")))["states"]
    by_path, seen = {}, set()
    for r in rows:
        s = states[r["state"]]
        key = (s["b"], 0 if s["sigma_z"] == 100e3 else (1 if s["sigma_z"] > 100e3 else -1))
        t = float(r["probe_wall_time"]) + (0 if r["state"] in seen else float(r["state_wall_time"]))
        seen.add(r["state"])
        by_path[key] = by_path.get(key, 0.0) + t
    assert len(c["paths"]) == len(by_path) == 11
    assert c["paths"] == pytest.approx(sorted(by_path.values(), reverse=True), rel=1e-12)
    assert c["rows_wall"] == pytest.approx(sum(by_path.values()), rel=1e-12)
    assert (c["reach_steps"], c["probe_steps"]) == (sum(int(r["state_steps"]) for r in {x["state"]: x for x in rows}.values()),
                                                   sum(int(r["probe_steps"]) for r in rows))
    text = cost.table([c])
    assert "spheres-53004-s1" in text and "{:,}".format(c["preparation"]["steps"]) in text


def test_a_script_ended_by_sigterm_says_so_first_then_records_its_cost(tmp_path):
    """The exit line comes before the record (cli.after_exit_line), and the record still comes."""
    import signal
    import subprocess
    import sys
    import time
    from conftest import SCRIPTS
    out = tmp_path / "study"
    p = subprocess.Popen([sys.executable, os.path.join(SCRIPTS, "run_states.py"), "--specimen", SPECIMEN, "--table-c1",
                          "--probes", "z", "--threads", "1", "--out", str(out)],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while p.poll() is None and time.time() < deadline and not (out / "probes.csv").exists():
        time.sleep(0.01)
    p.send_signal(signal.SIGTERM)
    _, err = p.communicate(timeout=120)
    assert p.returncode == 143, "the study ended before the signal: %s" % err[-500:]
    assert err.strip().endswith("error: interrupted; the same command " + cli.RESUMES_STUDY)
    assert json.load(open(out / "metadata.json"))["runs"][-1]["cost"]["ended"] == "interrupted"
