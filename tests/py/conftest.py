import json
import os
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "pyscripts"))
# Processes the tests start (python3 -m trueaniso.analysis.report, yade-double scripts) import this
# checkout's package, whichever checkout setup.sh linked for the machine.
os.environ["PYTHONPATH"] = os.pathsep.join([os.path.join(REPO, "pyscripts")]
                                           + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])
# The engines' baseline module (trueaniso/buildarch.py), in this process and every process it
# starts, unless TRUEANISO_LEVEL says otherwise: the committed fixtures and the numbers the tests
# compare with are the baseline's, which every x86-64 processor runs to the same bits, so the suite
# passes or fails alike on a processor with x86-64-v3 and on one without (docs/runs.md, "Across
# machines"). The other levels are tested in processes of their own (test_buildarch.py).
os.environ.setdefault("TRUEANISO_LEVEL", "x86-64")



def assert_page_is_its_data(tmp_path, page, rewrite):
    """A committed page (path under docs/) is what its generator writes from the committed data:
    `rewrite(path)` rewrites a copy of it, which must come out byte for byte the same."""
    committed = os.path.join(REPO, "docs", page)
    doc = tmp_path / os.path.basename(page)
    shutil.copy(committed, doc)
    rewrite(str(doc))
    with open(committed) as f:
        assert doc.read_text() == f.read()

# The files of the most CPU time first (largest first), the others after them in their order:
# pytest-xdist hands whole files to its workers (--dist loadfile) in the order collected, and a long
# file handed out last keeps one worker busy while the other has nothing left to do.
LONGEST_FIRST = ("test_report.py", "test_prep_checkpoint.py", "test_main_job.py", "test_input_checks.py",
                 "test_yade_peer.py", "test_study_reruns.py", "test_manual.py", "test_clumps.py")


def pytest_collection_modifyitems(session, config, items):
    rank = {name: i for i, name in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0].split("/")[-1], len(LONGEST_FIRST)))


def run_yade(script, *args, timeout=600):
    """Run a script under yade-double and return the JSON it wrote (last argument: output path)."""
    if shutil.which("yade-double") is None:
        pytest.fail("yade-double is not installed (the test command installs it with apt-get)")
    return subprocess.run(["yade-double", "-n", "-x", script, *args], capture_output=True, text=True,
                          timeout=timeout)


@pytest.fixture
def yade_json(tmp_path):
    def go(name, *args, timeout=600):
        out = tmp_path / (name + ".json")
        proc = run_yade(os.path.join(HERE, "yade_scripts", name + ".py"), *args, str(out), timeout=timeout)
        if proc.returncode != 0 or not out.exists():
            raise AssertionError("yade-double %s failed:\n%s\n%s" % (name, proc.stdout[-3000:], proc.stderr[-3000:]))
        return json.loads(out.read_text())
    return go


class YadeResults:
    """The JSON of each script of one yade-double run (run_yade_scripts), by name; a script that
    failed fails the test that reads it, with its traceback and the run's output."""

    def __init__(self, outs, proc):
        self.outs, self.proc = outs, proc

    def __getitem__(self, name):
        out = self.outs[name]
        if os.path.exists(out):
            with open(out) as f:
                return json.load(f)
        error = open(out + ".error").read() if os.path.exists(out + ".error") else "(no traceback: it did not end)"
        raise AssertionError("yade-double %s failed (status %d):\n%s\n%s\n%s" % (
            name, self.proc.returncode, error, self.proc.stdout[-3000:], self.proc.stderr[-3000:]))


def run_yade_scripts(directory, jobs, timeout=1800):
    """Several scripts of yade_scripts/ in one yade-double (in_one_yade.py gives each a new scene
    and its own argv): jobs = {name: (script name, arg, ...)}; each writes directory/name.json."""
    if shutil.which("yade-double") is None:
        pytest.fail("yade-double is not installed (the test command installs it with apt-get)")
    outs = {name: str(directory / (name + ".json")) for name in jobs}
    listed = [[os.path.join(HERE, "yade_scripts", script + ".py"), *map(str, args), outs[name]]
              for name, (script, *args) in jobs.items()]
    (directory / "jobs.json").write_text(json.dumps(listed))
    proc = run_yade(os.path.join(HERE, "yade_scripts", "in_one_yade.py"), str(directory / "jobs.json"),
                    timeout=timeout)
    return YadeResults(outs, proc)


SCRIPTS = os.path.join(REPO, "pyscripts")


def script_path(name):
    """pyscripts/<name>, or <repository>/<name> for a benchmark (bench/...)."""
    return os.path.join(REPO if name.startswith("bench" + os.sep) else SCRIPTS, name)


def run_script(name, *args, timeout=600, cwd=None, env=None):
    """Run pyscripts/<name> (or bench/<name>) under /usr/bin/python3 on one engine thread: the tests
    that use it check orchestration, not parallel speed, and two OpenMP threads on a shared 2-core
    machine wait at every barrier (15x slower measured while other jobs ran)."""
    full = dict(os.environ, OMP_NUM_THREADS="1")
    full.update(env or {})
    return subprocess.run([sys.executable, script_path(name), *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd, env=full)


def one_line_error(proc, *words, yade=False):
    """A refusal: exit status 2 and exactly one line 'error: ...' holding every word (under
    yade-double, among YADE's own start-up lines)."""
    lines = proc.stderr.strip().splitlines()
    if yade:
        lines = [x for x in lines if x.startswith("error")]
    ok = proc.returncode == 2 and len(lines) == 1 and lines[0].startswith("error: ")
    ok = ok and all(w in lines[0] for w in words)
    assert ok, "status %d, stderr:\n%s\nstdout tail:\n%s" % (proc.returncode, proc.stderr, proc.stdout[-1500:])
    return lines[0]


@pytest.fixture(scope="session")
def specimen_100(tmp_path_factory):
    """A 100-sphere specimen (seed 3), prepared once for the robustness tests."""
    import fixture_recipes  # one engine thread, as run_script: the same specimen on any machine
    path = tmp_path_factory.mktemp("specimen100") / "s100.npz"
    fixture_recipes.save_spheres(100, 3)(str(path))
    return path


# The eight Table C1 states of the report tests' small table (docs/data/table-c1-spheres-4000.csv).
SMALL_TABLE_STATES = ("1", "5", "9", "13", "21", "25", "29", "37")


@pytest.fixture(scope="module")
def small_table(tmp_path_factory):
    """The committed 4000-sphere Table C1 study cut to SMALL_TABLE_STATES: a report in seconds."""
    import csv
    path = tmp_path_factory.mktemp("report") / "probes.csv"
    with open(os.path.join(REPO, "docs", "data", "table-c1-spheres-4000.csv")) as f:
        rows = list(csv.reader(f))
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(rows[0])
        w.writerows(r for r in rows[1:] if r[0] in SMALL_TABLE_STATES)
    return str(path)


def committed_specimen(name, tmp_path_factory):
    """A copy of tests/data/NAME (tests/data/README.md says how each was made), first loaded
    through specimen_file.load: its checksum and every field are checked."""
    from trueaniso import specimen_file
    path = tmp_path_factory.mktemp(name.replace(".npz", "")) / name
    shutil.copyfile(os.path.join(REPO, "tests", "data", name), path)
    specimen_file.load(str(path))
    return path


@pytest.fixture(scope="session")
def specimen_300(tmp_path_factory):
    """A 300-sphere specimen (prepare_spheres(300, seed=3) on one engine thread), committed: the
    tests of probes, zeta and the YADE peers share it instead of each preparing its own."""
    return committed_specimen("spheres-300-s3.npz", tmp_path_factory)


@pytest.fixture(scope="session")
def specimen_150(tmp_path_factory):
    """A 150-sphere specimen (prepare_spheres(150, seed=4) by the variant grown-to-target, one engine
    thread), committed, for the static solves and the time step's tests: what they check does not
    depend on the recipe (test_specimen prepares its own, spheres-150-s5: the recipe is what it checks)."""
    return committed_specimen("spheres-150-s4.npz", tmp_path_factory)
