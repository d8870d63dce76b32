"""Ctrl-C (SIGINT) and a kill (SIGTERM) in the middle of every entry point of the product: the
scripts and the analysis tools (python3 -m trueaniso.analysis.X). Each ends with one line
'error: interrupted...' and the signal's status (130, 143), never a traceback, and never runs on
as if nothing had happened.

The signal is a real one, sent by the process to itself once it opens a given file (an audit hook
in a sitecustomize of the test's own, optionally after a delay): at a known point of the work, on
a machine of any speed. Each process starts with SIGINT's default disposition restored: a job
started from a background shell inherits SIGINT ignored, under which Python installs no handler of
its own and a tool without one finishes as if no key had been pressed, which hid the traceback.
"""
import os
import shutil
import signal
import subprocess
import sys

import pytest
from conftest import REPO, SCRIPTS

DATA = os.path.join(REPO, "docs", "data")

HOOK = '''
import os, signal, sys, threading
_on = os.environ.get("TRUEANISO_TEST_INTERRUPT_ON")
if _on:
    _signal = getattr(signal, os.environ["TRUEANISO_TEST_INTERRUPT_SIGNAL"])
    _after = float(os.environ.get("TRUEANISO_TEST_INTERRUPT_AFTER", "0"))
    _event = os.environ.get("TRUEANISO_TEST_INTERRUPT_EVENT", "open")
    _fired = []

    def _send():
        os.kill(os.getpid(), _signal)

    def _hook(event, args):
        if event == _event and not _fired and args and isinstance(args[0], str) and _on in args[0]:
            _fired.append(True)
            if _after:
                t = threading.Timer(_after, _send)
                t.daemon = True
                t.start()
            else:
                _send()
    sys.addaudithook(_hook)
'''


def _default_sigint():
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _run(tmp_path, args, on, sig, after=0.0, event="open"):
    hook = tmp_path / "hook"
    hook.mkdir(exist_ok=True)
    (hook / "sitecustomize.py").write_text(HOOK)
    env = dict(os.environ, OMP_NUM_THREADS="1", TRUEANISO_TEST_INTERRUPT_ON=on, TRUEANISO_TEST_INTERRUPT_SIGNAL=sig,
               TRUEANISO_TEST_INTERRUPT_AFTER=str(after), TRUEANISO_TEST_INTERRUPT_EVENT=event,
               PYTHONPATH=os.pathsep.join([str(hook), SCRIPTS]))
    return subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True, cwd=tmp_path, env=env,
                          timeout=600, preexec_fn=_default_sigint)


def _interrupted(proc, sig, *words):
    status = 128 + getattr(signal, sig)
    errors = [x for x in proc.stderr.splitlines() if x.startswith("error")]
    ok = proc.returncode == status and "Traceback" not in proc.stdout + proc.stderr and len(errors) == 1
    ok = ok and errors[0].startswith("error: interrupted") and all(w in errors[0] for w in words)
    assert ok, "status %d (want %d)\nstderr:\n%s\nstdout tail:\n%s" % (proc.returncode, status, proc.stderr[-3000:],
                                                                      proc.stdout[-1500:])
    return errors[0]


SPHERES = os.path.join(DATA, "spheres-4000-s1")
FIG16 = os.path.join(DATA, "fig16-spheres-4000-s1")
TOOLS = {
    "report": (["-m", "trueaniso.analysis.report", SPHERES, "--out", "rep"], "probes.csv"),
    "figures": (["-m", "trueaniso.analysis.figures", os.path.join(SPHERES, "probes.csv"), "--out", "figs"], "probes.csv"),
    "zeta_contrast": (["-m", "trueaniso.analysis.zeta_contrast", SPHERES], "probes.csv"),
    "cross_anisotropy": (["-m", "trueaniso.analysis.cross_anisotropy", os.path.join(FIG16, "probes.csv")], "probes.csv"),
    "path_fidelity": (["-m", "trueaniso.analysis.path_fidelity", os.path.join(SPHERES, "probes.csv")], "probes.csv"),
}


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
@pytest.mark.parametrize("name", sorted(TOOLS))
def test_an_analysis_tool_interrupted_mid_work_is_one_line(tmp_path, name, sig):
    """analysis.report ended in a KeyboardInterrupt traceback of 47-377 lines, 8 times in 8."""
    args, on = TOOLS[name]
    proc = _run(tmp_path, args, on, sig)
    _interrupted(proc, sig)
    assert not (tmp_path / "rep" / "report.md").exists()


@pytest.mark.parametrize("name", sorted(TOOLS))
def test_an_analysis_tool_interrupted_while_starting_is_one_line(tmp_path, name):
    """The first second of `python3 -m trueaniso.analysis.X`, while Python imports the package and
    numpy (the signal sent as the tool imports trueaniso.analysis.results): the start guard the package
    installs when run as a tool."""
    proc = _run(tmp_path, TOOLS[name][0], "trueaniso.analysis.results", "SIGINT", event="import")
    assert proc.returncode == 130 and proc.stderr == "error: interrupted while starting; nothing was done\n", \
        (proc.returncode, proc.stderr)


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_prepare_specimen_interrupted_mid_work(tmp_path, sig):
    """A second into the preparation (after its lock is taken): the one line says how to go on."""
    proc = _run(tmp_path, [os.path.join(SCRIPTS, "prepare_specimen.py"), "--n", 100, "--seed", 3, "--out", "s.npz"],
                ".s.npz.lock", sig, after=1.0)
    _interrupted(proc, sig, "the same command")
    assert not (tmp_path / "s.npz").exists()


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_run_states_interrupted_mid_work(tmp_path, specimen_100, sig):
    """When the probes of state 1 open its checkpoint: mid-work however fast the machine (a timer
    after the lock missed a run that ended within its second)."""
    proc = _run(tmp_path, [os.path.join(SCRIPTS, "run_states.py"), "--specimen", specimen_100, "--ids", "1,5",
                           "--out", "study"], os.path.join("states", "1.npz"), sig)
    _interrupted(proc, sig, "the same command")


@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM"])
def test_run_study_interrupted_mid_work(tmp_path, sig):
    proc = _run(tmp_path, [os.path.join(SCRIPTS, "run_study.py"), "--n", 100, "--seed", 3, "--ids", "1",
                           "--out", "study"], ".lock", sig, after=1.0)
    _interrupted(proc, sig, "the same command")


def test_the_hook_fires(tmp_path):
    """The control: without the trigger the tool runs to its end (the hook alone changes nothing)."""
    shutil.copy(os.path.join(FIG16, "probes.csv"), tmp_path / "t.csv")
    proc = _run(tmp_path, ["-m", "trueaniso.analysis.cross_anisotropy", tmp_path / "t.csv"], "no-such-file", "SIGINT")
    assert proc.returncode == 0 and "G_vh" in proc.stdout, proc.stderr
