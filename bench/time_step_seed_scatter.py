"""What the per-axis time step changes in the states reached, against what another seed changes.

    /usr/bin/python3 bench/time_step_seed_scatter.py --specimens s1.npz,s2.npz,s3.npz \
        [--ids 1,5,9,21,39] [--json out.json] [--doc docs/studies/time-step.md --block B]

Each specimen (one seed each, the same recipe) is taken to every state asked for, from the
specimen itself, once under the reference rule (smallest-inertia) and once under per-axis, as
bench_time_step_states.py does. At each reached state: e, Zm, the rattlers, the fabric tensors R
and H (Eq. 15-16, as fractions of their trace), E_i and nu_ij of the exact static solve (rotations
free) and E_z/E_x. The table gives, per quantity, the largest change the rule makes at a state
(over the seeds) beside the scatter between the seeds at that state under the reference rule (their
sample standard deviation): the rule changes "the same physics" no more than another seed does
when the first is well below the second.
"""
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

RULES = ("smallest-inertia", "per-axis")


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimens", required=True, help="specimen files (.npz), comma separated, one per seed (>= 2)")
    p.add_argument("--ids", default="1,5,9,21,39", help="Table C1 states by number")
    p.add_argument("--json", help="write every measurement here (atomically)")
    p.add_argument("--doc", help="Markdown file whose table between <!-- BLOCK:begin/end --> is replaced")
    p.add_argument("--block", default="time-step-seeds", help="the block of --doc")
    o = cli.parse(p)
    o.specimens = o.specimens.split(",")
    if len(o.specimens) < 2:
        cli.fail("--specimens: at least two (the scatter between seeds needs two)")
    for path in o.specimens:
        if not os.path.isfile(path):
            cli.fail("--specimens %s: no such file" % path)
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def measure(path, b, sz, rule):
    """The state reached from the specimen under the rule: its scalars, one list per quantity."""
    import numpy as np
    from trueaniso import fabric, specimen_file, statics, triaxial
    scene, _ = specimen_file.load(path)
    info = triaxial.reach_state(scene, b, sz, time_step=rule)
    f = fabric.fabric(scene)
    res = statics.static_stiffness(scene, rotations=True)
    E, nu = [float(x) for x in res["E"]], res["nu"]
    R, H = np.asarray(f["R"]), np.asarray(f["H"])
    return dict(steps=int(info["steps"]), e=[float(f["e"])], Zm=[float(f["Zm"])], rattlers=[float(f["Np0"])],
                R=list(np.diag(R) / np.trace(R)), H=list(np.diag(H) / np.trace(H)), E=E, Ez_Ex=[E[2] / E[0]],
                nu=[float(nu[i][j]) for i in range(3) for j in range(3) if i != j])


# How a change of each quantity is measured: relative for moduli, absolute for the rest.
QUANTITIES = (("e", "abs"), ("Zm", "abs"), ("rattlers", "abs"), ("R", "abs"), ("H", "abs"), ("E", "rel"),
              ("nu", "abs"), ("Ez_Ex", "rel"))


def change(a, b, kind):
    return max(abs(x / y - 1) if kind == "rel" else abs(x - y) for x, y in zip(a, b))


def scatter(values, kind):
    """The largest, over the components, sample standard deviation between the seeds (relative to
    the mean for moduli)."""
    import numpy as np
    v = np.asarray(values, dtype=float)  # seeds x components
    sd = v.std(axis=0, ddof=1)
    return float(np.max(sd / np.abs(v.mean(axis=0)) if kind == "rel" else sd))


def main():
    o = options()
    from trueaniso import atomic, study
    states = study.table_states(study.parse_ids(o.ids))
    data = {}
    for sid, b, sz in states:
        data[sid] = {rule: [measure(path, b, sz, rule) for path in o.specimens] for rule in RULES}
        print("state %s: steps %s" % (sid, {r: sum(x["steps"] for x in data[sid][r]) for r in RULES}), flush=True)
    if o.json:
        atomic.write_json(o.json, dict(specimens=[os.path.basename(p) for p in o.specimens], rules=RULES,
                                       states=data))
    head = " | ".join("%s: rule / seeds" % q for q, _ in QUANTITIES)
    lines = ["Specimens %s (one seed each), one OpenMP thread, %s; each state from its specimen. Per quantity: the "
             "largest change the per-axis rule makes at the state over the seeds, then the scatter between the seeds "
             "under the reference rule (sample standard deviation); E, E_z/E_x relative, the rest absolute; R and H "
             "as fractions of their trace. Machine: %s, shared with other jobs." % (
                 ", ".join(os.path.basename(p) for p in o.specimens), time.strftime("%Y-%m-%d"), _bench.machine()), "",
             "| state | steps: reference -> per-axis | %s |" % head, "|---|---|%s" % ("---|" * len(QUANTITIES))]
    worst = {q: 0.0 for q, _ in QUANTITIES}
    total = {r: 0 for r in RULES}
    for sid, by_rule in data.items():
        ref, new = by_rule[RULES[0]], by_rule[RULES[1]]
        cells = []
        for q, kind in QUANTITIES:
            d = max(change(n[q], r[q], kind) for n, r in zip(new, ref))
            s = scatter([r[q] for r in ref], kind)
            worst[q] = max(worst[q], d / s if s > 0 else float("inf"))
            cells.append("%.1e / %.1e" % (d, s))
        for r in RULES:
            total[r] += sum(x["steps"] for x in by_rule[r])
        lines.append("| %s | %d -> %d | %s |" % (sid, sum(x["steps"] for x in ref), sum(x["steps"] for x in new),
                                                " | ".join(cells)))
    lines += ["", "Steps, all states and seeds: %d -> %d (%.2fx fewer). The largest ratio of the rule's change to the "
              "seeds' scatter at a state: %s." % (total[RULES[0]], total[RULES[1]], total[RULES[0]] / total[RULES[1]],
                                                   ", ".join("%s %.2g" % (q, worst[q]) for q, _ in QUANTITIES))]
    _bench.publish(o.doc, o.block, lines)


if __name__ == "__main__":
    cli.guarded(main)
