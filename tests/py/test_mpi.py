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
from trueaniso import cli

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
    # Whole lines: printed unbuffered under mpiexec, two workers' lines ran together, each followed
    # by an empty one (progress.say writes a line at once).
    assert all(line.strip() for line in proc.stdout.splitlines()), proc.stdout
    assert "warning" not in proc.stdout  # 2 workers x 1 thread: within 2 cores


def test_more_threads_than_cores_is_said_before_work(specimen_100, tmp_path):
    """A study continued under MPI keeps its thread count (a rerun adopts it): 2 workers x 2
    threads on 2 cores is allowed, but said, since teams on shared cores wait at every barrier."""
    cmd = mpi_cmd(specimen_100, tmp_path / "study", ranks=3)
    cmd[cmd.index("--ids") + 1], cmd[cmd.index("--probes") + 1] = "1", "z"
    from trueaniso import resources
    threads = 2 * resources.cores()  # 2 workers x 2 x cores: beyond the cores, within --threads' bound
    proc = subprocess.run(cmd + ["--threads", str(threads)], env=mpi_env(), capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    first = proc.stdout.splitlines()[0]
    assert first.startswith("warning: 2 workers x %d engine threads exceed" % threads), first


def test_more_one_thread_workers_than_cores_is_said_with_advice_that_applies(specimen_100, tmp_path):
    """One-thread workers beyond the cores are not told to use --threads 1, which they do."""
    from trueaniso import resources
    cmd = mpi_cmd(specimen_100, tmp_path / "study", ranks=resources.cores() + 2)
    cmd[cmd.index("--ids") + 1], cmd[cmd.index("--probes") + 1] = "1", "z"
    proc = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    first = proc.stdout.splitlines()[0]
    assert first.startswith("warning: %d workers take turns on this machine's %d cores; %d workers (mpiexec -n %d)"
                            % (resources.cores() + 1, resources.cores(), resources.cores(), resources.cores() + 1)), first
    assert "--threads 1" not in first


def job_tree(pid):
    """mpiexec and every process below it (its ranks sit in process groups of their own)."""
    children = {}
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open("/proc/%s/stat" % entry) as f:
                ppid = int(f.read().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        children.setdefault(ppid, []).append(int(entry))
    tree, todo = [], [pid]
    while todo:
        tree.append(todo.pop())
        todo.extend(children.get(tree[-1], []))
    return tree


def kill_job(p):
    """SIGKILL to mpiexec and its ranks at once; the pids it reached."""
    tree = job_tree(p.pid)
    for pid in tree:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    p.wait(timeout=60)
    return tree


def test_killed_mpi_job_resumes_to_the_same_values(serial, specimen_100, tmp_path):
    """The whole job (mpiexec, master and workers) killed with SIGKILL as soon as a worker has written
    a checkpoint, as a scheduler's time limit or a lost node ends it: no handler runs. SIGKILL, not
    Ctrl-C: mpiexec takes about 1 s to carry out a SIGINT, and the 100-sphere study ends about 1 s
    after its first checkpoint, so a Ctrl-C often interrupts nothing; SIGKILL acts at once."""
    out = tmp_path / "study"
    p = subprocess.Popen(mpi_cmd(specimen_100, out, ranks=3), env=mpi_env(), stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.time() + 300
    while p.poll() is None and time.time() < deadline:
        if (out / "states").is_dir() and any(n.endswith(".npz") for n in os.listdir(out / "states")):
            break
        time.sleep(0.01)
    tree = kill_job(p)
    assert len(tree) >= 4, "mpiexec and its 3 ranks were running: %s" % tree
    done = len(values(out)) if (out / "probes.csv").exists() else 0
    assert done < 8 and any(n.endswith(".npz") for n in os.listdir(out / "states")), "a checkpoint, not every row"
    proc = subprocess.run(mpi_cmd(specimen_100, out), env=mpi_env(), capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert values(out) == values(serial)


def test_ctrl_c_on_mpiexec_says_the_job_resumes(specimen_100, tmp_path):
    """Ctrl-C on mpiexec: mpiexec sends its ranks SIGTERM, which ended the master with no word
    (exit 1, nothing on stderr) before cli.guarded turned SIGTERM into the resume line; the workers
    must stay silent (cli.release_start_guard). Thirteen
    states, so that the job is still running when mpiexec acts, about 1 s after the signal."""
    out = tmp_path / "study"
    cmd = mpi_cmd(specimen_100, out, ranks=3)
    cmd[cmd.index("--ids") + 1] = ",".join(str(i) for i in range(1, 14))
    p = subprocess.Popen(cmd, env=mpi_env(), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 300
    while p.poll() is None and time.time() < deadline:
        if (out / "states").is_dir() and any(n.endswith(".npz") for n in os.listdir(out / "states")):
            break
        time.sleep(0.01)
    p.send_signal(signal.SIGINT)
    _, err = p.communicate(timeout=120)
    assert p.returncode != 0, "the job ended before the signal: give it more states"
    # values() holds a row per state and probe (z and x here): count the states. Comparing its rows
    # with the 13 states would fail when 7 states are done before mpiexec acts.
    done = {state for state, _ in values(out)} if (out / "probes.csv").exists() else set()
    assert len(done) < 13, "every state was done: the signal interrupted nothing"
    assert "error: interrupted; the same command " + cli.RESUMES_STUDY in err, err[-3000:]
    # The workers load the script without running it: its start-up guard must not make each of them
    # say 'interrupted while starting; nothing was done' beside the master's line.
    assert "nothing was done" not in err, err[-3000:]


def test_mpi_without_workers_is_refused(specimen_100, tmp_path):
    proc = run_script("run_states.py", "--mpi", "--specimen", str(specimen_100), "--out", str(tmp_path / "x"),
                      "--ids", "1")
    one_line_error(proc, "--mpi", "mpiexec -n K")
    assert not (tmp_path / "x").exists()


def test_mpiexec_without_mpi4py_futures_is_refused(specimen_100, tmp_path):
    """`mpiexec -n 2 python3 run_states.py --mpi` (no `-m mpi4py.futures`) ran the script on both
    ranks, each a master with its own pool: both wrote the study and left a metadata.json. Now rank
    0 says how to start it, once, and nothing is written."""
    cmd = mpi_cmd(specimen_100, tmp_path / "x")
    del cmd[cmd.index("-m"):cmd.index("-m") + 2]
    proc = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0
    assert proc.stderr.count("without mpi4py.futures") == 1, proc.stderr
    assert "-m mpi4py.futures pyscripts/run_states.py --mpi" in proc.stderr
    assert not (tmp_path / "x").exists()


def test_mpiexec_without_mpi_option_is_refused(specimen_100, tmp_path):
    """`mpiexec -n 2 python3 run_states.py` without --mpi ran one study per rank in the same --out:
    one held the lock, the other refused, and mpiexec killed the first mid-state. Now refused once."""
    cmd = mpi_cmd(specimen_100, tmp_path / "x")
    del cmd[cmd.index("-m"):cmd.index("-m") + 2]
    cmd.remove("--mpi")
    proc = subprocess.run(cmd, env=mpi_env(), capture_output=True, text=True, timeout=300)
    assert proc.returncode != 0
    assert proc.stderr.count("mpiexec started this script on 2 ranks without --mpi") == 1, proc.stderr
    assert not (tmp_path / "x").exists()
