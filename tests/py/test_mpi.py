"""A study's loading paths on MPI workers (run_states.py --mpi under mpiexec and mpi4py.futures):
the same values as a serial run, an interrupted MPI run resumed to the same values, and a clear
refusal without workers. 100 spheres, states 1, 2, 3 (3 is reached from 2) and 21 (three paths)."""
import csv
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest
from conftest import SCRIPTS, one_line_error, run_script

WALL = {"probe_wall_time", "state_wall_time"}
IDS = "1,2,3,21"
pytestmark = pytest.mark.skipif(shutil.which("mpiexec") is None, reason="needs openmpi-bin (setup.sh installs it)")


def values(out):
    """{(state, probe): row without wall times}: MPI appends rows in the order paths end."""
    with open(os.path.join(out, "probes.csv"), newline="") as f:
        return {(r["state"], r["probe"]): {k: v for k, v in r.items() if k not in WALL} for r in csv.DictReader(f)}


def mpi_cmd(spec, out, ranks=2):
    return ["mpiexec", "-n", str(ranks), sys.executable, "-m", "mpi4py.futures",
            os.path.join(SCRIPTS, "run_states.py"), "--mpi", "--specimen", str(spec), "--out", str(out),
            "--ids", IDS, "--probes", "zx"]


def mpi_env():
    # root in containers and CI; more ranks than cores (the master mostly waits)
    return dict(os.environ, OMP_NUM_THREADS="1", OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
                OMPI_MCA_rmaps_base_oversubscribe="1")


@pytest.fixture(scope="module")
def serial(specimen_100, tmp_path_factory):
    out = tmp_path_factory.mktemp("serial") / "study"
    proc = run_script("run_states.py", "--specimen", str(specimen_100), "--out", str(out), "--ids", IDS,
                      "--probes", "zx", "--threads", "1")
    assert proc.returncode == 0, proc.stderr
    return out


def test_mpi_run_equals_the_serial_run(serial, specimen_100, tmp_path):
    out = tmp_path / "study"
    proc = subprocess.run(mpi_cmd(specimen_100, out), env=mpi_env(), capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "3 loading paths with work left, on MPIPoolExecutor" in proc.stdout
    assert values(out) == values(serial) and len(values(out)) == 8


def test_interrupted_mpi_run_resumes_to_the_same_values(serial, specimen_100, tmp_path):
    # The 100-sphere study is short: on an idle machine its last paths can end while Ctrl-C travels
    # through mpiexec (it did once in CI). Such an attempt interrupted nothing and is tried again in
    # a fresh directory; a run that really was interrupted is required.
    for attempt in range(4):
        out = tmp_path / ("study-%d" % attempt)
        p = subprocess.Popen(mpi_cmd(specimen_100, out, ranks=3), env=mpi_env(), stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL, start_new_session=True)
        deadline = time.time() + 300
        while p.poll() is None and time.time() < deadline:  # interrupt once a worker has written a checkpoint
            if (out / "states").is_dir() and any(n.endswith(".npz") for n in os.listdir(out / "states")):
                break
            time.sleep(0.02)
        os.killpg(p.pid, signal.SIGINT)  # Ctrl-C on mpiexec: it stops every rank
        p.wait(timeout=120)
        done = len(values(out)) if (out / "probes.csv").exists() else 0
        if done < 8:
            break
    assert done < 8, "the run ended before it could be interrupted, %d times" % (attempt + 1)
    proc = subprocess.run(mpi_cmd(specimen_100, out), env=mpi_env(), capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert values(out) == values(serial)


def test_mpi_without_workers_is_refused(specimen_100, tmp_path):
    proc = run_script("run_states.py", "--mpi", "--specimen", str(specimen_100), "--out", str(tmp_path / "x"),
                      "--ids", "1")
    one_line_error(proc, "--mpi", "mpiexec -n K")
    assert not (tmp_path / "x").exists()
