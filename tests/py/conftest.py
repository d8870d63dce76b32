import json
import os
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "pyscripts"))
sys.path.insert(0, REPO)


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


SCRIPTS = os.path.join(REPO, "pyscripts")


def run_script(name, *args, timeout=600, cwd=None, env=None):
    """Run pyscripts/<name> under /usr/bin/python3 on one engine thread: the tests that use it
    check orchestration, not parallel speed, and two OpenMP threads on a shared 2-core machine
    wait at every barrier (15x slower measured while other jobs ran)."""
    full = dict(os.environ, OMP_NUM_THREADS="1")
    full.update(env or {})
    return subprocess.run([sys.executable, os.path.join(SCRIPTS, name), *map(str, args)], capture_output=True,
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
    from trueaniso import engines, specimen, specimen_file
    threads = engines.threads()
    engines.set_threads(1)  # as run_script: the same specimen on any machine
    try:
        scene, log = specimen.prepare_spheres(100, seed=3)
    finally:
        engines.set_threads(threads)
    path = tmp_path_factory.mktemp("specimen100") / "s100.npz"
    specimen_file.save(str(path), scene, seed=3, parameters=log, summary=specimen.state(scene))
    return path


def pytest_configure(config):
    # Tests that take more than about 20 s (./test.sh --long runs them). Registered here because
    # this tree has no pytest.ini; the one place to move it to when there is one.
    config.addinivalue_line("markers", "long: a test that takes more than about 20 s")
