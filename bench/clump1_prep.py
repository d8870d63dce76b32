"""Where a clump preparation's steps go: one preparation (prepare_clumps, as prepare_specimen.py runs
it at one thread without checkpoints) traced every chunk (the normal stresses, the shear stresses,
p, q/p with q = sqrt(3 J2), the unbalanced force, the radius scale), then measured at its
isotropic state as clump_recipe_variants.py measures (e, Zm, rattlers, E_i from the static
solve, rotations restrained and free). One JSON object a run, appended to --json.

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/clump1_prep.py --n 1000 --seed 1 \
        [--recipe hold-deviator] [--time-step per-axis] --out /tmp/c1.npz --json docs/data/clump1-prep/runs.jsonl

    /usr/bin/python3 bench/clump1_prep.py --doc docs/studies/clumps.md   # the table, from the data
"""
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)

from trueaniso import cli  # noqa: E402

DATA = "docs/data/clump1-prep"


def deviator(sig):
    """(p, q) of a stress tensor, compression positive: p the mean, q = sqrt(3 J2)."""
    p = (sig[0][0] + sig[1][1] + sig[2][2]) / 3.0
    s = [[sig[i][j] - (p if i == j else 0.0) for j in range(3)] for i in range(3)]
    j2 = 0.5 * sum(s[i][j] * s[j][i] for i in range(3) for j in range(3))
    return p, math.sqrt(3.0 * max(j2, 0.0))


def label(r):
    parts = ["hold, gain %g" % r["hold_deviator"]] if r.get("hold_deviator") else []
    parts += ["%s %s" % kv for kv in sorted((r.get("settings") or {}).items())]
    if r.get("time_step", "smallest-inertia") != "smallest-inertia":
        parts.append("%s step" % r["time_step"])
    return ", ".join(parts) or "recipe"


def summary(r):
    """From a row's trace: the first stages' steps (gas and stage 1), the free expansion's, the
    free-expansion step at which p first reached 97 % of its goal, and the medians of q/p and of the
    normal deviator max |sigma_k - p| / p over the free expansion once p > 50 kPa."""
    import statistics
    tr = r["trace"]
    first = sum(max([t["steps"] for t in tr if t["stage"].startswith(k)] or [0]) for k in ("expansion (gas", "stage 1"))
    free = [t for t in tr if t["stage"].startswith("expansion (free")]
    reach = next((t["steps"] for t in free if t["p"] >= 0.97 * 100e3), None)
    loaded = [t for t in free if t["p"] > 50e3]
    qp = statistics.median(t["q_over_p"] for t in loaded) if loaded else float("nan")
    dev = statistics.median(max(abs(x - t["p"]) for x in t["sigma"]) / t["p"] for t in loaded) if loaded else float("nan")
    return first, r["steps_expansion"] - first, reach, qp, dev


def table(rows):
    out = ["| preparation | clumps | seed | steps: first stages + free expansion + consolidation | free-expansion step of p >= 97 kPa | "
           "q/p, normal deviator / p (median, p > 50 kPa) | e | Zm | rattlers | E_z/E_x restrained | free | wall |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (label(r) != "recipe", label(r), r["n"], r["seed"])):
        first, free, reach, qp, dev = summary(r)
        out.append("| %s | %d | %d | %d + %d + %d | %s | %.3f, %.3f | %.4f | %.2f | %s | %s | %s | %.0f s |" % (
            label(r), r["n"], r["seed"], first, free, r["steps_consolidation"], "-" if reach is None else reach,
            qp, dev, r["e"], r["Zm"], r.get("rattlers_free", "-"),
            "%.3f" % r["Ez_Ex_restrained"] if "Ez_Ex_restrained" in r else "-",
            "%.3f" % r["Ez_Ex_free"] if "Ez_Ex_free" in r else "-", r["wall_prep"]))
    return "\n".join(out)


def rows_of(data):
    """The rows of every runs-*.jsonl in `data`."""
    rows = []
    for name in sorted(os.listdir(data)):
        if name.startswith("runs-") and name.endswith(".jsonl"):
            with open(os.path.join(data, name)) as f:
                rows += [json.loads(line) for line in f if line.strip()]
    return rows


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--assembly", choices=("clump1", "clump2"), default="clump1", help="clump assembly")
    p.add_argument("--n", type=int, default=1000, help="number of clumps")
    p.add_argument("--seed", type=int, default=1, help="seed of the random packing")
    p.add_argument("--recipe", default=None, help="a named variant of the assembly's recipe")
    p.add_argument("--time-step", default=None, help="the time step rule (as prepare_specimen.py --time-step)")
    p.add_argument("--hold-deviator", type=float, default=None,
                   help="the deviator hold's gain (prepare_clumps hold_deviator), over the recipe's")
    p.add_argument("--set", action="append", default=[],
                   help="KEY=VALUE, repeatable: a recipe parameter or a keyword of prepare_clumps (prep_unbalanced, gain, ...)")
    p.add_argument("--max-steps", type=int, default=5_000_000, help="steps a stage may take (prepare_clumps)")
    p.add_argument("--no-statics", action="store_true", help="the trace and the state only, no static solve")
    p.add_argument("--out", help="specimen file (.npz)")
    p.add_argument("--json", help="JSON-lines file a row is appended to")
    p.add_argument("--doc", help="rewrite the table of this Markdown file from --data instead")
    p.add_argument("--data", default=DATA, help="the measurements the table is made of")
    o = cli.parse(p)
    if o.doc:
        _bench.replace_block(o.doc, "clump1-prep", table(rows_of(o.data)))
        return
    if not (o.json and o.out):
        raise cli.InputError("give --out and --json")
    import numpy as np
    from trueaniso import clump_recipes, dem, engines, provenance
    import clump_recipe_variants
    engines.set_threads(1)
    provenance.versions()  # the code version, taken now: sources edited during the run do not refuse its save
    rule = o.time_step or cli.DEFAULT_PREPARATION_TIME_STEP
    if o.time_step:
        dem.time_step_rule = o.time_step
    trace = []

    def progress(label, scene, engine, steps):
        sig = np.asarray(engines.stress(scene))
        pm, q = deviator(sig)
        trace.append(dict(stage=label, steps=int(steps), sigma=[float(sig[k, k]) for k in range(3)],
                          shear=[float(sig[1, 2]), float(sig[0, 2]), float(sig[0, 1])], p=float(pm),
                          q_over_p=float(q / pm) if pm > 0 else None, unbalanced=float(engine.unbalanced),
                          scale=float(getattr(engine, "scale", 1.0)), dt=float(scene.dt)))
        if len(trace) % 20 == 0:
            t = trace[-1]
            sys.stderr.write("%s %d: sigma %s kPa, q/p %.4f, unbalanced %.2e\n" % (
                t["stage"], t["steps"], " ".join("%.2f" % (x / 1e3) for x in t["sigma"]), t["q_over_p"] or 0.0,
                t["unbalanced"]))
            sys.stderr.flush()

    kwargs = dict(clump_recipes.variant(o.assembly, o.recipe)) if o.recipe else {}
    if o.hold_deviator is not None:
        kwargs["hold_deviator"] = o.hold_deviator
    changed = {}
    for item in o.set:
        k, _, v = item.partition("=")
        changed[k] = json.loads(v)
    kwargs.update(changed)
    t0 = time.time()
    scene, log, st = clump_recipe_variants.prepare_saved(o, dict(kwargs, max_steps=o.max_steps), progress=progress)
    prep_wall = time.time() - t0
    expansion = [t for t in trace if not t["stage"].startswith("consolidation")]
    row = dict(assembly=o.assembly, n=o.n, seed=o.seed, recipe=o.recipe, time_step=rule,
               hold_deviator=kwargs.get("hold_deviator"), settings=changed,
               e=st["void_ratio"], Zm=st["Zm"], Np0=st["Np0"], Np1=st["Np1"],
               sigma=[st["sigma_x"], st["sigma_y"], st["sigma_z"]],
               steps_expansion=log["steps_expansion"], steps_consolidation=log["steps_consolidation"],
               q_over_p_end_expansion=expansion[-1]["q_over_p"] if expansion else None,
               wall_prep=prep_wall, load=os.getloadavg()[0])
    if not o.no_statics:
        row.update(clump_recipe_variants.static_moduli(scene))
    row["trace"] = trace
    row["wall"] = time.time() - t0
    print(json.dumps({k: v for k, v in row.items() if k != "trace"}), flush=True)
    with open(o.json, "a") as f:
        f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    cli.guarded(main)
