r"""Path fidelity of a Table C1 study: how far Zm (and Zm with a gap tolerance) moves over
the states, and where the stiffness trend reverses.

A reversal is a step along one loading path where a modulus $E_i$ falls while its own stress
$\sigma_i$ rises (by more than `threshold`, 0.5 kPa: a stress that stays put, e.g. $\sigma_x$ on a b = 0
path, is no trend). The paths are the constant-b paths of triaxial.paths, each walked from the
isotropic state (sigma_z = p) outwards by distance from it, as in docs/studies/table-c1-4000.md.

    /usr/bin/python3 -m trueaniso.analysis.path_fidelity results/x/probes.csv [more.csv ...]
    /usr/bin/python3 -m trueaniso.analysis.path_fidelity --gaps 1e-5,1e-4,1e-3,1e-2 results/x [more study dirs ...]
    /usr/bin/python3 -m trueaniso.analysis.path_fidelity --table results/x [more study dirs ...]

The second form recounts Zm with other gap tolerances on the study's state checkpoints
(states/<id>.npz), which the table's single Zm_gap1e-3 column cannot give. The third prints the
path-fidelity table (markdown), one row per study: variant (spheres, seed, rolling
resistance), Zm and Zm_gap1e-3 ranges, reversals, the fitted zeta and how the per-state zeta follows
Zm, E at the isotropic state, and the cost (steps, wall time).
"""
import sys

from .results import ResultsError, number, read_metadata, read_probes
from trueaniso import triaxial

NORMAL = ("x", "y", "z")


def _states(rows, path):
    """{state: dict(b, sigma_z_goal, sigma_i, E_i)} from the normal-probe rows."""
    out = {}
    for r in rows:
        if r["probe"] not in NORMAL:
            continue
        s = out.setdefault(r["state"], dict(b=number(r, "b", path), sz=number(r, "sigma_z_goal", path), E={},
                                            sigma={a: number(r, "sigma_" + a, path) for a in NORMAL}, row=r))
        s["E"][r["probe"]] = number(r, "E", path)
    return out


def reversals(rows, threshold=500.0, path="probe table"):
    """[(state_from, state_to, axis, E_from, E_to, sigma_from, sigma_to)] of every reversal."""
    st = _states(rows, path)
    groups = triaxial.paths([(k, v["b"], v["sz"]) for k, v in st.items()])
    iso = [s for key, ss in groups.items() if key[1] == 0 for s in ss]
    found = []
    for key, states in sorted(groups.items(), key=lambda kv: (kv[0][1] != 0, kv[0])):
        if key[1] == 0:
            continue
        walk = [s[0] for s in iso[:1] + states]
        for a_id, b_id in zip(walk, walk[1:]):
            a, b = st[a_id], st[b_id]
            for ax in NORMAL:
                if ax in a["E"] and ax in b["E"] and b["sigma"][ax] - a["sigma"][ax] > threshold \
                        and b["E"][ax] < a["E"][ax]:
                    found.append((a_id, b_id, ax, a["E"][ax], b["E"][ax], a["sigma"][ax], b["sigma"][ax]))
    return found


def summary(rows, path="probe table"):
    """Zm and Zm_gap ranges over the states, the reversals, and the states' wall time."""
    st = _states(rows, path)
    out = dict(states=len(st), reversals=len(reversals(rows, path=path)))
    for col in ("Zm", "Zm_gap1e-3"):
        if all(col in s["row"] for s in st.values()):
            vals = [number(s["row"], col, path) for s in st.values()]
            out[col] = (min(vals), max(vals))
    out["wall_time"] = sum(number(r, "probe_wall_time", path) for r in rows) + \
        sum(number(s["row"], "state_wall_time", path) for s in st.values())
    return out


def _say_note(rows):
    """Rows left out of the table (a NaN cell, a torn last row), said on stderr as the report says them."""
    if rows.note:
        sys.stderr.write("note: %s\n" % rows.note)
    return rows


def study_row(study):
    """One row of the path-fidelity table from a study directory (metadata.json, probes.csv)."""
    import os
    import numpy as np
    from . import chain, zeta_contrast
    meta = read_metadata(study, required=True)
    fp, spec = meta["fingerprint"], meta["specimen"]
    csv_path = os.path.join(study, "probes.csv")
    rows = read_probes(csv_path, need=zeta_contrast.NEEDED + ["b", "sigma_z_goal", "Zm", "probe_steps", "state_steps"])
    _say_note(rows)
    s = summary(rows, csv_path)
    rev = reversals(rows, path=csv_path)
    strong = [r for r in rev if r[4] < 0.99 * r[3]]
    worst = min((r[4] / r[3] - 1 for r in rev), default=0.0)
    mat = spec["material"]
    fit = zeta_contrast.fit(csv_path, mat["shear_modulus"], mat["poisson"])
    tab = chain.state_table(rows)
    ref = tab["state"].index("1") if "1" in tab["state"] else 0
    parts = chain.fabric_parts(csv_path, tab, mat["shear_modulus"], mat["poisson"], rows[0]["rotations"])
    trend = chain.zeta_trend(tab, chain.zeta_per_state(tab, parts, ref))
    st = _states(rows, csv_path)
    steps = sum(number(r, "probe_steps", csv_path) for r in rows) + \
        sum(number(v["row"], "state_steps", csv_path) for v in st.values())
    n = spec["summary"]["n"]
    roll = fp["state"].get("rolling_stiffness", 0.0), fp["state"].get("rolling_friction", 0.0)
    return dict(study=study, n=n, seed=spec["seed"], rolling=roll, states=s["states"], Zm=s["Zm"],
                Zm_gap=s.get("Zm_gap1e-3"), reversals=len(rev), strong=len(strong), worst=worst,
                zeta=fit and fit["zeta"], zeta_se=fit and fit["se"], rho=trend["rho"], zeta_high=trend["high"],
                zeta_low=trend["low"], E_iso=float(np.mean(tab["E"][ref])) if len(tab["state"]) else None,
                steps=steps, wall=s["wall_time"], threads=fp.get("threads"))


def markdown_table(summaries):
    """The path-fidelity table: one line per study_row."""
    f = lambda x, fmt: "-" if x is None else fmt % x  # noqa: E731
    out = ["| spheres | seed | rolling (beta, eta_r) | states | Zm (drop) | Zm_gap1e-3 | reversals (> 1 %; worst) "
           "| zeta fitted | zeta per state: rho with Zm; high-Zm, low-Zm mean | E iso (MPa) | steps | wall (threads) |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in summaries:
        roll = "off" if r["rolling"][0] == 0 else "%g, %g" % r["rolling"]
        out.append("| %d | %s | %s | %d | %.3f-%.3f (%.3f) | %s | %d (%d; %+.1f %%) | %s | %s; %s, %s | %s | %.3g | %.0f s (%s) |"
                   % (r["n"], r["seed"], roll, r["states"], r["Zm"][0], r["Zm"][1], r["Zm"][1] - r["Zm"][0],
                      "-" if r["Zm_gap"] is None else "%.3f-%.3f" % r["Zm_gap"], r["reversals"], r["strong"],
                      100 * r["worst"], "-" if r["zeta"] is None else "%.3f +/- %.3f" % (r["zeta"], r["zeta_se"]),
                      f(r["rho"], "%.2f"), f(r["zeta_high"], "%.2f"), f(r["zeta_low"], "%.2f"),
                      f(r["E_iso"] and r["E_iso"] / 1e6, "%.1f"), r["steps"], r["wall"], r["threads"]))
    return "\n".join(out)


def gap_scan(study, tolerances):
    """{state id: [Zm, Zm with each tolerance]} from the checkpoints of a study directory."""
    import glob
    import os
    from trueaniso import engines, specimen_file
    out = {}
    for f in glob.glob(os.path.join(study, "states", "*.npz")):
        s, _ = specimen_file.load(f)
        out[os.path.basename(f)[:-4]] = [engines.coordination(s)["Zm"]] + \
            [engines.coordination_gap(s, t)["Zm"] for t in tolerances]
    if not out:
        raise ResultsError("%s has no state checkpoints (states/*.npz)" % study)
    return out


def main(argv):
    if not argv:
        sys.stderr.write("usage: python3 -m trueaniso.analysis.path_fidelity PROBES.csv [...] | --gaps TOLS STUDY_DIR [...] "
                         "| --table STUDY_DIR [...]\n")
        return 2
    if argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0
    if argv[0] == "--table":
        if len(argv) < 2:
            sys.stderr.write("error: --table needs one or more study directories\n")
            return 2
        try:
            print(markdown_table([study_row(d) for d in argv[1:]]))
        except ResultsError as exc:
            sys.stderr.write("error: %s\n" % exc)
            return 2
        return 0
    if argv[0] == "--gaps":
        try:
            tols = [float(t) for t in argv[1].split(",")]
        except (IndexError, ValueError):
            tols = []
        if not tols or not all(0 < t < 1 for t in tols) or len(argv) < 3:
            sys.stderr.write("error: --gaps takes gap tolerances in (0, 1), comma separated (e.g. 1e-4,1e-3), "
                             "then one or more study directories\n")
            return 2
        for d in argv[2:]:
            try:
                scan = gap_scan(d, tols)
            except ResultsError as exc:
                sys.stderr.write("error: %s\n" % exc)
                return 2
            from trueaniso.fabric import gap_column
            for k, name in enumerate(["Zm"] + [gap_column(t) for t in tols]):
                v = [z[k] for z in scan.values()]
                print("%s: %-12s %.3f-%.3f over %d states" % (d, name, min(v), max(v), len(v)))
        return 0
    for p in argv:
        try:
            s = summary(_say_note(read_probes(p, need=("state", "probe", "E", "b", "sigma_z_goal", "Zm"))), p)
        except ResultsError as exc:
            sys.stderr.write("error: %s\n" % exc)
            return 2
        zr = "Zm %.3f-%.3f" % s["Zm"]
        gr = ("  Zm_gap1e-3 %.3f-%.3f" % s["Zm_gap1e-3"]) if "Zm_gap1e-3" in s else ""
        print("%s: %d state%s  %s%s  reversals %d  wall %.0f s" % (p, s["states"], "" if s["states"] == 1 else "s", zr, gr, s["reversals"],
                                                                  s["wall_time"]))
    return 0


if __name__ == "__main__":
    from trueaniso import cli
    cli.tool(lambda: main(sys.argv[1:]))
