"""What the default time step rule changes in a study, against what another seed changes.

    /usr/bin/python3 bench/time_step_defaults.py --work DIR [--assemblies sphere=1000,clump1=200,clump2=200]
        [--seeds 1,2,3] [--ids 1,21,39] [--json out.json] [--doc docs/time-step.md]

The default time step rule of the states and the probes is per-axis; the preparation's stays
smallest-inertia (docs/time-step.md). For each assembly and seed the specimen is prepared once by
the default recipe (prepare_specimen.py, one thread, no checkpoints), and taken to every state asked
for, from the specimen itself, once under each rule. At each state: e, Zm, the rattlers, the fabric
tensors R and H (Eq. 15-16, as fractions of their trace), E_i and nu_ij of the exact static solve
(rotations free) and E_z/E_x. Per quantity, the table gives the largest change the rule makes (over
the seeds and the components) beside the scatter between the seeds under smallest-inertia (their
sample standard deviation, at that component), and their ratio: the rule changes the physics no
more than another seed does when the ratio is well below 1.

The probes: at each state, reached under smallest-inertia, the probes on z and x run under each rule
from the same state, each against the exact static solve of that state (the probe's own error): the
rule measures the same modulus when it moves E by less than that error.

Each specimen, state and probe is kept in --work as it ends (specimens, and results-ASSEMBLY.json),
so an interrupted run goes on where it stopped, and runs of one assembly each (--only) may share a
--work folder: the tables read every assembly's results there.
"""
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

RULES = ("smallest-inertia", "per-axis")  # the old rule first, then the default
QUANTITIES = (("e", "abs"), ("Zm", "abs"), ("rattlers", "abs"), ("R", "abs"), ("H", "abs"), ("E", "rel"),
              ("nu", "abs"), ("Ez_Ex", "rel"))
PROBES = ("z", "x")


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--work", required=True, help="folder for the specimens and results.json (resumable)")
    p.add_argument("--assemblies", default="sphere=1000,clump1=200,clump2=200",
                   help="assembly=particles, comma separated")
    p.add_argument("--seeds", default="1,2,3", help="seeds, comma separated (>= 2)")
    p.add_argument("--ids", default="1,21,39", help="Table C1 states by number (probes at each)")
    p.add_argument("--only", help="run this assembly of --assemblies alone (the tables need all)")
    p.add_argument("--json", help="write every measurement here too (atomically)")
    p.add_argument("--doc", help="Markdown file whose tables between the markers (--block) are replaced")
    p.add_argument("--block", default="time-step-defaults", help="the block of --doc (and BLOCK-probes)")
    o = cli.parse(p)
    try:
        o.assemblies = [(a.split("=")[0], int(a.split("=")[1])) for a in o.assemblies.split(",")]
        o.seeds = [int(s) for s in o.seeds.split(",")]
    except (IndexError, ValueError):
        cli.fail("--assemblies: assembly=particles, comma separated; --seeds: whole numbers, comma separated")
    if len(o.seeds) < 2:
        cli.fail("--seeds: at least two (the scatter between seeds needs two)")
    os.makedirs(o.work, exist_ok=True)
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def prepared(o, assembly, n, seed):
    """The specimen of the default recipe (the preparation's default rule), made once (kept in --work)."""
    path = os.path.join(o.work, "%s-%d-s%d.npz" % (assembly, n, seed))
    if not os.path.exists(path):
        cmd = ["/usr/bin/python3", os.path.join(os.path.dirname(HERE), "pyscripts", "prepare_specimen.py"), "--assembly",
               assembly, "--n", str(n), "--seed", str(seed), "--threads", "1", "--checkpoint-every", "0", "--quiet",
               "--out", path]
        out = subprocess.run(cmd, capture_output=True, text=True, env=dict(os.environ, OMP_NUM_THREADS="1"))
        if out.returncode != 0:
            cli.fail("preparation failed: %s\n%s" % (" ".join(cmd), out.stderr[-2000:]), 1)
    return path


def measured(scene, extra=None):
    """The state's scalars, one list per quantity."""
    import numpy as np
    from trueaniso import fabric, statics
    f = fabric.fabric(scene)
    res = statics.static_stiffness(scene, rotations=True)
    E, nu = [float(x) for x in res["E"]], res["nu"]
    R, H = np.asarray(f["R"]), np.asarray(f["H"])
    out = dict(e=[float(f["e"])], Zm=[float(f["Zm"])], rattlers=[float(f["Np0"])],
               R=list(np.diag(R) / np.trace(R)), H=list(np.diag(H) / np.trace(H)), E=E, Ez_Ex=[E[2] / E[0]],
               nu=[float(nu[i][j]) for i in range(3) for j in range(3) if i != j])
    out.update(extra or {})
    return out


def run(o, results, save):
    from trueaniso import specimen_file, study, triaxial
    states = study.table_states(study.parse_ids(o.ids))
    for assembly, n in o.assemblies:
        if o.only and assembly != o.only:
            continue
        for seed in o.seeds:
            key = "%s-%d-s%d" % (assembly, n, seed)
            entry = results.get(key)
            if entry and all(str(sid) in entry["states"].get(rule, {}) for rule in RULES for sid, _, _ in states) \
                    and all(str(sid) in entry["probes"] for sid, _, _ in states):
                continue
            t0 = time.time()
            path = prepared(o, assembly, n, seed)
            entry = results.setdefault(key, dict(assembly=assembly, n=n, seed=seed, states={}, probes={}))
            for rule in RULES:
                done = entry["states"].setdefault(rule, {})
                for sid, b, sz in states:
                    if str(sid) in done and (rule != RULES[0] or str(sid) in entry["probes"]):
                        continue
                    scene, _ = specimen_file.load(path)
                    info = triaxial.reach_state(scene, b, sz, time_step=rule)
                    done[str(sid)] = measured(scene, dict(steps=int(info["steps"]), wall=float(info["wall_time"])))
                    if rule == RULES[0]:
                        entry["probes"][str(sid)] = probes(scene)
                    save(assembly)
            print("%s: %.0f s" % (key, time.time() - t0), flush=True)


def probes(scene):
    """The probes on z and x at the scene's state under each rule, and the static solve's moduli."""
    from trueaniso import statics, triaxial
    hold = triaxial.stress_as_held(scene)
    static = [float(x) for x in statics.static_stiffness(scene, rotations=True)["E"]]
    out = dict(static=static)
    for rule in RULES:
        rows = triaxial.probe_state(scene, hold, axes=PROBES, time_step=rule)
        out[rule] = [dict(E=float(r["E"]), steps=int(r["steps"])) for r in rows]
    return out


def tables(o, results):
    """The states' table (the rule's largest change against the seeds' scatter, per quantity) and the
    probes' (each probe's error against the static solve under each rule, and the rule's change)."""
    import numpy as np
    states = [str(s) for s in o.ids.split(",")]
    head = " | ".join("%s: change / seeds" % q for q, _ in QUANTITIES)
    lines = ["| assembly | state | steps: smallest-inertia -> per-axis (all seeds) | %s |" % head,
             "|---|---|---|%s" % ("---|" * len(QUANTITIES))]
    worst = {}
    for assembly, n in o.assemblies:
        runs = [results["%s-%d-s%d" % (assembly, n, s)] for s in o.seeds]
        for where in states:
            old = [r["states"][RULES[0]][where] for r in runs]
            new = [r["states"][RULES[1]][where] for r in runs]
            cells = []
            for q, kind in QUANTITIES:
                a = np.asarray([x[q] for x in old], dtype=float)  # seeds x components
                b = np.asarray([x[q] for x in new], dtype=float)
                scale = np.abs(a.mean(axis=0)) if kind == "rel" else 1.0
                d = (np.abs(b - a) / scale).max(axis=0)  # the largest change over the seeds
                sd = a.std(axis=0, ddof=1) / scale
                ratio = np.where(sd > 0, d / np.where(sd > 0, sd, 1.0), np.where(d > 0, np.inf, 0.0))
                k = int(np.argmax(ratio))
                worst[(assembly, q)] = max(worst.get((assembly, q), 0.0), float(ratio[k]))
                cells.append("%.1e / %.1e" % (d[k], sd[k]))
            lines.append("| %s %d | %s | %d -> %d | %s |" % (
                assembly, n, where, sum(x["steps"] for x in old), sum(x["steps"] for x in new), " | ".join(cells)))
    lines += ["", "The largest ratio of the rule's change to the scatter between seeds, per assembly: " + "; ".join(
        "%s %s" % (a, ", ".join("%s %.2g" % (q, worst[(a, q)]) for q, _ in QUANTITIES)) for a, _ in o.assemblies) + "."]
    probe_lines = ["| assembly | seed | state | probe | E static (MPa) | probe error, smallest-inertia | probe error, "
                   "per-axis | change of E by the rule | probe steps: smallest-inertia -> per-axis |",
                   "|---|---|---|---|---|---|---|---|---|"]
    for assembly, n in o.assemblies:
        for s in o.seeds:
            for where in states:
                p = results["%s-%d-s%d" % (assembly, n, s)]["probes"][where]
                for k, axis in enumerate(PROBES):
                    i = "xyz".index(axis)
                    Es, Eo, En = p["static"][i], p[RULES[0]][k]["E"], p[RULES[1]][k]["E"]
                    probe_lines.append("| %s %d | %d | %s | %s | %.2f | %.1e | %.1e | %.1e | %d -> %d |" % (
                        assembly, n, s, where, axis, Es / 1e6, Eo / Es - 1, En / Es - 1, En / Eo - 1,
                        p[RULES[0]][k]["steps"], p[RULES[1]][k]["steps"]))
    return "\n".join(lines), "\n".join(probe_lines), worst


def main():
    o = options()
    import json
    from trueaniso import atomic
    store = {a: os.path.join(o.work, "results-%s.json" % a) for a, _ in o.assemblies}
    results = {}
    for path in store.values():
        if os.path.exists(path):
            with open(path) as f:
                results.update(json.load(f))

    def save(assembly):
        atomic.write_json(store[assembly], {k: v for k, v in results.items() if v["assembly"] == assembly})
    run(o, results, save)
    if o.only:
        return
    if o.json:
        atomic.write_json(o.json, dict(rules=RULES, ids=o.ids, seeds=o.seeds, results=results))
    from trueaniso import engines
    states, probe_table, _ = tables(o, results)
    intro = ("Default recipe of each assembly (prepared under smallest-inertia), seeds %s, one OpenMP thread, engines "
             "at %s, %s; each state from the specimen under each rule. Per quantity: the largest change the rule makes "
             "(per-axis minus smallest-inertia, over the seeds), then the scatter between the seeds under "
             "smallest-inertia (sample standard deviation), at the component where their ratio is largest; E, "
             "E_z/E_x relative, the rest absolute; R and H as fractions of their trace. Machine: %s, shared with "
             "other jobs." % (",".join(map(str, o.seeds)), engines.build_arch(), time.strftime("%Y-%m-%d"),
                              _bench.machine()))
    text = intro + "\n\n" + states
    print(text + "\n\n" + probe_table)
    if o.doc:
        _bench.replace_block(o.doc, o.block, text)
        _bench.replace_block(o.doc, o.block + "-probes", probe_table)


if __name__ == "__main__":
    cli.guarded(main)
