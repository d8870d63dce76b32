"""Progress lines for long work: steps, stress error and unbalanced force, every few seconds.

One plain line at a time (no carriage returns, no bar), flushed: it reads the same on a terminal
and in a log file (./main.sh's output, a yade-batch job's log). The interval is wall-clock time,
so a line costs nothing measurable whatever the size of the scene. States and probes are stepped
in chunks sized so that a chunk takes well under the interval (``chunk_for``); their chunk size
changes no result (the servo and the probe end a chunk at the step they are done). The specimen
preparation keeps its fixed 2,000-step chunks, which are part of its recipe (its servos run to the
end of a chunk), so on very large specimens its lines come once per chunk.
"""
import sys
import time

import numpy as np

EVERY = 5.0  # seconds between lines: "about every few seconds"


def say(message):
    """`message` and its newline to stdout in one write, flushed: the log of every script. Under
    mpiexec, Python's output is unbuffered (PYTHONUNBUFFERED=1), so print() writes the text and the
    newline apart, and lines of two workers can run together on one line, with an empty one after
    (59 of 4000 lines of two ranks). One write of a line stays whole."""
    sys.stdout.write(message + "\n")
    sys.stdout.flush()


def chunk_for(num_bodies, steps_per_body=2_000_000, smallest=100, largest=5000):
    """Steps per chunk: ~2e6 body-steps (about 1 s at 0.75 us per body-step on one thread)."""
    return int(min(largest, max(smallest, steps_per_body // max(1, num_bodies))))


class Progress:
    """``line(steps, stress_error, unbalanced)`` prints when `every` seconds have passed since the
    last line (every call when every = 0)."""

    def __init__(self, label, log=print, every=EVERY):
        self.label, self.log, self.every = label, log, float(every)
        self.t0 = self.last = time.monotonic()

    def due(self):
        return time.monotonic() - self.last >= self.every

    def line(self, steps, stress_error, unbalanced, extra=""):
        from . import cli
        cli.raise_pending()  # after every chunk: a Ctrl-C that a finalizer swallowed ends the run here
        if not self.due():
            return
        self.last = time.monotonic()
        # The unbalanced force is a ratio to the mean contact force: undefined before any contact.
        ub = "%.2e" % unbalanced if np.isfinite(unbalanced) else "n/a (no contact yet)"
        self.log("%s: step %d  stress error %.3g Pa  unbalanced %s%s  (%.0f s)"
                 % (self.label, steps, stress_error, ub, extra, self.last - self.t0))

    # Callbacks for the protocols' progress hooks.
    def servo(self, servo):
        """For triaxial.reach_state(progress=...): the servo's own error against the state (its
        principal and shear stresses, engines/control/StressGap.hpp) and the largest shear stress."""
        self.line(int(servo.steps), float(servo.stress_error), float(servo.unbalanced),
                  "  |shear| %.3g Pa  [%s]" % (float(servo.max_shear), servo.status))

    def probe(self, probe):
        """For triaxial.probe(progress=...): error against the probe's current goal."""
        err = float(np.max(np.abs(np.asarray(probe.stress) - np.asarray(probe.target))))
        self.line(int(probe.steps), err, float(probe.unbalanced), "  [%s]" % probe.stage)

    def preparation(self, label, scene, engine, steps):
        """For specimen.prepare_spheres(progress=...)."""
        from . import engines
        sig = np.diag(engines.stress(scene))
        target = getattr(engine, "target_pressure", None)
        # Radius expansion servoes the mean stress; the consolidation servo every principal and
        # shear stress (its own error, engines/control/StressGap.hpp).
        err = abs(sig.mean() - target) if target is not None else engine.stress_error
        self.line(steps, float(err), float(engine.unbalanced), "  [%s]" % label)
