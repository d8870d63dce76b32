"""The clump recipes screened along Table C1: one preparation with some recipe settings changed
(as clump_recipe_variants.py makes it), its isotropic state's static E_i with rotations
restrained, and a run_study.py study of a few states on it; the tables of docs/studies/clumps.md
("clump2 consolidated at friction 0.5", "clump1's growth friction") from the committed data.

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/clump2_recipe_screen.py --label NAME --n 1000 --seed 1 \\
        [--set stage1_pressure=5e3 --set mu_free=0.25 ...] --ids 1,9,21,33 --work /tmp/screen \\
        --data docs/data/clump2-recipes
    /usr/bin/python3 bench/clump2_recipe_screen.py --doc docs/studies/clumps.md --data docs/data/clump2-recipes
    OMP_NUM_THREADS=1 /usr/bin/python3 bench/clump2_recipe_screen.py --assembly clump1 --label mu-prep-0.01 \\
        --set mu_prep=0.01 --ids 1,9,21,33 --work /tmp/screen --data docs/data/clump1-recipes
    /usr/bin/python3 bench/clump2_recipe_screen.py --assembly clump1 --doc docs/studies/clumps.md \\
        --data docs/data/clump1-recipes

The first form prepares WORK/NAME/specimen.npz (one thread), solves its isotropic state, runs
`run_study.py --specimen ... --ids IDS --time-step per-axis --threads 1` into WORK/NAME/study and
copies what the table reads into DATA/NAME/: prep.json (the preparation's settings, steps, e, Zm,
rattlers and the static E_i) and the study's probes.csv, metadata.json and statics records; the
table computes each study's headlines (trueaniso.analysis.seeds). A study that stops at a state
that does not settle keeps the rows of the states it reached; the table says which states each row
covers. A study made otherwise (run_study.py preparing its own specimen) is copied in with --study
DIR --label NAME; --reciprocity IDS compares its probes' compliance with the exact static solve's.
"""
import json
import os
import shutil
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)

from trueaniso import cli  # noqa: E402

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COPIED = ("probes.csv", "metadata.json", "statics_isotropic.json", "statics_state-21.json", "specimen.json")


def value(text):
    try:
        return json.loads(text)
    except ValueError:
        return text


def prepare(assembly, label, n, seed, settings, work):
    """The preparation and its restrained static solve: WORK/LABEL/specimen.npz and a dict."""
    from trueaniso import clump_specimen, engines, provenance, specimen, specimen_file, statics
    engines.set_threads(1)
    provenance.versions()
    d = os.path.join(work, label)
    os.makedirs(d, exist_ok=True)
    t0 = time.time()
    scene, log = clump_specimen.prepare_clumps(assembly, n, seed=seed, **settings)
    log["threads"] = 1
    st = specimen.state(scene)
    specimen_file.save(os.path.join(d, "specimen.npz"), scene, seed=seed, parameters=log, summary=st)
    wall = time.time() - t0
    r = statics.static_stiffness(scene, rotations=False)
    E = [float(x) for x in r["E"]]
    return dict(assembly=assembly, label=label, n=n, seed=seed, settings=settings, e=st["void_ratio"], Zm=st["Zm"], Np0=st["Np0"],
                steps_expansion=log["steps_expansion"], steps_unloading=log.get("steps_unloading", 0),
                steps_consolidation=log["steps_consolidation"], wall_prep=wall, E_restrained=E,
                Ez_Ex=E[2] / (0.5 * (E[0] + E[1])), rattlers_restrained=len(r["rattlers"]))


def study(specimen_path, ids, out):
    """run_study.py on the specimen (its return code: a state not settled stops the run)."""
    env = dict(os.environ, OMP_NUM_THREADS="1")
    cmd = [sys.executable, os.path.join(REPO, "pyscripts", "run_study.py"), "--specimen", specimen_path, "--ids", ids,
           "--time-step", "per-axis", "--threads", "1", "--out", out, "--progress-every", "60"]
    with open(out + ".log", "w") as f:
        return subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT, env=env).returncode


def from_study(label, study_dir):
    """The record of prepare() for the specimen run_study.py prepared in its directory (the E_i of its
    isotropic state's statics record, rotations restrained)."""
    from trueaniso import specimen_file
    _, meta = specimen_file.read(os.path.join(study_dir, "specimen.npz"))
    p, st = meta["parameters"], meta["summary"]
    with open(os.path.join(study_dir, "statics_isotropic.json")) as f:
        E = json.load(f)["E_blocked"]
    return dict(label=label, n=p["n"], seed=meta["seed"], settings={}, e=st["void_ratio"], Zm=st["Zm"], Np0=st["Np0"],
                steps_expansion=p["steps_expansion"], steps_unloading=p.get("steps_unloading", 0),
                steps_consolidation=p["steps_consolidation"], wall_prep=p["wall_time"], E_restrained=E,
                Ez_Ex=E[2] / (0.5 * (E[0] + E[1])), checkpoint_every=p.get("checkpoint_every"))


def collect(label, study_dir, data, prep=None):
    """Copy what the table reads into DATA/LABEL/ (and the preparation's record, prep.json)."""
    dest = os.path.join(data, label)
    os.makedirs(dest, exist_ok=True)
    for name in COPIED:
        if os.path.exists(os.path.join(study_dir, name)):
            shutil.copyfile(os.path.join(study_dir, name), os.path.join(dest, name))
    if prep is None and os.path.exists(os.path.join(study_dir, "specimen.npz")):  # run_study.py prepared it
        prep = from_study(label, study_dir)
    if prep is not None:
        with open(os.path.join(dest, "prep.json"), "w") as f:
            json.dump(prep, f, indent=1)


def reciprocity_check(study_dir, ids):
    """Where the probes' reciprocity error comes from: at each state, the off-diagonal compliances
    S_ij = -nu_ij/E_i of the probes against those of the exact static solve of the state's checkpoint
    (rotations free, as the probes), and the asymmetry of each (seeds.reciprocity_errors' measure)."""
    import csv
    import numpy as np
    from trueaniso import engines, specimen_file, statics
    engines.set_threads(1)

    def asymmetry(S):
        return max(abs(S[i, j] - S[j, i]) / (0.5 * (abs(S[i, j]) + abs(S[j, i]))) for i, j in ((0, 1), (0, 2), (1, 2)))
    out = {}
    with open(os.path.join(study_dir, "probes.csv")) as f:
        rows = list(csv.DictReader(f))
    for sid in ids:
        scene, _ = specimen_file.load(os.path.join(study_dir, "states", "%s.npz" % sid))
        S = np.array(statics.static_stiffness(scene, rotations=True)["S"])[:3, :3]
        P = np.zeros((3, 3))
        for r in (r for r in rows if r["state"] == sid and r["rotations"] == "free"):
            i = "xyz".index(r["probe"])
            P[i, i] = 1.0 / float(r["E"])
            for k in ("nu_1", "nu_2"):
                P["xyz".index(r[k + "_name"][-1]), i] = -float(r[k]) / float(r["E"])  # S_ji = -nu_ij/E_i
        off = [(i, j) for i in range(3) for j in range(3) if i != j]
        out[sid] = dict(asymmetry_probes=asymmetry(P), asymmetry_static=asymmetry(S),
                        probe_over_static_offdiagonal=[P[i, j] / S[i, j] - 1.0 for i, j in off],
                        probe_over_static_diagonal=[P[i, i] / S[i, i] - 1.0 for i in range(3)])
    return out


def _row(d):
    from trueaniso.analysis import seeds, chain
    from trueaniso.analysis.results import read_probes
    prep = {}
    if os.path.exists(os.path.join(d, "prep.json")):
        with open(os.path.join(d, "prep.json")) as f:
            prep = json.load(f)
    if not os.path.exists(os.path.join(d, "probes.csv")):  # a preparation measured at its isotropic state only
        return [prep["n"], "%.4f" % prep["e"], "%.2f" % prep["Zm"], str(prep["Np0"]), "-", "-", "-", "-",
                "%.3f" % prep["Ez_Ex"], "{:,}".format(prep["steps_expansion"] + (prep.get("steps_unloading") or 0)
                                                      + prep["steps_consolidation"]), "-"]
    h = seeds.headlines(d)
    rows = read_probes(os.path.join(d, "probes.csv"), need=["state", "probe", "E", "void_ratio", "state_steps",
                                                            "nu_1", "nu_2", "nu_1_name", "nu_2_name"])
    tab = chain.state_table(rows)
    per_state = {}
    for r in rows:
        per_state.setdefault(r["state"], r)
    steps = [int(float(r["state_steps"])) for s, r in per_state.items() if s != "1"]
    ezex = prep.get("Ez_Ex", h.get("Ez_Ex"))
    prep_steps = None if not prep else (prep["steps_expansion"] + (prep.get("steps_unloading") or 0)
                                        + prep["steps_consolidation"])
    if prep_steps is None and os.path.exists(os.path.join(d, "specimen.json")):  # a study with its specimen's record
        with open(os.path.join(d, "specimen.json")) as f:
            prep_steps = seeds.preparation_steps(json.load(f).get("parameters") or {})
    zeta = h.get("zeta")
    zeta_said = "-" if zeta is None else "%.3f%s" % (zeta, " (h %.3f, v %.3f%s)" % (
        h["zeta_h"], h["zeta_v"], ", at a bound" if h.get("zeta_at_bound") else ""))
    recip = max(seeds.reciprocity_errors(tab)) if tab["state"] else float("nan")
    return [h.get("n") or prep.get("n"), "%.4f" % h["e"], "%.2f" % h["Zm"], str(h.get("rattlers")),
            _states(sorted(per_state, key=int)), "%.4f" % h["e_change"], "%.2f %%" % (100 * recip), zeta_said,
            "-" if ezex is None else "%.3f" % ezex, "-" if prep_steps is None else "{:,}".format(prep_steps),
            _steps(steps)]


def _steps(steps):
    if not steps:
        return "-"
    return "{:,}".format(steps[0]) if len(steps) == 1 else "{:,}-{:,}".format(min(steps), max(steps))


def _states(ids):
    """The states of a row: listed when few, else their count and those missing."""
    if len(ids) <= 9:
        return ", ".join(ids)
    missing = sorted(set(range(1, 40)) - {int(i) for i in ids})
    return "%d of 39%s" % (len(ids), " (not %s)" % ", ".join(map(str, missing)) if missing else "")


def table(data, order, paper):
    out = ["| recipe | clumps | e | Zm | rattlers | states | largest abs(e - e(1)) | largest reciprocity error | "
           "zeta fitted | E_z/E_x restrained | steps to prepare | steps to reach a state |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for label, said in order:
        d = os.path.join(REPO, label) if label.startswith("docs/") else os.path.join(data, label)
        if os.path.isdir(d):
            out.append("| %s | %s |" % (said, " | ".join(str(x) for x in _row(d))))
    out.append(paper)
    return "\n".join(out)


# The rows of the table, in the order of the study's text: directory under --data, and what it is.
ROWS = (("docs/data/clump2-4000-s1", "grown to 100 kPa at 0.01, rotations blocked, w 0.5 (the earlier default; "
                                     "its 4000-clump study)"),
        ("unloaded-20kPa", "the same, unloaded to 20 kPa, then 0.5"),
        ("free-0.5-at-5kPa", "blocked at 0.01 to 5 kPa, then free at 0.5"),
        ("free-0.3-at-5kPa", "blocked at 0.01 to 5 kPa, then free at 0.3"),
        ("free-0.2-at-5kPa", "blocked at 0.01 to 5 kPa, then free at 0.2"),
        ("free-0.25-at-5kPa", "blocked at 0.01 to 5 kPa, then free at 0.25"),
        ("free-0.25-at-5kPa-w0.3", "the same, long axes weighted 0.3"),
        ("default-1000-s1", "**the default**: the same, by run_study.py, all 39 states"),
        ("unloaded-20kPa-free-0.25", "the default unloaded at 0.25 to 20 kPa, then 0.5"))
PAPER = "| paper | 53,004 | 0.636 | | | 39 | approximately constant | | Fig. 13f only | 0.855 | | |"

# clump1's growth friction (mu_prep, also the unloading's), the pentamer recipe otherwise.
ROWS1 = (("default-1000-s1", "mu_prep 0.002 (the pentamer recipe before), by run_study.py, nine states"),
         ("mu-prep-0.005", "mu_prep 0.005"),
         ("mu-prep-0.01", "mu_prep 0.01"),
         ("mu-prep-0.02", "mu_prep 0.02"),
         ("mu-prep-0.01-s2", "mu_prep 0.01, seed 2"))
PAPER1 = "| paper | 53,004 | 0.445 | | | 39 | approximately constant | | | 1.90 | | |"
TABLES = {"clump2": ("clump2-recipes", ROWS, PAPER), "clump1": ("clump1-recipes", ROWS1, PAPER1)}


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--assembly", default="clump2", choices=sorted(TABLES), help="the clump assembly screened")
    p.add_argument("--label", help="name of the row (a directory under --data)")
    p.add_argument("--n", type=int, default=1000, help="number of clumps")
    p.add_argument("--seed", type=int, default=1, help="seed of the random packing")
    p.add_argument("--set", action="append", default=[], help="KEY=VALUE of the recipe or preparation, repeatable")
    p.add_argument("--ids", default="1,9,21,33", help="Table C1 states of the study")
    p.add_argument("--work", default="results/clump2-recipes", help="where specimens and studies are made")
    p.add_argument("--study", help="a study made otherwise, copied in as --label")
    p.add_argument("--data", default="results/clump2-recipes/data",
                   help="the measurements the table is made of (the committed ones: docs/data/clump2-recipes)")
    p.add_argument("--reciprocity", help="with --study and --label: the states (e.g. 17,33) whose probes' compliance is "
                                         "compared with the exact static solve's, into DATA/LABEL/reciprocity.json")
    p.add_argument("--doc", help="rewrite the table of this Markdown file from --data instead")
    o = cli.parse(p)
    if o.doc:
        block, rows, paper = TABLES[o.assembly]
        _bench.replace_block(o.doc, block, table(o.data, rows, paper))
        return
    if not o.label:
        raise cli.InputError("give --label (or --doc)")
    if o.reciprocity:
        with open(os.path.join(o.data, o.label, "reciprocity.json"), "w") as f:
            json.dump(reciprocity_check(o.study, o.reciprocity.split(",")), f, indent=1)
        return
    if o.study:
        collect(o.label, o.study, o.data)
        return
    settings = {}
    for item in o.set:
        k, _, v = item.partition("=")
        settings[k] = value(v)
    prep = prepare(o.assembly, o.label, o.n, o.seed, settings, o.work)
    d = os.path.join(o.work, o.label)
    code = study(os.path.join(d, "specimen.npz"), o.ids, os.path.join(d, "study"))
    prep["study_returncode"] = code
    collect(o.label, os.path.join(d, "study"), o.data, prep)
    print(json.dumps(prep))


if __name__ == "__main__":
    cli.guarded(main)
