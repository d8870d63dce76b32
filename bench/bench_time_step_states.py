"""Steps to reach a state under each time step rule, and what the rule changes in the state reached.

    /usr/bin/python3 bench/bench_time_step_states.py --specimen S.npz [--ids 1,21,39] \
        [--rules smallest-inertia,per-axis] [--doc docs/studies/time-step.md]

Every state of Table C1 asked for is reached from the specimen itself once per time step rule
(dem.TIME_STEP_RULES; docs/time-step.md), with everything else at the study's defaults. The path
rate, the servo's gain and the hold and stall counts are per step of the reference rule
(scene.reference_dt), so a rule with a longer step loads at the same rate in time, in fewer steps.
At each reached state: the steps, the mean time step, Zm and E_i, nu_ij of the exact static solve
(rotations free); the table gives the differences of each rule from the first, beside the default
probe's own error (6.0e-4 in E, 1.1e-4 in nu).
"""
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

PROBE_ERROR_E, PROBE_ERROR_NU = 6.0e-4, 1.1e-4  # docs/speed-vs-error.md, default probe


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz)")
    p.add_argument("--ids", default="1,10,21,30,39", help="Table C1 states by number")
    p.add_argument("--rules", default="smallest-inertia,per-axis", help="time step rules, the first is the reference")
    p.add_argument("--doc", help="Markdown file whose table between <!-- BLOCK:begin/end --> is replaced")
    p.add_argument("--block", default="time-step-states", help="the block of --doc (default time-step-states)")
    o = cli.parse(p)
    o.rules = _bench.time_step_rules(o.rules)
    if not os.path.isfile(o.specimen):
        cli.fail("--specimen %s: no such file" % o.specimen)
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def measure(path, b, sz, rule):
    from trueaniso import fabric, specimen_file, statics, triaxial
    scene, _ = specimen_file.load(path)
    t0 = scene.time
    info = triaxial.reach_state(scene, b, sz, time_step=rule)
    res = statics.static_stiffness(scene, rotations=True)
    nu = res["nu"]
    return dict(steps=info["steps"], wall=info["wall_time"], dt=(scene.time - t0) / max(info["steps"], 1),
                Zm=fabric.fabric(scene)["Zm"], E=list(res["E"]),
                nu=[nu[i][j] for i in range(3) for j in range(3) if i != j])


def main():
    o = options()
    from trueaniso import specimen_file, study
    states = study.table_states(study.parse_ids(o.ids))
    n = specimen_file.load(o.specimen)[0].num_bodies
    lines = ["Specimen %s (%d particles), %s OpenMP thread(s), %s; each state from the specimen, moduli from the "
             "static solve. Machine: %s, shared with other jobs." % (
                 os.path.basename(o.specimen), n, os.environ.get("OMP_NUM_THREADS", "all"), time.strftime("%Y-%m-%d"),
                 _bench.machine()), "",
             "| state | b | sigma_z (kPa) | rule | steps | mean dt (s) | s | abs dZm | max abs dE/E | max abs dnu |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    totals = {r: [0, 0.0] for r in o.rules}
    worst = {r: [0.0, 0.0] for r in o.rules[1:]}
    for sid, b, sz in states:
        res = {r: measure(o.specimen, b, sz, r) for r in o.rules}
        ref = res[o.rules[0]]
        for r in o.rules:
            x = res[r]
            totals[r][0] += x["steps"]
            totals[r][1] += x["wall"]
            dZ = abs(x["Zm"] - ref["Zm"])
            dE = max(abs(a / c - 1) for a, c in zip(x["E"], ref["E"]))
            dnu = max(abs(a - c) for a, c in zip(x["nu"], ref["nu"]))
            if r != o.rules[0]:
                worst[r] = [max(worst[r][0], dE), max(worst[r][1], dnu)]
            lines.append("| %s | %.2f | %.0f | %s | %d | %.3g | %.1f | %s | %s | %s |" % (
                sid, b, sz / 1e3, r, x["steps"], x["dt"], x["wall"],
                *(("-", "-", "-") if r == o.rules[0] else ("%.4f" % dZ, "%.1e" % dE, "%.1e" % dnu))))
            print(lines[-1], flush=True)
    lines.append("")
    for r in o.rules[1:]:
        lines.append("%s against %s: %d -> %d steps (%.2fx fewer), %.0f -> %.0f s; max abs dE/E %.1e, max abs dnu %.1e "
                     "(the default probe's own error: %.1e, %.1e)." % (
                         r, o.rules[0], totals[o.rules[0]][0], totals[r][0], totals[o.rules[0]][0] / max(totals[r][0], 1),
                         totals[o.rules[0]][1], totals[r][1], worst[r][0], worst[r][1], PROBE_ERROR_E, PROBE_ERROR_NU))
    _bench.publish(o.doc, o.block, lines)


if __name__ == "__main__":
    cli.guarded(main)
