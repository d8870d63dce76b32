r"""Headline numbers of one study, and their mean and standard deviation over the seeds of a recipe.

    /usr/bin/python3 -m trueaniso.analysis.seeds STUDY_DIR [STUDY_DIR ...]
    /usr/bin/python3 -m trueaniso.analysis.seeds --label default DIR DIR DIR --label grown-to-target DIR DIR

The first form prints one row per study; the second the table of the manual (docs/studies/specimens.md,
"Spheres: old and new recipes"): one column per label, each number the mean +/- sample standard deviation
over that label's studies (one seed: its value, and the count says so), the paper's value beside.

A study is a run_study.py or run_states.py directory: probes.csv, metadata.json, and where written,
the statics records of the isotropic state and state 21 (statics_isotropic.json or statics_state-1.json,
statics_state-21.json) (Table B1, $E_z/E_x$ with rotations restrained) and specimen.json, the
specimen's own summary (prepare_specimen.py writes it beside the .npz; copied into the study), for
the preparation's steps and wall time. What a study lacks is left out of its column, not guessed.

The headlines (section numbers are the paper's):

- e, Zm and rattlers (particles without a contact) of the specimen at the isotropic 100 kPa;
- Zm's drop over the states (largest less smallest) and e's change along the paths (largest
  ``abs(e - e of state 1)``): the paper's Zm stays in 5.94-5.99 for spheres (Fig. 8a) and its void ratios
  "approximately constant" (section 2.2);
- the moduli $E_i$ that fall by more than 1 % from one state to the next along a path while $\sigma_i$
  rises (path_fidelity.reversals; the paper's $E_i$ follow their stress);
- the largest reciprocity error over the states, ``abs(nu_ij/E_i - nu_ji/E_j)`` over their mean modulus
  (a compliance is symmetric: an elastic response has none, a creeping packing does);
- K and G at the isotropic state (state 1, Eqs. 21-22 inverted), against the paper's Table 2
  quadratics at our Zm (spheres only: the clumps' fits hold on the other side of their vertex);
- zeta fitted on the contrast (section 4.2), the $\nu_{ij}$ RMSE (Eq. 22) and the relative $E_i$ RMSE
  (Eq. 21) at that zeta with the study's own Table 2 fits;
- $E_z/E_x$ at the isotropic state, rotations restrained (the static solve; Table B1's DEM row);
- Table B1: $E_i$ at state 21 over $E_i$ at the isotropic state, rotations restrained, and the
  kinematic (zeta = 1) prediction over the static solve, mean $E_i$, at both states;
- the steps and wall time to prepare the specimen and to reach and probe the states.
"""
import json
import os
import sys

import numpy as np

from . import chain, hyperelastic
from .results import ResultsError, number, read_metadata, read_probes

AXES = "xyz"
PAIRS = ((0, 1), (0, 2), (1, 2))


def reciprocity_errors(tab):
    r"""Per state, the largest of ``abs(nu_ij/E_i - nu_ji/E_j) / mean(abs(nu_ij/E_i), abs(nu_ji/E_j))``
    over the three pairs (``nu[i, j]`` = $\nu_{ij}$: probe on i, strain on j; the compliance
    ``S_ji = -nu_ij/E_i``)."""
    out = []
    for E, nu in zip(tab["E"], tab["nu"]):
        worst = 0.0
        for i, j in PAIRS:
            a, b = nu[i, j] / E[i], nu[j, i] / E[j]
            worst = max(worst, abs(a - b) / (0.5 * (abs(a) + abs(b))))
        out.append(worst)
    return np.array(out)


def _specimen_record(study, meta):
    """The specimen's parameters (preparation steps, wall time, recipe) and summary: specimen.json
    in the study when there, else the summary the study's metadata keeps (no parameters)."""
    path = os.path.join(study, "specimen.json")
    if os.path.exists(path):
        with open(path) as f:
            rec = json.load(f)
        return rec.get("parameters") or {}, rec.get("summary") or meta["specimen"]["summary"]
    return {}, meta["specimen"]["summary"]




# What makes a specimen's recipe, of its preparation's parameters (specimen.json): its seed, size,
# steps and wall time differ between the seeds of one recipe; these do not.
RECIPE_KEYS = ("pressure", "mu_prep", "mu_final", "switch_pressure", "unloaded_from", "phi_cell", "inertial_number",
               "d50", "cu", "time_step", "gain")


def recipe_problem(hs):
    """Why the studies of `hs` (headlines) are not seeds of one recipe, or None: another assembly,
    one seed at one size twice (it would shrink the sd), or a preparation setting that differs
    where both specimens record it (a study without specimen.json is not compared)."""
    kinds = {h["assembly"] for h in hs}
    if len(kinds) > 1:
        return "the studies are of %s: seeds of one recipe are of one assembly" % ", ".join(sorted(map(str, kinds)))
    first = next((h for h in hs if h["recipe_settings"]), None)
    for h in hs:
        if not h["recipe_settings"] or h is first:
            continue
        if h["recipe"] != first["recipe"]:
            return "%s is of the recipe %r, %s of %r" % (h["study"], h["recipe"], first["study"], first["recipe"])
        for k in RECIPE_KEYS:
            a, b = first["recipe_settings"].get(k), h["recipe_settings"].get(k)
            if a is not None and b is not None and a != b:
                return "%s was prepared with %s %s, %s with %s: not one recipe" % (h["study"], k, b, first["study"], a)
    seen = {}
    for h in hs:
        key = (h["n"], h["seed"])
        if key in seen:
            return "%s and %s are both seed %s of %s particles: one specimen counted twice" % (
                seen[key], h["study"], h["seed"], h["n"])
        seen[key] = h["study"]
    return None


def preparation_steps(params):
    """Every step of a preparation its parameters record (expansion, unloading, consolidation), or None."""
    keys = [k for k in params if k.startswith("steps_")]
    return sum(int(params[k]) for k in keys) if keys else None


def headlines(study):
    """The headline numbers of one study directory (module doc), a dict; None for what it lacks."""
    meta = read_metadata(study, required=True)
    spec = meta.get("specimen") or {}
    summary = spec.get("summary") or {}
    lacks = [k for k in ("n", "void_ratio", "Zm") if k not in summary] + ([] if spec.get("material") else ["material"])
    if lacks:
        raise ResultsError("%s: its metadata.json records no specimen %s (a specimen saved without its summary, "
                           "or a study written by hand)" % (study, ", ".join(lacks)))
    csv_path = os.path.join(study, "probes.csv")
    rows = read_probes(csv_path, need=["state", "probe", "E", "Zm", "void_ratio", "rotations", "state_steps",
                                       "probe_steps", "nu_1", "nu_2", "nu_1_name", "nu_2_name"])
    rows = [r for r in rows if r["rotations"] == "free"] or rows
    params, summary = _specimen_record(study, meta)
    tab = chain.state_table(rows)
    if not tab["state"]:
        raise ResultsError("%s: no state probed on x, y and z" % csv_path)
    ref = tab["state"].index("1") if "1" in tab["state"] else 0
    per_state = {}
    for r in rows:
        per_state.setdefault(r["state"], r)
    e = np.array([number(r, "void_ratio", csv_path) for r in per_state.values()])
    zm = np.array([number(r, "Zm", csv_path) for r in per_state.values()])
    e1 = number(per_state[tab["state"][ref]], "void_ratio", csv_path)
    mat = meta["specimen"]["material"]
    out = dict(study=study, n=summary.get("n"), seed=meta["specimen"].get("seed"), states=len(tab["state"]),
               assembly=(meta.get("fingerprint") or {}).get("assembly", "sphere"),
               recipe=params.get("recipe", "default" if params else None),
               recipe_settings={k: params[k] for k in RECIPE_KEYS if k in params},
               e=summary["void_ratio"], Zm=summary["Zm"], rattlers=summary.get("Np0"),
               Zm_drop=float(zm.max() - zm.min()), e_change=float(np.max(np.abs(e - e1))),
               reciprocity=float(np.max(reciprocity_errors(tab))))
    iso = hyperelastic.scalar_moduli(tab["E"][ref], tab["nu"][ref])
    out.update(K_iso=iso["K"] / 1e6, G_iso=iso["G"] / 1e6, Zm_iso=float(tab["Zm"][ref]))
    from . import path_fidelity, zeta_contrast
    walk = read_probes(csv_path, need=zeta_contrast.NEEDED + ["b", "sigma_z_goal"])
    walk = [r for r in walk if r["rotations"] == rows[0]["rotations"]]
    rev = path_fidelity.reversals(walk, path=csv_path)
    out["reversals"] = len([r for r in rev if r[4] < 0.99 * r[3]])
    out.update(zeta=None, zeta_h=None, zeta_v=None, zeta_at_bound=None, nu_rmse=None, E_rmse=None)
    if len(tab["state"]) >= 3 and hyperelastic.quadratic_fittable(tab["Zm"]):
        parts = chain.fabric_parts(csv_path, tab, mat["shear_modulus"], mat["poisson"], rows[0]["rotations"])
        contrast = chain.fit_contrast(tab["E"], *parts)
        pred = chain.predictions(tab, chain.table2(tab),
                                 chain.micromechanical_a2(parts, contrast["zeta_h"], contrast["zeta_v"]))
        out.update(zeta=contrast["zeta"], zeta_h=contrast["zeta_h"], zeta_v=contrast["zeta_v"],
                   zeta_at_bound=bool(contrast["at_bound"]), nu_rmse=pred["nu_rmse"], E_rmse=pred["E_rel_rmse"])
    from .report import b1_records  # the isotropic state's record under either name (run_study.py's, --statics')
    found = b1_records(study)
    s1, s21 = found.get("isotropic"), found.get("21")
    out["Ez_Ex"] = None
    out["B1_ratio"] = out["B1_pred_dem_iso"] = out["B1_pred_dem_21"] = None
    if s1:
        E = s1["E_blocked"]
        out["Ez_Ex"] = E[2] / (0.5 * (E[0] + E[1]))
        out["B1_pred_dem_iso"] = float(np.mean(s1["E_kinematic"]) / np.mean(E))
    if s1 and s21:
        out["B1_ratio"] = [a / b for a, b in zip(s21["E_blocked"], s1["E_blocked"])]
        out["B1_pred_dem_21"] = float(np.mean(s21["E_kinematic"]) / np.mean(s21["E_blocked"]))
    steps = sum(number(r, "probe_steps", csv_path) for r in rows) + \
        sum(number(r, "state_steps", csv_path) for r in per_state.values())
    wall = sum(number(r, "probe_wall_time", csv_path) for r in rows if r.get("probe_wall_time")) + \
        sum(number(r, "state_wall_time", csv_path) for r in per_state.values() if r.get("state_wall_time"))
    out.update(prep_steps=preparation_steps(params), prep_wall=params.get("wall_time"),
               study_steps=int(steps), study_wall=float(wall))
    return out


def paper_values(assembly):
    """The paper's value of each headline where it gives one (chain.PAPER, section 2.1, Fig. 8a)."""
    p = chain.PAPER[assembly]
    b1 = p["B1"]
    ratio = [a / b for a, b in zip(b1["21"]["dem"], b1["isotropic"]["dem"])]
    out = dict(e=chain.PAPER_VOID_RATIO[assembly], nu_rmse=p["nu_rmse"], B1_ratio=ratio,
               Ez_Ex=b1["isotropic"]["dem"][2] / b1["isotropic"]["dem"][0],
               B1_pred_dem_iso=float(np.mean(b1["isotropic"]["pred"]) / np.mean(b1["isotropic"]["dem"])),
               B1_pred_dem_21=float(np.mean(b1["21"]["pred"]) / np.mean(b1["21"]["dem"])),
               e_change="approximately constant")
    if assembly == "spheres":
        out.update(Zm="5.94-5.99", Zm_drop="<= 0.05 (5.94-5.99 over the states)", zeta=chain.PAPER_ZETA)
    return out


def paper_K_G(assembly, zm):
    """K and G (MPa) of the paper's Table 2 quadratics at Zm `zm`, where its fits hold (spheres)."""
    if assembly != "spheres":
        return None
    p = chain.PAPER[assembly]
    return float(np.polyval(p["K"], zm)), float(np.polyval(p["G"], zm))


def mean_sd(values, fmt="%.3f", count=False):
    """'m +/- s' over the values (sample sd, n - 1); one value alone as it is; '-' for none.
    `count`: followed by how many values it is of, '(3 seeds)', since a study may lack a value that
    the others have (Table B1 of a study not solved at state 21)."""
    v = [x for x in values if x is not None]
    if not v:
        return "-"
    text = fmt % v[0] if len(v) == 1 else \
        ("%s +/- %s" % (fmt, fmt)) % (float(np.mean(v)), float(np.std(v, ddof=1)))
    return text + (" (%d seed%s)" % (len(v), "" if len(v) == 1 else "s") if count else "")


# (label, key, format, scale): the rows of the table, in the order.
ROWS = (("e", "e", "%.4f"), ("Zm", "Zm", "%.3f"), ("rattlers (no contact)", "rattlers", "%.0f"),
        ("Zm drop over the states", "Zm_drop", "%.3f"), ("largest \\|e - e(state 1)\\| along the paths", "e_change", "%.4f"),
        ("largest reciprocity error", "reciprocity", "%.4f"),
        ("E_i falling by > 1 % while sigma_i rises along a path", "reversals", "%.1f"), ("K at the isotropic state (MPa)", "K_iso", "%.1f"),
        ("G at the isotropic state (MPa)", "G_iso", "%.1f"), ("zeta fitted (one zeta)", "zeta", "%.3f"),
        ("zeta_h", "zeta_h", "%.3f"), ("zeta_v", "zeta_v", "%.3f"), ("nu RMSE at the fitted zeta", "nu_rmse", "%.4f"),
        ("E relative RMSE at the fitted zeta", "E_rmse", "%.4f"), ("E_z/E_x, isotropic, restrained", "Ez_Ex", "%.3f"),
        ("Table B1: E_x at 21 / isotropic, restrained", ("B1_ratio", 0), "%.3f"),
        ("Table B1: E_y at 21 / isotropic", ("B1_ratio", 1), "%.3f"),
        ("Table B1: E_z at 21 / isotropic", ("B1_ratio", 2), "%.3f"),
        ("Table B1: predicted (zeta = 1) / DEM, isotropic", "B1_pred_dem_iso", "%.3f"),
        ("Table B1: predicted (zeta = 1) / DEM, state 21", "B1_pred_dem_21", "%.3f"),
        ("steps to prepare", "prep_steps", "%.0f"), ("wall time to prepare (s)", "prep_wall", "%.0f"),
        ("steps of the states and probes", "study_steps", "%.0f"), ("wall time of the states and probes (s)",
                                                                    "study_wall", "%.0f"))


def _value(h, key):
    if isinstance(key, tuple):
        v = h.get(key[0])
        return None if v is None else v[key[1]]
    return h.get(key)


def _paper_cell(paper, key, fmt):
    v = _value(paper, key)
    if v is None:
        return ""
    return v if isinstance(v, str) else fmt % v


# The report's headline table (report.py, its first section): the numbers the paper states for an
# assembly and that a reader compares first; the preparation's bookkeeping stays in the manual's table.
HEADLINE_KEYS = ("e", "Zm", "K_iso", "G_iso", "zeta", "zeta_h", "zeta_v", "nu_rmse", "E_rmse", "Ez_Ex",
                 ("B1_ratio", 0), ("B1_ratio", 1), ("B1_ratio", 2), "B1_pred_dem_iso", "B1_pred_dem_21",
                 "Zm_drop", "e_change", "reciprocity")
HEADLINE_ROWS = tuple(sorted((r for r in ROWS if r[1] in HEADLINE_KEYS), key=lambda r: HEADLINE_KEYS.index(r[1])))


def table(groups, assembly, rows=ROWS, counts=False):
    """Markdown: one column per (label, [headlines of its studies]), mean +/- sd, the paper's beside.
    `rows`: which of ROWS (HEADLINE_ROWS: the report's); `counts`: each cell says how many seeds it
    is of (mean_sd)."""
    paper = paper_values(assembly)
    head = "| | %s | paper |" % " | ".join("%s (%s)" % (label, _seeds_said(hs)) if label else _seeds_said(hs)
                                          for label, hs in groups)
    out = [head, "|---|%s---|" % ("---|" * len(groups))]
    for label, key, fmt in rows:
        cells = [mean_sd([_value(h, key) for h in hs], fmt, counts) for _, hs in groups]
        if all(c == "-" for c in cells):
            continue
        pc = _paper_cell(paper, key, fmt)
        if key in ("K_iso", "G_iso") and assembly == "spheres":
            zm = [h["Zm_iso"] for _, hs in groups for h in hs]
            kg = paper_K_G(assembly, float(np.mean(zm)))
            pc = "%.1f (Table 2 at Zm %.2f)" % (kg[0 if key == "K_iso" else 1], float(np.mean(zm)))
        out.append("| %s | %s | %s |" % (label, " | ".join(cells), pc))
    return "\n".join(out)


def _seeds_said(hs):
    sizes = sorted({h["n"] for h in hs if h["n"]})
    seeds = sorted({h["seed"] for h in hs if h["seed"] is not None})
    return "%s, seed%s %s" % ("/".join(str(n) for n in sizes) or "?", "" if len(seeds) == 1 else "s",
                              ", ".join(str(s) for s in seeds))


def write_block(path, name, body):
    """`body` between the <!-- NAME:begin --> and <!-- NAME:end --> lines of the Markdown file `path`
    (which must hold them), written atomically."""
    begin, end = "<!-- %s:begin -->" % name, "<!-- %s:end -->" % name
    try:
        with open(path) as f:
            text = f.read()
    except OSError as exc:
        raise ResultsError("%s: cannot read it (%s)" % (path, exc.strerror or exc)) from None
    if begin not in text or end not in text:
        raise ResultsError("%s has no %s ... %s block" % (path, begin, end))
    head, rest = text.split(begin, 1)
    tail = rest.split(end, 1)[1]
    # The new file replaces the old by a rename, which a read-only file does not stop (nor, for root,
    # its permissions): its write bits are asked first.
    import stat
    if not os.stat(path).st_mode & (stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH) or not os.access(path, os.W_OK):
        raise ResultsError("%s is read-only: not rewritten" % path)
    from trueaniso import atomic
    try:
        with atomic.atomic_open(path) as f:
            f.write(head + begin + "\n" + body.rstrip("\n") + "\n" + end + tail)
    except OSError as exc:
        raise ResultsError("%s: cannot write it (%s)" % (path, exc.strerror or exc)) from None


def publish(text, doc=None, block=None):
    """A tool's table: written between the markers of `block` in the page `doc` (write_block), and said
    so, when a page is given; else printed."""
    if doc:
        write_block(doc, block, text)
        print("wrote the %s block of %s" % (block, doc))
    else:
        print(text)


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        print("\nOptions: --assembly A (default: the first study's), --label NAME (starts a column), "
              "--doc FILE --block NAME (the table written between that block's markers in FILE).")
        return 0 if argv else 2
    assembly = doc = block = None
    groups = []
    try:
        it = iter(argv)
        for a in it:
            if a in ("--assembly", "--label", "--doc", "--block"):
                value = next(it, None)
                if value is None:
                    raise ResultsError("%s needs a value" % a)
                if a == "--assembly":
                    assembly = {"sphere": "spheres"}.get(value, value)
                elif a == "--label":
                    groups.append((value, []))
                elif a == "--doc":
                    doc = value
                else:
                    block = value
                continue
            if not groups:
                groups.append(("", []))
            groups[-1][1].append(headlines(a))
        if not groups or not any(hs for _, hs in groups):
            raise ResultsError("no study directory given")
        if assembly is None:
            from .report import study_assembly
            assembly = study_assembly(next(hs for _, hs in groups if hs)[0]["study"]) or "spheres"
        if assembly not in chain.PAPER:
            raise ResultsError("--assembly must be one of %s" % ", ".join(chain.PAPER))
        if len(groups) == 1 and groups[0][0] == "" and not doc:
            for h in groups[0][1]:
                print(json.dumps(h, default=float))
            return 0
        text = table(groups, assembly)
        if doc:
            if not block:
                raise ResultsError("--doc needs --block NAME")
        publish(text, doc, block)
    except ResultsError as exc:
        sys.stderr.write("error: %s\n" % exc)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
