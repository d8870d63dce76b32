"""What the time step rule changes in a stress probe: E_i and nu_ij under each rule, against each other and the exact static solve.

    /usr/bin/python3 bench/bench_time_step_probes.py --specimen spheres=S.npz [--specimen clump1=C.npz] \
        [--ids 1,21,39] [--rules smallest-inertia,per-axis] [--doc docs/studies/time-step.md]

Each state of Table C1 asked for is reached from the specimen under the reference rule
(smallest-inertia) and saved, so that every probe starts from the same bytes, as a study's probes
start from the state's checkpoint. The state is then probed on z, x and y (the default probe,
triaxial.probe) once per time step rule; its exact static moduli (statics.static_stiffness,
rotations free) are what a quasi-static probe converges to. The gain and the step counts of the
probe are per step of the reference rule (scene.reference_dt), so a rule with a longer step probes
over the same time in fewer steps. The table gives each rule's steps, the change of E_i and nu_ij
from the first rule, and each rule's largest error against the static solve, beside the default
probe's own error (6.0e-4 in E, 1.1e-4 in nu).
"""
import os
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

PROBE_ERROR_E, PROBE_ERROR_NU = 6.0e-4, 1.1e-4  # docs/speed-vs-error.md, default probe
AXES = ("z", "x", "y")


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", action="append", required=True, help="LABEL=specimen file (.npz), repeatable")
    p.add_argument("--ids", default="1,21,39", help="Table C1 states by number (1: the isotropic state)")
    p.add_argument("--rules", default="smallest-inertia,per-axis", help="time step rules, the first is the reference")
    p.add_argument("--doc", help="Markdown file whose table between <!-- BLOCK:begin/end --> is replaced")
    p.add_argument("--block", default="time-step-probes", help="the block of --doc (default time-step-probes)")
    o = cli.parse(p)
    o.rules = _bench.time_step_rules(o.rules)
    specs = []
    for s in o.specimen:
        label, _, path = s.rpartition("=")
        if not os.path.isfile(path):
            cli.fail("--specimen %s: no such file" % path)
        specs.append((label or os.path.basename(path), path))
    o.specimen = specs
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def held_state(path, b, sz, where):
    """The state reached from the specimen under the reference rule, saved to `where`."""
    from trueaniso import dem, specimen, specimen_file, triaxial
    scene, meta = specimen_file.load(path)
    triaxial.reach_state(scene, b, sz, time_step=dem.REFERENCE_TIME_STEP)
    specimen_file.save(where, scene, seed=meta.get("seed"), parameters=dict(meta.get("parameters") or {}),
                       summary=specimen.state(scene))
    return scene


def probes(where, hold, rule):
    from trueaniso import specimen_file, triaxial
    out = {}
    for axis in AXES:
        scene, _ = specimen_file.load(where)  # every probe from the state's bytes, as a study's
        out[axis] = triaxial.probe(scene, hold, axis, time_step=rule)
    return out


def nus(r):
    return [v for k, v in sorted(r.items()) if k.startswith("nu_")]


def main():
    o = options()
    from trueaniso import statics, study, triaxial
    states = study.table_states(study.parse_ids(o.ids))
    lines = ["%s OpenMP thread(s), %s; each state reached from its specimen under %s, every probe from its saved "
             "bytes. Per state: the steps of the three probes (z, x, y), the largest change of E_i (relative) and "
             "nu_ij from %s, and each rule's largest error against the exact static solve. Machine: %s, shared with "
             "other jobs." % (os.environ.get("OMP_NUM_THREADS", "all"), time.strftime("%Y-%m-%d"), o.rules[0],
                              o.rules[0], _bench.machine()), "",
             "| specimen | state | b | sigma_z (kPa) | rule | probe steps | max abs dE/E | max abs dnu | "
             "E error vs static | nu error vs static |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    totals = {r: 0 for r in o.rules}
    worst = {r: [0.0, 0.0] for r in o.rules}
    errors = {r: [0.0, 0.0] for r in o.rules}
    with tempfile.TemporaryDirectory() as tmp:
        for label, path in o.specimen:
            for sid, b, sz in states:
                where = os.path.join(tmp, "%s-%s.npz" % (label, sid))
                scene = held_state(path, b, sz, where)
                exact = statics.static_stiffness(scene, rotations=True)
                hold = triaxial.path_stresses("true-triaxial", b, sz)
                res = {r: probes(where, hold, r) for r in o.rules}
                ref = res[o.rules[0]]
                for r in o.rules:
                    x = res[r]
                    steps = sum(x[a]["steps"] for a in AXES)
                    totals[r] += steps
                    dE = max(abs(x[a]["E"] / ref[a]["E"] - 1) for a in AXES)
                    dnu = max(abs(u - v) for a in AXES for u, v in zip(nus(x[a]), nus(ref[a])))
                    i_of = {"x": 0, "y": 1, "z": 2}
                    eE = max(abs(x[a]["E"] / exact["E"][i_of[a]] - 1) for a in AXES)
                    enu = max(abs(x[a]["nu_%s%s" % (a, c)] - exact["nu"][i_of[a]][i_of[c]])
                              for a in AXES for c in "xyz" if c != a)
                    errors[r] = [max(errors[r][0], eE), max(errors[r][1], enu)]
                    if r != o.rules[0]:
                        worst[r] = [max(worst[r][0], dE), max(worst[r][1], dnu)]
                    lines.append("| %s | %s | %.2f | %.0f | %s | %d | %s | %s | %.1e | %.1e |" % (
                        label, sid, b, sz / 1e3, r, steps,
                        *(("-", "-") if r == o.rules[0] else ("%.1e" % dE, "%.1e" % dnu)), eE, enu))
                    print(lines[-1], flush=True)
    lines.append("")
    for r in o.rules[1:]:
        lines.append("%s against %s: %d -> %d probe steps (%.2fx fewer); max abs dE/E %.1e, max abs dnu %.1e; largest "
                     "error against the static solve %.1e in E, %.1e in nu (%s: %.1e, %.1e); the default probe's own "
                     "error: %.1e, %.1e." % (
                         r, o.rules[0], totals[o.rules[0]], totals[r], totals[o.rules[0]] / max(totals[r], 1),
                         worst[r][0], worst[r][1], errors[r][0], errors[r][1], o.rules[0], errors[o.rules[0]][0],
                         errors[o.rules[0]][1], PROBE_ERROR_E, PROBE_ERROR_NU))
    _bench.publish(o.doc, o.block, lines)


if __name__ == "__main__":
    cli.guarded(main)
