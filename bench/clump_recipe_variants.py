"""One clump preparation with some recipe settings changed, measured at its isotropic state: void
ratio, Zm, rattlers (bodies left with fewer than two force-carrying contacts, removed one after
another, as the static solve finds them) and E_x, E_y, E_z from the exact static solve with
particle rotations restrained and free (docs/statics.md). One JSON object a run, appended to --json.

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/clump_recipe_variants.py --assembly clump2 --n 1000 \
        --seed 1 --set unbalanced=1e-4 --out /tmp/c2-u1e-4.npz --json docs/data/clump-recipes/clump2-variants-1000.jsonl

--set KEY=VALUE (repeatable) is a recipe parameter (clump_recipes.RECIPES) or one of the preparation's
own settings (inertial_number, prep_unbalanced, unbalanced, damping, gain); --recipe NAME starts from a
named variant (clump_recipes.VARIANTS). The specimen is saved with its settings, so that
run_states.py can take it through Table C1's states.

    /usr/bin/python3 bench/clump_recipe_variants.py --study DIR --json DIR/statics.json

measures the states 1 and 21 of a run_states.py study instead (its checkpoints DIR/states/1.npz and
21.npz: e, Zm, rattlers, the static E_i, rotations restrained and free, and their ratios state 21 /
state 1), written as one JSON object.
"""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)

from trueaniso import cli  # noqa: E402

PREPARATION = ("inertial_number", "prep_unbalanced", "unbalanced", "damping", "gain")


def value(text):
    try:
        return json.loads(text)
    except ValueError:
        return text


def measure_states(study, ids=("1", "21")):
    """e, Zm, rattlers and the static E_i of the study's checkpoints of states `ids`, and the ratios
    of E_i at the last state to the first, rotations restrained and free."""
    from trueaniso import specimen, specimen_file, statics
    out = {}
    for sid in ids:
        scene, _ = specimen_file.load(os.path.join(study, "states", "%s.npz" % sid))
        st = specimen.state(scene)
        row = dict(e=st["void_ratio"], Zm=st["Zm"], Np0=st["Np0"], Np1=st["Np1"],
                   sigma=[st["sigma_x"], st["sigma_y"], st["sigma_z"]])
        for rot in ("restrained", "free"):
            r = statics.static_stiffness(scene, rotations=(rot == "free"))
            row["E_" + rot] = [float(x) for x in r["E"]]
            row["rattlers_" + rot] = len(r["rattlers"])
        out[sid] = row
    for rot in ("restrained", "free"):
        out["ratio_" + rot] = [a / b for a, b in zip(out[ids[-1]]["E_" + rot], out[ids[0]]["E_" + rot])]
    return out


def variants_table(rows):
    """The Markdown table of docs/studies/clumps.md ("clump2 recipe variants") from the JSON-lines rows."""
    out = ["| variant | seed | e | Zm | rattlers | E_z/E_x restrained | free | E_x, E_y, E_z restrained (MPa) "
           "| steps (expansion + consolidation) | wall |", "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append("| %s | %d | %.4f | %.3f | %d (%.1f %%) | %.3f | %.3f | %.1f, %.1f, %.1f | %d + %d | %.0f s |" % (
            r["label"], r["seed"], r["e"], r["Zm"], r["rattlers_free"], 100.0 * r["rattler_fraction"],
            r["Ez_Ex_restrained"], r["Ez_Ex_free"], *[x / 1e6 for x in r["E_restrained"]], r["steps_expansion"],
            r["steps_consolidation"], r["wall_prep"]))
    return "\n".join(out)


def state21_table(runs):
    """The Markdown table of the state-21 runs: (label, seed, statics record, probes.csv rows, steps, wall)."""
    out = ["| variant | seed | e: state 1 -> 21 | Zm | rattlers | E_x, E_y, E_z at 21 / at 1, probes | static solve "
           "| rotations free, static | steps to state 21 | wall |", "|---|---|---|---|---|---|---|---|---|---|"]
    for label, seed, st, probes, steps, wall in runs:
        a, b = st["1"], st["21"]
        out.append("| %s | %d | %.3f -> %.3f | %.2f -> %.2f | %d -> %d | %s | %s | %s | %s | %s |" % (
            label, seed, a["e"], b["e"], a["Zm"], b["Zm"], a["rattlers_free"], b["rattlers_free"],
            ", ".join("%.3f" % x for x in probes), ", ".join("%.3f" % x for x in st["ratio_restrained"]),
            ", ".join("%.3f" % x for x in st["ratio_free"]), "{:,}".format(steps), wall))
    out.append("| paper (Table B1, restrained) | | 0.636 | | | 0.987, 0.880, 1.072 | | | | |")
    return "\n".join(out)


def state21_runs(data):
    """(label, seed, statics record, probe ratios, steps, wall) of every state21-LABEL-sSEED directory in `data`."""
    import csv
    runs = []
    for name in sorted(os.listdir(data)):
        if not name.startswith("state21-"):
            continue
        label, seed = name[len("state21-"):].rsplit("-s", 1)
        with open(os.path.join(data, name, "statics.json")) as f:
            st = json.load(f)
        with open(os.path.join(data, name, "probes.csv")) as f:
            rows = list(csv.DictReader(f))
        E = {}
        for r in rows:
            E.setdefault((r["state"], r["probe"]), []).append(float(r["E"]))
        probes = [sum(E[("21", a)]) / len(E[("21", a)]) / (sum(E[("1", a)]) / len(E[("1", a)])) for a in "xyz"]
        at21 = next(r for r in rows if r["state"] == "21")
        runs.append((label, int(seed), st, probes, int(float(at21["state_steps"])),
                     "%.0f s" % float(at21["state_wall_time"])))
    return runs


def write_doc(doc, data):
    for block, name in (("clump2-variants", "clump2-variants-1000.jsonl"),
                        ("clump1-variants", "clump1-variants-300.jsonl")):
        with open(os.path.join(data, name)) as f:
            _bench.replace_block(doc, block, variants_table([json.loads(line) for line in f if line.strip()]))
    _bench.replace_block(doc, "clump2-state21", state21_table(state21_runs(data)))


def prepare_saved(o, settings, progress=None):
    """The preparation of o.assembly, o.n, o.seed with `settings` at one thread, saved to o.out with
    its log (threads, and the recipe's name when o.recipe names one) and its state summary.
    Returns the scene, the log and the summary."""
    from trueaniso import clump_specimen, specimen, specimen_file
    extra = dict(progress=progress) if progress else {}
    scene, log = clump_specimen.prepare_clumps(o.assembly, o.n, seed=o.seed, **dict(extra, **settings))
    log["threads"] = 1
    if o.recipe:
        log["recipe"] = o.recipe
    st = specimen.state(scene)
    specimen_file.save(o.out, scene, seed=o.seed, parameters=log, summary=st)
    return scene, log, st


def static_moduli(scene):
    """E_i, E_z/E_x, E_z/E_y and the rattlers of the exact static solve, rotations restrained and free."""
    from trueaniso import statics
    row = {}
    for rot in ("restrained", "free"):
        r = statics.static_stiffness(scene, rotations=(rot == "free"))
        row["E_" + rot] = [float(x) for x in r["E"]]
        row["Ez_Ex_" + rot] = float(r["E"][2] / r["E"][0])
        row["Ez_Ey_" + rot] = float(r["E"][2] / r["E"][1])
        row["rattlers_" + rot] = len(r["rattlers"])
    return row


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--assembly", choices=("clump1", "clump2"), help="clump assembly (to prepare)")
    p.add_argument("--n", type=int, default=1000, help="number of clumps")
    p.add_argument("--seed", type=int, default=1, help="seed of the random packing")
    p.add_argument("--recipe", default=None, help="a named variant of the assembly's recipe")
    p.add_argument("--set", action="append", default=[], help="KEY=VALUE, repeatable")
    p.add_argument("--label", default=None, help="name of the row (default: the settings)")
    p.add_argument("--out", help="specimen file (.npz)")
    p.add_argument("--study", help="a run_states.py study of states 1 and 21: measure those instead")
    p.add_argument("--json", help="JSON-lines file a row is appended to (with --study: written)")
    p.add_argument("--doc", help="rewrite the tables of this Markdown file (docs/studies/clumps.md) from --data instead")
    p.add_argument("--data", default="docs/data/clump-recipes", help="the measurements the tables are made of")
    o = cli.parse(p)
    if o.doc:
        write_doc(o.doc, o.data)
        return
    if not o.json:
        raise cli.InputError("give --json")
    from trueaniso import atomic, clump_recipes, engines, provenance
    engines.set_threads(1)
    provenance.versions()  # the code version, taken now: sources edited during the run do not refuse its save
    if o.study:
        atomic.write_json(o.json, measure_states(o.study))
        return
    if not (o.out and o.assembly):
        raise cli.InputError("give --assembly and --out (the specimen), or --study")
    changed = {}
    for item in o.set:
        k, _, v = item.partition("=")
        changed[k] = value(v)
    kwargs = dict(clump_recipes.variant(o.assembly, o.recipe)) if o.recipe else {}
    kwargs.update(changed)
    t0 = time.time()
    scene, log, st = prepare_saved(o, kwargs)
    prep_wall = time.time() - t0
    row = dict(label=o.label or (o.recipe or "default") + "".join(" %s=%s" % kv for kv in changed.items()),
               assembly=o.assembly, n=o.n, seed=o.seed, recipe=o.recipe, settings=changed,
               e=st["void_ratio"], Zm=st["Zm"], Np0=st["Np0"], Np1=st["Np1"],
               steps_expansion=log["steps_expansion"], steps_consolidation=log["steps_consolidation"],
               wall_prep=prep_wall)
    row.update(static_moduli(scene))
    row["rattler_fraction"] = row["rattlers_free"] / float(o.n)
    row["wall"] = time.time() - t0
    print(json.dumps(row), flush=True)
    with open(o.json, "a") as f:
        f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    cli.guarded(main)
