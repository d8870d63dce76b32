"""One clump preparation with some recipe settings changed, measured at its isotropic state: void
ratio, Zm, rattlers (bodies left with fewer than two force-carrying contacts, removed one after
another, as the static solve finds them) and E_x, E_y, E_z from the exact static solve with
particle rotations restrained and free (docs/statics.md). One JSON object a run, appended to --json.

    OMP_NUM_THREADS=1 /usr/bin/python3 pyscripts/bench/clump_recipe_variants.py --assembly clump2 --n 1000 \
        --seed 1 --set unbalanced=1e-4 --out /tmp/c2-u1e-4.npz --json docs/data/clump2-recipes/variants.jsonl

--set KEY=VALUE (repeatable) is a recipe parameter (clump_recipes.RECIPES) or one of the preparation's
own settings (inertial_number, prep_unbalanced, unbalanced, damping, gain); --recipe NAME starts from a
named variant (clump_recipes.VARIANTS). The specimen is saved with its settings, so that
run_states.py can take it through Table C1's states.
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


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--assembly", choices=("clump1", "clump2"), required=True, help="clump assembly")
    p.add_argument("--n", type=int, default=1000, help="number of clumps")
    p.add_argument("--seed", type=int, default=1, help="seed of the random packing")
    p.add_argument("--recipe", default=None, help="a named variant of the assembly's recipe")
    p.add_argument("--set", action="append", default=[], help="KEY=VALUE, repeatable")
    p.add_argument("--label", default=None, help="name of the row (default: the settings)")
    p.add_argument("--out", required=True, help="specimen file (.npz)")
    p.add_argument("--json", required=True, help="JSON-lines file a row is appended to")
    o = cli.parse(p)
    from trueaniso import clump_recipes, clump_specimen, engines, specimen, specimen_file, statics
    engines.set_threads(1)
    changed = {}
    for item in o.set:
        k, _, v = item.partition("=")
        changed[k] = value(v)
    kwargs = dict(clump_recipes.variant(o.assembly, o.recipe)) if o.recipe else {}
    kwargs.update(changed)
    t0 = time.time()
    scene, log = clump_specimen.prepare_clumps(o.assembly, o.n, seed=o.seed, **kwargs)
    log["threads"] = 1
    if o.recipe:
        log["recipe"] = o.recipe
    st = specimen.state(scene)
    specimen_file.save(o.out, scene, seed=o.seed, parameters=log, summary=st)
    prep_wall = time.time() - t0
    row = dict(label=o.label or (o.recipe or "default") + "".join(" %s=%s" % kv for kv in changed.items()),
               assembly=o.assembly, n=o.n, seed=o.seed, recipe=o.recipe, settings=changed,
               e=st["void_ratio"], Zm=st["Zm"], Np0=st["Np0"], Np1=st["Np1"],
               steps_expansion=log["steps_expansion"], steps_consolidation=log["steps_consolidation"],
               wall_prep=prep_wall, specimen=o.out)
    for rot in ("restrained", "free"):
        r = statics.static_stiffness(scene, rotations=(rot == "free"))
        row["E_" + rot] = [float(x) for x in r["E"]]
        row["Ez_Ex_" + rot] = float(r["E"][2] / r["E"][0])
        row["Ez_Ey_" + rot] = float(r["E"][2] / r["E"][1])
        row["rattlers_" + rot] = len(r["rattlers"])
    row["rattler_fraction"] = row["rattlers_free"] / float(o.n)
    row["wall"] = time.time() - t0
    print(json.dumps(row), flush=True)
    with open(o.json, "a") as f:
        f.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    cli.guarded(main)
