"""Where a state's steps go: the servo's ramp (and its stalls) against its hold, for servo gains.

    /usr/bin/python3 bench/bench_state_split.py --specimen S.npz [--ids 2,6,10] [--gains 0.01,0.03] \
        [--feed-forward off,on]

Every state is reached from the specimen itself, once per gain, with the study's servo settings
otherwise (triaxial.reach_state's defaults: 2 Pa per step, damping 0.4, inertial number 1e-3, one
engine thread). The ramp is the steps until the servo's goal reaches the state (its progress
reaches 1), "stalled" the ramp's steps in which the goal did not move (a stress more than the
follow tolerance behind it; "waited" is the servo's own exact count of them); the hold is the
rest, until every stress is within 100 Pa and the unbalanced force below 1e-4 for 200 steps.
While loading, looked at every chunk: the largest lag of a stress behind the goal (max_lag) and
the largest distance of the normal stresses from the straight path (off_path), in Pa.
--feed-forward off,on runs each gain with the servo's feed-forward off and on (docs/triaxial.md).
One JSON line per state, gain and setting (docs/studies/paper-size.md, "Where clump2's steps to a state go").
"""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz)")
    p.add_argument("--ids", default="2,6,10,14,18,22", help="Table C1 states by number")
    p.add_argument("--gains", default="0.01,0.03", help="servo gains (fraction of the stress error closed a step)")
    p.add_argument("--feed-forward", default="off", help="servo feed-forward settings: off, on, or off,on")
    p.add_argument("--chunk", type=cli.at_least(1), default=500,
                   help="steps between looks at the servo: the ramp's end and its stalls are counted to this "
                        "many steps (the state's total is exact)")
    o = cli.parse(p)
    try:
        o.gains = [float(g) for g in o.gains.split(",")]
        o.ids = [int(i) for i in o.ids.split(",")]
    except ValueError:
        cli.fail("--gains and --ids take numbers separated by commas")
    # Every value checked before the first state runs (a bad second gain failed after the first's work).
    bad = [g for g in o.gains if not 0 < g <= 1]  # the servo's range (CellServoLaw); nan fails too
    if bad:
        cli.fail("--gains: %s not in (0, 1] (the fraction of the stress error closed a step)" % bad[0])
    if len(set(o.ids)) != len(o.ids) or len(set(o.gains)) != len(o.gains):
        cli.fail("--ids and --gains name each value once")
    o.feed_forward = o.feed_forward.split(",")
    if any(f not in ("off", "on") for f in o.feed_forward) or len(set(o.feed_forward)) != len(o.feed_forward):
        cli.fail("--feed-forward: off, on, or both separated by a comma")
    return o


def split(specimen_path, b, sigma_z, gain, chunk, feed_forward=False):
    """The state reached as a study reaches it (triaxial.reach_state), its servo watched every chunk."""
    import numpy as np
    from trueaniso import engines, specimen_file, triaxial
    s, _ = specimen_file.load(specimen_path)
    seen = dict(ramp=None, stalled=0, last=-1.0, lag=0.0, off_path=0.0)
    start = np.diag(engines.stress(s)).copy()
    line = engines.true_triaxial_stresses(b, sigma_z) - start
    line /= max(np.linalg.norm(line), 1e-300)

    def watch(servo):
        if servo.status == "loading":  # the normal stresses' distance from the straight path, and the lag
            x = np.asarray(servo.stress[:3]) - start
            seen["off_path"] = max(seen["off_path"], float(np.linalg.norm(x - x.dot(line) * line)))
            seen["lag"] = max(seen["lag"], float(servo.lag))
        if seen["ramp"] is None and servo.progress >= 1.0:
            seen["ramp"] = servo.steps
        elif seen["ramp"] is None:
            seen["stalled"] += chunk if servo.progress == seen["last"] else 0
            seen["last"] = servo.progress
    t0 = time.time()
    try:
        info = triaxial.reach_state(s, b, sigma_z, gain=gain, chunk=chunk, progress=watch, feed_forward=feed_forward)
    except triaxial.StateNotReached as exc:
        return dict(status="failed", message=str(exc), seconds=round(time.time() - t0, 1))
    return dict(status=info["status"], steps=info["steps"], ramp=seen["ramp"], ramp_stalled=seen["stalled"],
                waited=info["waited_steps"], overshoot=max(info["overshoot"]), max_lag=seen["lag"],
                off_path=seen["off_path"],
                hold=info["steps"] - (seen["ramp"] or 0), seconds=round(time.time() - t0, 1))


def main():
    o = options()
    from trueaniso import engines, triaxial
    engines.set_threads(1)
    states = {i: (b, sz) for i, b, sz in triaxial.table_c1_states()}
    for i in o.ids:
        if i not in states:
            cli.fail("--ids: no Table C1 state %d" % i)
    for i in o.ids:
        for g in o.gains:
            for f in o.feed_forward:
                print(json.dumps(dict(state=i, gain=g, feed_forward=f,
                                      **split(o.specimen, *states[i], g, o.chunk, f == "on"))), flush=True)


if __name__ == "__main__":
    cli.guarded(main)
