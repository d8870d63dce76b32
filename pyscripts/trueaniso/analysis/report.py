"""report.md with its figures from a study's results: every table and figure beside the paper's.

Run as a tool::

    /usr/bin/python3 -m trueaniso.analysis.report results/default            # writes results/default/report/
    /usr/bin/python3 -m trueaniso.analysis.report docs/data/table-c1-spheres-4000.csv --out docs/report-spheres

A results directory (of run_study.py or run_states.py) or a probe table alone. The material
(particle shear modulus and Poisson's ratio) comes from the study's metadata.json, else from
--shear-modulus/--poisson; either way it is checked against the micromechanical moduli the table
itself holds (trueaniso.analysis.zeta_contrast.check_rebuild), so a wrong one is an error, not a wrong report.
The chain is pyscripts/trueaniso/analysis/chain.py; this module only lays it out. Figures and the report are written
atomically; a rerun replaces them.
"""
import argparse
import json
import os
import sys
import time

import numpy as np

from . import b1_checks, chain, figures, hyperelastic, zeta_contrast
from .results import ResultsError, read_metadata, read_probes, said, table_path
from trueaniso import validate  # noqa: E402 (results put pyscripts/ on the path)
from trueaniso.options import flag  # noqa: E402

__all__ = ["build"]

AXES = "xyz"
DEFAULT_MATERIAL = dict(shear_modulus=18e9, poisson=0.15)  # the paper's particles (section 2.1)

# The departures from the paper and why (docs/equations.md, docs/fabric.md, docs/statics.md).
DEPARTURES = [
    ("Boundary", "a periodic cell, stress-controlled by the cell's strain rate",
     "the paper's box has frictionless rigid walls; a periodic cell has no wall layer, so every particle is "
     "bulk (docs/cell.md)"),
    ("Eq. 36 (Nc/V)", "read with the mean r^3 over particles", "as printed it divides by the sum of r^3; the "
     "mean gives Zm Np/(2V), which exceeds the counted Nc/V by Zm/Z (docs/fabric.md). Nc/V only scales C, so "
     "a_i^2, nu_ij and the contrast zeta do not depend on it"),
    ("zeta in C", "directional form C_ik = A_n + sqrt(zeta_i zeta_k) A_s", "the paper names zeta_h and zeta_v "
     "but not how they combine off the diagonal; the geometric mean keeps C symmetric (docs/fabric.md)"),
    ("K and G", "from E_i and nu_ij: E0 = mean E_i/a_i^4, nu0 = mean nu_ij a_j^2/a_i^2", "Eqs. 21-22 inverted "
     "with a_i^2 of Eq. 25; the paper does not say how K and G were taken (pyscripts/trueaniso/analysis/hyperelastic.py)"),
    ("Eq. 42", "nu_zy = (C23 C11 - C12 C13)/(C11 C22 - C12^2)", "the printed last line is a misprint (label "
     "nu_xy, numerator C12 C23): tested against the numerical inverse (docs/fabric.md)"),
    ("Appendix A7-A9", "implemented as printed, and reported beside the derived shear modulus",
     "C44 = (C2323 + C3232)/2 omits C2332 + C3223 and, with engineering shear strains, doubles G: on FCC "
     "763.97 MPa printed against 390.2 MPa for the true C44 (docs/statics.md section 5); E and nu use the "
     "normal block only and are unaffected"),
    ("zeta range", "[0, 5]", "the paper's zeta is a reduction in [0, 1]; a fit with rotations blocked lands at "
     "1.01, which [0, 1] would clip, so the search goes to 5 (docs/equations.md). A fit that stops at 0 or 5 is "
     "reported as at a bound: not determined by the states"),
    ("Preparation friction", "0.015 (spheres), 0.002 (clump1), 0.01 (clump2) while the packing forms, then 0.5",
     "the paper's Table 1 gives 0.5 for consolidation and no other friction; consolidated at 0.5 throughout, "
     "spheres settle at e ~ 0.74 and Zm ~ 4.4. A lower friction while the radii grow is how ours reach the "
     "paper's e and Zm together; friction is 0.5 from the consolidated state on (docs/specimens.md)"),
    ("Table B1 Sphere*", "406.7 MPa closed form for the simple cubic packing at 100 kPa",
     "the paper prints 386.1-386.7 MPa for its equal-sized cubic packing; its own Eqs. 5-6 give "
     "E = (12 E*^2 sigma)^(1/3)/2 = 406.7 MPa at 100 kPa (docs/triaxial.md). Unexplained: a 5 % gap that "
     "neither the force-dependent stiffness nor the Love-Weber stress accounts for"),
]


_plt = figures._plt  # one home for matplotlib's backend choice


def _save(fig, path):
    """figures._save (atomic), then the figure closed; returns the file's name for the report."""
    figures._save(fig, path)
    _plt().close(fig)
    return os.path.basename(path)


def _identity(ax, lo, hi):
    ax.plot([lo, hi], [lo, hi], "k--", lw=0.8, label="$y = x$")


def _tex(text):
    """A report's plain name of zeta (zeta_h, zeta_v, zeta) in mathtext, for a figure's text."""
    return (text.replace("zeta_h", "@h").replace("zeta_v", "@v").replace("zeta", r"$\zeta$")
            .replace("@h", r"$\zeta_h$").replace("@v", r"$\zeta_v$"))


def _state_order(states):
    """State ids in Table C1's order (numbers first, by value), with their positions in `states`."""
    key = lambda sid: (0, int(sid), "") if sid.isdigit() else (1, 0, sid)  # noqa: E731
    return sorted(range(len(states)), key=lambda k: key(states[k]))


FIG13_MARKERS = "os^"  # a_x^2, a_y^2, a_z^2
FIG13_LEGEND_COLOUR = "0.3"  # a grey: no colour of the Zm map
FIG13_SIZE = 18  # points^2, as scatter takes it; a legend's marker takes its square root


def fig13(tab, a2_by_zeta, path, who=None):
    """Micromechanical against DEM a_i^2 at each zeta, coloured by Zm (the paper's Fig. 13)."""
    plt = _plt()
    fig, axes = plt.subplots(1, len(a2_by_zeta), figsize=(4.2 * len(a2_by_zeta) + 1.0, 4.4), squeeze=False,
                             layout="constrained")
    lo = min(tab["a2_dem"].min(), min(a.min() for _, a in a2_by_zeta)) - 0.01
    hi = max(tab["a2_dem"].max(), max(a.max() for _, a in a2_by_zeta)) + 0.01
    from matplotlib.lines import Line2D  # after _plt(), which chooses the backend
    for ax, (label, a2) in zip(axes[0], a2_by_zeta):
        for i, mark in zip(range(3), FIG13_MARKERS):
            sc = ax.scatter(tab["a2_dem"][:, i], a2[:, i], c=tab["Zm"], marker=mark, s=FIG13_SIZE, cmap="viridis")
        _identity(ax, lo, hi)
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        ax.set_title(_tex(label), fontsize=9)
        ax.set_xlabel("DEM $a_i^2$, Eq. 25 (-)")
        ax.set_ylabel("micromechanical $a_i^2$ (-)")
    # Colour is Zm (the colour bar), so the axis is told by its marker alone: a scatter's own
    # legend entry would take one Zm's colour for all three and suggest that Zm. One legend for the
    # panels, right of the last, off the data.
    figures.legend_outside(axes[0][-1], handles=[Line2D([], [], ls="none", marker=mark, markersize=np.sqrt(FIG13_SIZE),
                                                        color=FIG13_LEGEND_COLOUR, label="$a_%s^2$" % a)
                                                 for a, mark in zip(AXES, FIG13_MARKERS)]
                           + axes[0][-1].get_legend_handles_labels()[0])
    fig.colorbar(sc, ax=axes[0].tolist(), label=figures.ZM_LABEL)
    figures.entitle(fig, r"Fig. 13: does the micromechanical $a_i^2$ (Eq. 37) follow the DEM's at each $\zeta$?", who)
    return _save(fig, path)


NU_PAIRS = (((2, 0), (0, 2)), ((1, 2), (2, 1)), ((0, 1), (1, 0)))  # the paper's Fig. 15 panels (a)-(c)


def fig14_15(tab, pred, path_E, path_nu, assembly="spheres", path_parity=None, who=None):
    r"""Fig. 14 ($E_i$, predicted against DEM) and Fig. 15 as the paper draws it: $\nu_{ij}$ of DEM and
    predicted against the state ID, one panel per pair; the parity plot of $\nu_{ij}$ beside it."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.6, 4.6))
    for i, mark in zip(range(3), "os^"):
        ax.scatter(tab["E"][:, i] / 1e6, pred["E"][:, i] / 1e6, marker=mark, s=16, label="$E_%s$" % AXES[i])
    lo, hi = np.nanmin(tab["E"]) / 1e6 * 0.97, np.nanmax(tab["E"]) / 1e6 * 1.03
    _identity(ax, lo, hi)
    ax.set_xlabel("DEM $E_i$ (MPa)")
    ax.set_ylabel("predicted $E_i$, Eq. 21 (MPa)")
    figures.entitle(fig, "Fig. 14: does Eq. 21 (Table 2 fits, fitted $\\zeta$) predict the DEM $E_i$?", who,
                    "relative RMSE %.4f" % pred["E_rel_rmse"])
    figures.legend_outside(ax)
    fig.tight_layout()
    names = [_save(fig, path_E)]
    order = _state_order(tab["state"])
    numbered = all(s.isdigit() for s in tab["state"])  # Table C1's ids: a missing state leaves its gap
    x = np.array([int(tab["state"][k]) for k in order]) if numbered else np.arange(len(order))
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.6), layout="constrained")
    for ax, pair in zip(axes, NU_PAIRS):
        for (i, j), mark in zip(pair, "os"):
            name = r"\nu_{%s%s}" % (AXES[i], AXES[j])
            line, = ax.plot(x, tab["nu"][order, i, j], mark, ms=4, mfc="none", label="DEM $%s$" % name)
            ax.plot(x, pred["nu"][order, i, j], "-", color=line.get_color(), lw=1, label="predicted $%s$" % name)
        if not numbered:
            ax.set_xticks(x)
            ax.set_xticklabels([tab["state"][k] for k in order], fontsize=7, rotation=90)
        ax.set_xlabel("state ID, Table C1 (-)")
        ax.set_ylabel(r"$%s$, $%s$ (-)" % tuple(r"\nu_{%s%s}" % (AXES[i], AXES[j]) for i, j in pair))
        figures.legend_above(ax)
    rmse = "RMSE %.4f (paper, %s: %.3f)" % (pred["nu_rmse"], assembly, chain.PAPER[assembly]["nu_rmse"])
    figures.entitle(fig, r"Fig. 15: does Eq. 22 predict the DEM's Poisson's ratios $\nu_{ij}$ state by state?",
                    who, rmse)
    names.append(_save(fig, path_nu))
    if path_parity:
        fig, ax = plt.subplots(figsize=(5.6, 4.6))
        for i in range(3):
            for j in range(3):
                if i != j:
                    ax.scatter(tab["nu"][:, i, j], pred["nu"][:, i, j], s=12,
                               label=r"$\nu_{%s%s}$" % (AXES[i], AXES[j]))
        off = ~np.eye(3, dtype=bool)
        lo, hi = tab["nu"][:, off].min() * 0.95, tab["nu"][:, off].max() * 1.05
        _identity(ax, lo, hi)
        ax.set_xlabel(r"DEM $\nu_{ij}$ (-)")
        ax.set_ylabel(r"predicted $\nu_{ij}$, Eq. 22 (-)")
        figures.entitle(fig, r"Fig. 15: does Eq. 22 predict the DEM's $\nu_{ij}$?", who, rmse)
        figures.legend_outside(ax)
        fig.tight_layout()
        names.append(_save(fig, path_parity))
    return names


def fig4a(exp, path, label=r"$E_i/E_j$, $i \neq j$", who=None, panel="4a"):
    r"""Fig. 4: $E_i/E_j$ against $\sigma_i/\sigma_j$ on log axes, with the power law fitted. The ratios
    span about 0.5-2, where a log axis's own ticks (at powers of ten) label one tick: plain ticks."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.8, 4.4))
    x, y = np.exp(exp["log_sigma_ratio"]), np.exp(exp["log_E_ratio"])
    ax.loglog(x, y, "o", ms=3, alpha=0.7, label=label)
    xs = np.geomspace(x.min(), x.max(), 20)
    ax.loglog(xs, xs ** exp["m"], "r-", label=r"$(\sigma_i/\sigma_j)^{%.3f}$" % exp["m"])
    ax.set_xlabel(r"$\sigma_i/\sigma_j$ (-)")
    ax.set_ylabel("$E_i/E_j$ (-)")
    figures.plain_ticks(ax.xaxis)
    figures.plain_ticks(ax.yaxis)
    figures.entitle(fig, r"Fig. %s: does $E_i/E_j$ follow a power of $\sigma_i/\sigma_j$?" % panel, who,
                    "m = %.3f, $R^2$ = %.3f" % (exp["m"], exp["r2"]))
    figures.legend_outside(ax, fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def fig_zeta_zm(tab, zetas, path, assembly="spheres", who=None):
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.2, 4.4))
    pts = [(tab["Zm"][k], zetas[s]) for k, s in enumerate(tab["state"]) if zetas.get(s) is not None]
    if pts:
        ax.plot(*zip(*pts), "o", ms=4, label="ours, per state")
    ax.axhline(chain.PAPER_ZETA, color="r", lw=0.8,
               label="paper 0.552" if assembly == "spheres" else "paper's spheres, 0.552")
    ax.set_xlabel(figures.ZM_LABEL)
    ax.set_ylabel(r"$\zeta$ fitted on the state's contrast (-)")
    figures.entitle(fig, r"Is $\zeta$ one number over the states, as the paper's 0.552 (section 4.2)?", who)
    figures.legend_outside(ax, fontsize=8)
    fig.tight_layout()
    return _save(fig, path)


def _fmt(x, f="%.4g"):
    return "n/a" if x is None or (isinstance(x, float) and not np.isfinite(x)) else f % x


def _material(results):
    m = ((read_metadata(results) or {}).get("specimen") or {}).get("material")
    if m:
        return dict(shear_modulus=float(m["shear_modulus"]), poisson=float(m["poisson"])), "the study's metadata"
    return None, None


def _study_line(results, rows=()):
    """What the study is (from its metadata.json): specimen size, seed, void ratio and Zm, the
    loading path and the contact law's rolling resistance; None for a bare table. A specimen saved
    without a summary (from a YADE scene: specimen_file.save) gave '? spheres (seed None), e = nan';
    its size, e and Zm are then read from the isotropic state's row, and said so."""
    meta = read_metadata(results)
    if meta is None:
        return None
    spec, fp = meta.get("specimen") or {}, meta.get("fingerprint") or {}
    summ, state = dict(spec.get("summary") or {}), fp.get("state") or {}
    where = ""
    if not all(k in summ for k in ("n", "void_ratio", "Zm")):
        iso = next((r for r in rows if r.get("state") == "1"), None)
        try:
            summ = dict(n=int(float(iso["Np"])), void_ratio=float(iso["void_ratio"]), Zm=float(iso["Zm"]))
            where = " (the specimen records no summary: size, e and Zm from state 1's row)"
        except (TypeError, KeyError, ValueError):  # no isotropic row: said as not recorded
            where = " (the specimen records no summary)"
    beta, eta = state.get("rolling_stiffness", 0.0), state.get("rolling_friction", 0.0)
    law = ("rolling resistance off (the paper's contact law)" if not beta else
           "rolling resistance beta = %g, eta_r = %g (not the paper's law: docs/rolling.md)" % (beta, eta))
    rate = str(state.get("path_rate", 2.0))  # Pa per step; "inf" in metadata.json for the whole load at once
    reached = ("states reached with the whole load at once (--path-rate inf)" if rate == "inf"
               else "states reached at the default 2 Pa per step" if float(rate) == 2.0
               else "states reached at %s Pa per step" % rate)
    # A study that records no rule was made with smallest-inertia (options.UNRECORDED_TIME_STEP).
    if state.get("time_step", "smallest-inertia") != "smallest-inertia":
        # The rates are per step of the smallest-inertia rule (docs/time-step.md): another rule's
        # longer step reached the same states in fewer steps, at the same rate in time.
        reached += (" of the smallest-inertia time step, taken in the %s rule's longer steps (--time-step %s)"
                    % (state["time_step"], state["time_step"]))
    else:
        reached += " with the smallest-inertia time step (--time-step smallest-inertia)"
    seed = spec.get("seed")
    # The probes' settings, so that a study run with --skip-detection or rotations restrained does
    # not read like any other in its report.
    probe = fp.get("probe") or {}
    probes = "" if not probe else "; probes of strain %s, rotations %s, contact detection %s" % (
        _fmt(probe.get("gamma"), "%g"),
        probe.get("rotations", "?") + (" (--rotations restrained)" if probe.get("rotations") == "restrained" else ""),
        probe.get("detection", "?") + (" (--skip-detection)" if probe.get("detection") == "off" else ""))
    if probe:
        probes += ", time step %s" % probe.get("time_step", "smallest-inertia")
    host = fp.get("host") or {}
    if host.get("name") == "yade":  # run_states.py --host yade: the same protocol, stepped by YADE's loop
        probes += ("; states and probes stepped by YADE's loop with the trueaniso plugin's classes "
                   "(--host yade, %s thread%s)" % (host.get("threads", "?"), "" if host.get("threads") == 1 else "s"))
    return ("Study: %s %s (%s), e = %s and Zm = %s at the isotropic state%s; %s; %s path, %s; %s%s."
            % (summ.get("n", "?"), fp.get("assembly", "sphere") + "s" if fp.get("assembly", "sphere") == "sphere"
               else fp.get("assembly"), "seed not recorded" if seed is None else "seed %s" % seed,
               _fmt(summ.get("void_ratio"), "%.4f"), _fmt(summ.get("Zm"), "%.3f"), where,
               _size_said(spec.get("summary") or {}, fp.get("assembly", "sphere")),
               fp.get("path", "true-triaxial"), reached, law, probes))


def _size_said(summary, assembly):
    """D50 and Cu of the specimen (its summary, specimen.d50_cu) beside the paper's for the
    assembly; a specimen saved before they were stored says so."""
    from trueaniso import psd
    paper = psd.PAPER_D50_CU.get(assembly)
    theirs = " (paper: %.3f mm, %.2f)" % (paper[0] * 1e3, paper[1]) if paper else ""
    if "d50" not in summary or "cu" not in summary:
        return "D50 and Cu not stored in the specimen%s" % theirs
    return "D50 = %.3f mm and Cu = %.2f%s" % (summary["d50"] * 1e3, summary["cu"], theirs)


def _states(n):
    return "1 state" if n == 1 else "%d states" % n


def _missing_states_line(results, rows):
    """The states the study defines (metadata.json) that have no row in the table: not reached (a
    specimen near its strength creeps; docs/runs.md) or not run yet, named so that the report does
    not pass for the whole study. None when there are none, or no metadata."""
    meta = read_metadata(results)
    if meta is None:
        return None
    have = {r["state"] for r in rows}
    missing = [sid for sid in meta.get("states", {}) if sid not in have]
    if not missing:
        return None
    missing.sort(key=lambda sid: (0, int(sid), "") if sid.isdigit() else (1, 0, sid))
    # The ids are named as states: "States ...: 9" would read as a count of nine.
    one = len(missing) == 1
    named = missing[0] if one else ", ".join(missing[:-1]) + " and " + missing[-1]
    return ("State%s %s of this study ha%s no row in its table (not reached, or not run yet: the run that asked for "
            "%s ended with the reason; docs/runs.md)." % ("" if one else "s", named, "s" if one else "ve",
                                                         "it" if one else "them"))


def paper_figures(rows, out, tag, assembly, who=None):
    """Figs 5, 6, 8, 9, 10 and 12 from the rows of one rotations setting, each with the paper's
    statement beside our numbers; `who` (figures.who_said) in each figure's title."""
    f = dict(f5="fig5-nu-vs-q%s.png" % tag, f6="fig6-stress-ratios%s.png" % tag, f8="fig8-Zm-vs-q%s.png" % tag,
             f9="fig9-R%s.png" % tag, f10="fig10-H%s.png" % tag, f12b="fig12-B%s.png" % tag,
             f12m="fig12-M%s.png" % tag)
    nu = figures.poisson_vs_q(rows, os.path.join(out, f["f5"]), who)
    figures.stress_ratios_vs_q(rows, os.path.join(out, f["f6"]), who)
    zm = figures.zm_vs_q(rows, os.path.join(out, f["f8"]), band=figures.PAPER_ZM_SPHERES if assembly == "spheres"
                         else None, who=who)
    fab = {name: figures.fabric_vs_stress(rows, os.path.join(out, f[key]), name, who)
           for name, key in (("R", "f9"), ("H", "f10"), ("B", "f12b"), ("M", "f12m"))}
    span = lambda d: (min(v.min() for _, v in d.values()), max(v.max() for _, v in d.values()))  # noqa: E731
    nus = np.concatenate([v[1][:, ~np.eye(3, dtype=bool)].ravel() for v in nu.values()])
    nus = nus[np.isfinite(nus)]
    zr = span(zm)
    q_all = np.concatenate([v[0] for v in zm.values()])
    zm_all = np.concatenate([v[1] for v in zm.values()])
    sides = chain.zm_by_sign_of_q(q_all, zm_all, zm_all[np.argmin(np.abs(q_all))])
    side = lambda k: _fmt(sides[k]["drop"], "%.3f")  # noqa: E731
    h_rel = np.array([fab["H"][a][1] for a in "xyz"])  # Fig. 10 plots H_ii / tr H
    b_slope = {a: 1000 * np.polyfit(*fab["B"][a], 1)[0] / np.mean(fab["B"][a][1]) for a in "xyz"}  # % per 10 kPa
    sphere = assembly == "spheres"
    return ["### Figs 5, 6, 8, 9, 10 and 12", "",
            "| figure | paper (%s) | ours |" % assembly, "|---|---|---|",
            "| Fig. 5: nu_ij against q, by b | each nu_ij follows its stress ratio (Fig. 6) | %.3f-%.3f over the states |"
            % (nus.min(), nus.max()),
            "| Fig. 8: Zm against q | %s | %.3f-%.3f; largest drop below the isotropic state at q < 0: %s, at q > 0: %s |"
            % ("5.94-5.99, falls at large \\|q\\|, alike at q < 0 and q > 0" if sphere else "falls at large \\|q\\|, faster at q < 0", *zr,
               side("negative"), side("positive")),
            "| Fig. 9: R_ii against sigma_i | %s | %.3f-%.3f |" % ("close to 1/3, minor changes" if sphere
                                                                  else "inherent anisotropy", *span(fab["R"])),
            "| Fig. 10: H_ii / tr H against sigma_i | %s | %.3f-%.3f |" % ("almost identical, vary slightly" if sphere
                                                                          else "inherent anisotropy",
                                                                          h_rel.min(), h_rel.max()),
            "| Fig. 12: B_ii against sigma_i | %s | rises %.2f, %.2f, %.2f %% per 10 kPa (x, y, z; of the mean B_ii) |"
            % ("one trend for the three directions, rising" if sphere else "directional differences",
               b_slope["x"], b_slope["y"], b_slope["z"]), "",
            "![Fig. 5](%s)" % f["f5"], "", "![Fig. 6](%s) ![Fig. 8](%s)" % (f["f6"], f["f8"]), "",
            "![Fig. 9](%s) ![Fig. 10](%s)" % (f["f9"], f["f10"]), "",
            "![Fig. 12, B](%s) ![Fig. 12, M](%s)" % (f["f12b"], f["f12m"]), ""]


FIG16_KEYS = ("sigma_v", "sigma_h", "G_ratio", "E_ratio_root")
CLUMP_KEYS = ("assembly", "n", "e", "probe_restrained", "static_restrained")


def _json_list(source, keys, what, schema):
    try:
        with open(source) as f:
            rows = json.load(f)
    except (OSError, ValueError) as exc:
        raise ResultsError("%s: cannot read %s (%s)" % (source, what, exc)) from None
    if not isinstance(rows, list) or not rows or not all(isinstance(r, dict) and all(k in r for k in keys)
                                                         for r in rows):
        raise ResultsError("%s is not %s: a JSON list of objects with %s" % (source, what, ", ".join(keys)))
    return validate.check(rows, schema, source, ResultsError)  # and of the types its sections read


def fig16_rows(source):
    """The per-state cross-anisotropy measures of a cross-anisotropic study (its probes.csv or
    study directory) or of the JSON pyscripts/trueaniso/analysis/cross_anisotropy.py --out wrote; checked."""
    from . import cross_anisotropy
    if source.endswith(".json"):
        return _json_list(source, FIG16_KEYS, "the output of pyscripts/trueaniso/analysis/cross_anisotropy.py --out", "fig16_states")
    return cross_anisotropy.states(source)  # a study directory or its probes.csv (results.table_path)


def clump_entries(source):
    """The entries of bench/anisotropy_clumps.py --json, checked (clump1, clump2)."""
    from . import chain
    entries = _json_list(source, CLUMP_KEYS, "the output of bench/anisotropy_clumps.py --json",
                         "clump_anisotropy")
    bad = [m["assembly"] for m in entries if m["assembly"] not in chain.PAPER or m["assembly"] == "spheres"]
    if bad:
        raise ResultsError("%s: assemblies %s are not the paper's clump1 or clump2" % (source, bad))
    return entries


def study_size(source):
    """What a study is, by its size, as its metadata.json records it ("4000 spheres"), for a study
    directory or its probes.csv; None where nothing records it (a bare table, a JSON of measures)."""
    if source is None:
        return None
    d = source if os.path.isdir(source) else os.path.dirname(os.path.abspath(source))
    meta = read_metadata(d) if os.path.exists(os.path.join(d, "metadata.json")) else None
    n = (((meta or {}).get("specimen") or {}).get("summary") or {}).get("n")
    if n is None:
        return None
    kind = (meta.get("fingerprint") or {}).get("assembly", "sphere")
    return "%d %s" % (n, "spheres" if kind == "sphere" else kind if kind == "clumps" else kind + " clumps")


def headline_section(heads, assembly, borrowed_b1=False):
    """The report's first section: its headline numbers (analysis.seeds.HEADLINE_ROWS) beside the
    paper's, each the mean +/- sample standard deviation over the seeds in `heads` (the report's
    study first) with how many seeds it is of. `heads` None: a bare table, which records no
    specimen; a string: why the study's could not be computed."""
    from . import seeds
    out = ["## Headlines against the paper (%s)" % assembly, ""]
    if heads is None:
        return out + ["Not for a bare probe table: the headlines need the study's directory (its metadata.json "
                      "records the specimen's e, Zm and seed).", ""]
    if isinstance(heads, str):
        return out + ["Not computed for this study: %s." % heads.rstrip("."), ""]
    if len(heads) == 1:
        said = ("One seed: each number is this study's alone, with no spread between seeds (`--seeds DIR ...` "
                "gives the studies of the same recipe at other seeds).")
    else:
        said = ("The mean +/- sample standard deviation (n - 1) over %d seeds of one recipe: `%s` (this report's "
                "study; every figure and table after this one is of it alone), %s. Each cell says how many seeds "
                "it is of (a study without a statics record of state 21 has no Table B1 ratio)."
                % (len(heads), heads[0]["study"], ", ".join("`%s`" % h["study"] for h in heads[1:])))
    out += [said, "", seeds.table([("ours", heads)], assembly, seeds.HEADLINE_ROWS, counts=True), "",
            "e and Zm of each specimen as prepared at 100 kPa; K and G at the isotropic state (Eqs. 21-22 inverted) "
            "beside the paper's Table 2 at our Zm where it holds (spheres); zeta fitted on the contrast over all "
            "states, the nu_ij RMSE (Eq. 22) and the relative E_i RMSE (Eq. 21) at it, rotations free; E_z/E_x and "
            "Table B1 from the static solve, rotations restrained, the prediction at zeta = 1 with %s. Zm's drop "
            "and e's change over the states, and the largest reciprocity error, say whether the specimen stayed "
            "elastic along the paths." % B1_DENSITY_SHORT]
    if borrowed_b1 and heads[0]["B1_ratio"] is None:
        out += ["", "This study has no statics record of state 21: its Table B1 ratios are in the Table B1 section "
                "below, from the other studies given with --b1-data."]
    return out + [""]


def paper_table2(assembly, zm):
    """The paper's Table 2 quadratics for Fig. 11 (figures.scalar_moduli_vs_zm): for spheres over
    the paper's own Zm, 5.94-5.99 (Fig. 8a), since below it they turn and rise again (their vertex is
    at 5.94); for the clumps, whose Zm the paper shows in Fig. 8 only, over ours, with a note where
    our Zm lies outside the Zm on which they rise (where the paper's data must lie)."""
    paper = chain.PAPER[assembly]
    if assembly == "spheres":
        band = figures.PAPER_ZM_SPHERES
        return dict(K=paper["K"], G=paper["G"], zm=band,
                    note="dashed: the paper's quadratics over its $Z_m$, %.2f-%.2f (Fig. 8a)" % band)
    low, high, why = chain.rising_range({k: paper[k] for k in ("K", "G")})
    note = "dashed: the paper's quadratics at our $Z_m$"
    if not (low <= float(np.min(zm)) and float(np.max(zm)) <= high):
        # "K rises with Zm only below Zm = 7.45" -> "K below Zm = 7.45"
        where = ", ".join("%s %s" % (w.split()[0], w.split(" only ")[1]) for w in why)
        note += ", extrapolated:\nits fits rise only %s" % where.replace("Zm", "$Z_m$")
    return dict(K=paper["K"], G=paper["G"], note=note)


def _other_size(size, own):
    """The sentence that says a section's data are not the report's own study, by size."""
    if size is None:
        return " Its size is not recorded with it."
    return "" if own is None or size == own else " These are %s, not this report's %s." % (size, own)


def fig16_section(rows, source, out, calibrated=None, material=None, own=None, assembly="spheres"):
    """Fig. 16 from fig16_rows: lines of the report, its figure written into `out`. `calibrated`:
    (zeta_h, zeta_v) of the report's own study; with a study's table (not a JSON of measures) the
    micromechanical a_h^2/a_v^2 is drawn at that zeta, at the paper's 0.552 and at zeta = 1, each
    labelled."""
    from . import cross_anisotropy
    size = study_size(source) if not source.endswith(".json") else None
    curves, cols = None, []
    if not source.endswith(".json") and material:
        path = table_path(source)
        # The paper states its zeta, 0.552, for spheres; its clump2 Fig. 16b is at a zeta_h, zeta_v it
        # shows in Fig. 13 only, so 0.552 is the spheres' there, and said so.
        zetas = [("zeta = %g (the paper's%s)" % (chain.PAPER_ZETA, "" if assembly == "spheres" else ", of spheres"),
                  chain.PAPER_ZETA, chain.PAPER_ZETA, "r-"), ("zeta = 1 (unmodified)", 1.0, 1.0, "k:")]
        if calibrated is not None:
            zetas.insert(0, ("zeta_h = %.3f, zeta_v = %.3f (calibrated on this report's study)" % calibrated,
                             calibrated[0], calibrated[1], "k--"))
        curves = []
        for label, zh, zv, style in zetas:
            by_state = cross_anisotropy.predicted_ratios(path, material["shear_modulus"], material["poisson"], zh, zv)
            values = [by_state.get(m["state"], float("nan")) for m in rows]
            curves.append(("$a_h^2/a_v^2$ predicted, " + _tex(label), values, style))
            cols.append((label, values))
    else:
        z = rows[0].get("predicted_zeta")
        cols = [("zeta = %g" % z if z is not None else "the zeta of the table's columns",
                 [m.get("predicted_ratio", float("nan")) for m in rows])]
    cross_anisotropy.figure(rows, os.path.join(out, "fig16.png"), curves, figures.study_who(source, assembly))
    lines = ["## Fig. 16: one anisotropy in G, E and nu (cross-anisotropic states, z vertical)", "",
             "From `%s`%s.%s The paper (Fig. 16a, spheres; 16b, clump2): the predicted a_h^2/a_v^2 (at its "
             "calibrated zeta) agrees with G_hh/G_vh and (E_h/E_v)^0.5, as Eq. (24) says, while nu_hh/nu_vv follows "
             "another trend. Ours:" % (source, ", %s" % size if size else "", _other_size(size, own)), "",
             "| sigma_v/sigma_h | G_hh/G_vh | (E_h/E_v)^0.5 | difference | nu_hv/nu_hh | %s |"
             % " | ".join("predicted a_h^2/a_v^2, %s" % label for label, _ in cols),
             "|---|---|---|---|---|%s" % ("---|" * len(cols))]
    for k, m in enumerate(rows):
        lines.append("| %.2f | %.3f | %.3f | %+.1f %% | %s | %s |" % (
            m["sigma_v"] / m["sigma_h"], m["G_ratio"], m["E_ratio_root"], 100 * (m["G_ratio"] / m["E_ratio_root"] - 1),
            _fmt(m.get("nu_ratio"), "%.3f"), " | ".join(_fmt(v[k], "%.3f") for _, v in cols)))
    worst = max(abs(m["G_ratio"] / m["E_ratio_root"] - 1) for m in rows)
    lines += ["", "Largest difference between G_hh/G_vh and (E_h/E_v)^0.5: %.1f %% over %d states." % (100 * worst,
                                                                                                    len(rows))]
    for label, values in cols:
        dev = [abs(v / m["E_ratio_root"] - 1) for v, m in zip(values, rows) if np.isfinite(v)]
        if dev:
            lines.append("Largest difference between the predicted a_h^2/a_v^2 (%s) and (E_h/E_v)^0.5: %.1f %%."
                         % (label, 100 * max(dev)))
    return lines + ["", "![Fig. 16](fig16.png)", ""], worst


def clumps_section(entries, source, own_size=None):
    """The clump assemblies at their isotropic state (clump_entries): void ratio, the restrained
    moduli of Table B1 and $E_z/E_x$ beside the paper's."""
    from . import chain
    lines = ["## Clump assemblies at the isotropic state (100 kPa, rotations restrained)", "",
             "From `%s`, %s (docs/specimens.md has the fabric and the free-rotation moduli)%s. The paper's "
             "clump1 is vertically stiffer, its clump2 horizontally (Table B1, DEM row)."
             % (source, " and ".join("%d %s clumps" % (m["n"], m["assembly"]) for m in entries),
                "; not this report's study (%s)" % own_size if own_size else ""), "",
             "| assembly | | e | E_x | E_y | E_z (MPa) | E_z/E_x | E_z/E_x against the paper |", "|---|---|---|---|---|---|---|---|"]
    ratios = {}
    for m in entries:
        name = m["assembly"]
        p = chain.PAPER[name]
        pe = p["B1"]["isotropic"]["dem"]
        paper_ratio = pe[2] / pe[0]
        lines.append("| %s | paper, DEM | %.3f | %.1f | %.1f | %.1f | %.3f | |"
                     % (name, chain.PAPER_VOID_RATIO[name], *pe, paper_ratio))
        for label, key in (("ours, probe, %d clumps" % m["n"], "probe_restrained"),
                           ("ours, static solve", "static_restrained")):
            E = np.array(m[key]) / 1e6
            lines.append("| | %s | %.3f | %.1f | %.1f | %.1f | %.3f | %+.1f %% |"
                         % (label, m["e"], *E, E[2] / E[0], 100 * (E[2] / E[0] / paper_ratio - 1)))
        ratios[name] = m["probe_restrained"][2] / m["probe_restrained"][0]
    return lines + ["", "The moduli themselves differ from the paper's (the clump shapes and the preparation "
                    "recipes are ours, docs/clumps.md: the paper shows its shapes only in a figure and cites its "
                    "recipes); the direction and the size of the inherent anisotropy are the comparable numbers.",
                    ""], ratios


def _bound_failure(tab, parts, ref, a2, contrast):
    """Why a contrast fit at a bound of its search is a failure of the model, not noise: the
    micromechanical a_i^2 follow the DEM's (r) with a slope below 1 even with no tangential
    stiffness (zeta = 0), and each state's own zeta, searched below 0, comes out negative."""
    mic0 = chain.micromechanical_a2(parts, 0.0, 0.0)
    per = [chain.a2_regression(tab["a2_dem"][:, i], mic0[:, i]) for i in range(3)]
    slopes, rs = [r["slope"] for r in per], [r["r"] for r in per]
    free = [v for v in chain.zeta_below_zero(tab, parts, ref).values() if v is not None]
    neg = sum(v < 0 for v in free)
    return ["**The fit stops at a bound: a failure of the model, not noise.** At zeta = 0 (the tangential "
            "springs removed, the largest contrast Eq. 37 can give) the micromechanical a_x^2, a_y^2, a_z^2 follow "
            "the DEM's over the states (r %.3f, %.3f, %.3f) with slopes %.3f, %.3f, %.3f on them: the model's "
            "stress-induced contrast is %.0f-%.0f %% of the DEM's there, and less at a larger zeta (the slope over "
            "all three, in the table above, falls from %.3f at the fit to %.3f at zeta = 1). Each state's own zeta "
            "against state %s, searched over %g to %g (C = A_n + zeta A_s, one zeta), is negative in %d of %d "
            "states (median %s): no reduction of the tangential stiffness reaches the DEM contrast. The fitted "
            "zeta_h %.3f, zeta_v %.3f only minimise a misfit that the model cannot remove."
            % (*rs, *slopes, 100 * min(slopes), 100 * max(slopes),
               chain.a2_regression(tab["a2_dem"], a2[-1][1])["slope"], chain.a2_regression(tab["a2_dem"], a2[0][1])["slope"],
               tab["state"][ref], *chain.UNBOUNDED_ZETA,
               neg, len(free), _fmt(float(np.median(free)) if free else None, "%.2f"),
               contrast["zeta_h"], contrast["zeta_v"]), ""]


def study_assembly(results):
    """The paper's assembly a study is of (its metadata's fingerprint: sphere -> spheres), or None
    for a bare table or a study without metadata."""
    meta = read_metadata(results)
    if meta is None:
        return None
    name = (meta.get("fingerprint") or {}).get("assembly", "sphere")
    return "spheres" if name == "sphere" else name


def build(results, out=None, assembly=None, shear_modulus=None, poisson=None, log=print, fig16=None,
          clumps=None, statics=False, b1_data=None, b1_other_material=False, seeds=None):
    """Write a study's report.md and its figures, every table and figure beside the paper's (module doc).

    Args:
        results: a study directory (of run_study.py or run_states.py) or a probe table alone.
        out: the report's directory (None: the study's report/).
        assembly: "spheres", "clump1" or "clump2", the paper's assembly to compare with (None: the
            study's own).
        shear_modulus: the particles' shear modulus, Pa, for a table without its study's metadata
            (None: the metadata's, else the paper's); checked against the table's micromechanical
            moduli, and the bounds every row's moduli are held to.
        poisson: the particles' Poisson's ratio, likewise.
        log: called with each line the build says.
        fig16: a cross-anisotropic study (or its JSON) for the Fig. 16 section.
        clumps: the JSON of bench/anisotropy_clumps.py for the clump section.
        statics: solve Table B1's states from the study's checkpoints first.
        b1_data: directories of statics records of other studies, whose state 21 Table B1 shows where
            the study has none; each needs its metadata.json and the report's material.
        b1_other_material: True takes `b1_data` of another material too, marked so in Table B1.
        seeds: directories of studies of the same recipe at other seeds: the headline table, the
            report's first section, gives each number as the mean and sample standard deviation over
            them and the study (analysis.seeds); the figures and the other tables stay the study's.

    Returns:
        (path, numbers): the report's path, and the numbers it shows by rotations setting.

    Raises:
        ResultsError: results that cannot be analysed (a row that disagrees with its state's
            definition or the material's bounds, a metadata.json that cannot be read, a statics
            record of another study), in one line, before anything is written.

    Example:
        >>> import tempfile
        >>> from trueaniso.analysis import report
        >>> path, numbers = report.build("docs/data/spheres-53004-s1", out=tempfile.mkdtemp(), log=lambda line: None)
        >>> print(open(path).readline().strip())
        # Report: spheres
    """
    statics = flag("report.build", "statics", statics)  # bool('no') would solve the statics
    b1_other_material = flag("report.build", "b1_other_material", b1_other_material)
    csv_path = table_path(results)
    out = out or (os.path.join(results, "report") if os.path.isdir(results) else os.path.dirname(csv_path) or ".")
    # A study's probes.csv given as the file: its directory's metadata (assembly, material, the
    # states asked) still applies: a clump1 table given so is a clump1 study, not spheres against
    # the paper's default material.
    beside = os.path.dirname(os.path.abspath(csv_path))
    if not os.path.isdir(results) and os.path.basename(csv_path) == "probes.csv" and \
            os.path.exists(os.path.join(beside, "metadata.json")):
        results = beside
    # The study's own assembly unless told: a clump1 study against the paper's spheres would read
    # its sphere fit far outside its range (36,627 MPa at clump1's Zm 10.3).
    own = study_assembly(results)
    if own == "clumps":  # clumps saved without an assembly: only the user can say which paper's to compare with
        if assembly is None:
            raise ResultsError("%s is a study of clumps whose specimen records no assembly (saved outside "
                               "prepare_specimen.py); give --assembly clump1 or clump2 to compare with the paper's"
                               % results)
    elif assembly is None:
        assembly = own or "spheres"
    elif own is not None and own != assembly:
        raise ResultsError("%s is a study of %s, not %s (--assembly)" % (results, own, assembly))
    if assembly not in chain.PAPER:
        raise ResultsError("assembly must be one of %s" % ", ".join(chain.PAPER))
    # Inputs of the optional sections are read and checked before anything is written.
    f16_rows = fig16_rows(fig16) if fig16 else None
    clump_rows = clump_entries(clumps) if clumps else None
    material, where = _material(results)
    if shear_modulus is not None or poisson is not None or material is None:
        material = dict(shear_modulus=shear_modulus or DEFAULT_MATERIAL["shear_modulus"],
                        poisson=poisson if poisson is not None else DEFAULT_MATERIAL["poisson"])
        where = "the command line" if (shear_modulus or poisson is not None) else "the paper's default"
    b1_data = [b1_data] if isinstance(b1_data, str) else list(b1_data or ())
    other_material = {}
    for d in b1_data:
        meta = read_metadata(d, required=True)  # what the records are of: refused without it
        if "21" not in b1_records(d):
            raise ResultsError("%s: no statics record of state 21 (statics_state-21.json) for Table B1" % d)
        if study_assembly(d) != assembly:
            raise ResultsError("%s is of %s, not %s: Table B1 compares one assembly with the paper's"
                               % (d, study_assembly(d) or "no recorded assembly", assembly))
        problem = b1_checks.borrowed_material_problem(d, meta, material, where)
        if problem and not (b1_other_material and meta.get("specimen", {}).get("material")):
            raise ResultsError(problem)
        if problem:
            other_material[d] = meta["specimen"]["material"]
    seeds = [seeds] if isinstance(seeds, str) else list(seeds or ())
    if seeds and not os.path.isdir(results):
        raise ResultsError("--seeds needs the report's study as a directory with its metadata.json (a bare probe "
                           "table records no specimen or seed to set beside the others)")
    if statics:
        solve_statics(results, log=log)
    # The headlines of the study and of its other seeds, read and checked before anything is written.
    from . import seeds as seeds_mod
    heads = None
    if os.path.isdir(results):
        try:
            heads = [seeds_mod.headlines(results)]
        except ResultsError as exc:
            if seeds:  # asked for the table over seeds: refused, said why
                raise
            heads = str(exc)  # a study without what they need (no complete state, no specimen summary)
        if seeds:
            heads += [seeds_mod.headlines(d) for d in seeds]
            problem = seeds_mod.recipe_problem(heads)
            if problem:
                raise ResultsError("--seeds: %s" % problem)
    rows = read_probes(csv_path, need=zeta_contrast.NEEDED + ["Zm", "b", "q", "nu_1", "nu_2", "nu_1_name",
                                                            "nu_2_name"], material=material)
    if os.path.isdir(results):
        b1_records(results)  # the study's own records, checked (after its table) before anything is written
    paper = chain.PAPER[assembly]
    lines = ["# Report: %s" % assembly, "",
             "Made by `pyscripts/trueaniso/analysis/report.py` from `%s` on %s. Material: G = %.4g Pa, nu = %.3g (%s; checked "
             "against the table's micromechanical moduli). Each table gives the paper's number beside ours."
             % (csv_path, time.strftime("%Y-%m-%d"), material["shear_modulus"], material["poisson"], where), ""]
    # A torn last row is left out: said in the report itself, not only on the terminal (an outside
    # try: the report counted one complete state fewer and did not say why).
    left_out = "Left out: %s." % rows.note if getattr(rows, "note", None) else None
    for line in (_study_line(results, rows), _missing_states_line(results, rows), left_out):
        if line:
            lines += [line, ""]
    lines += headline_section(heads, assembly, borrowed_b1=bool(b1_data))
    os.makedirs(out, exist_ok=True)
    numbers = {}
    own_size = study_size(results) if os.path.isdir(results) else None
    who = figures.study_who(results, assembly)
    for rot in sorted({r["rotations"] for r in rows}):
        sel = [r for r in rows if r["rotations"] == rot]
        tab = chain.state_table(sel)
        n = len(tab["state"])
        lines += ["## Probes with rotations %s: %d complete state%s%s" % (rot, n, "" if n == 1 else "s",
                                                                       " of %s" % own_size if own_size else ""), ""]
        if n < 3:
            lines += ["Fewer than 3 complete states (a state is complete when probed on x, y and z, which the "
                      "fits need): no fits.", ""]
            continue
        if not hyperelastic.quadratic_fittable(tab["Zm"]):
            lines += ["Fewer than 3 distinct Zm among the %d states (states of one contact network share Zm): "
                      "no fits." % n, ""]
            continue
        if n == 3:
            lines += ["Three states: each quadratic of Table 2 passes through its three points, so its R^2 is 1 by "
                      "construction, not a test of the fit.", ""]
        tag = "" if rot == "free" else "-" + rot
        ref = tab["state"].index("1") if "1" in tab["state"] else int(np.argmin(np.abs(tab["sigma"] - tab["sigma"].mean(1, keepdims=True)).sum(1)))
        fits = chain.table2(tab)
        parts = chain.fabric_parts(csv_path, tab, material["shear_modulus"], material["poisson"], rot)
        A_n, A_s = parts
        contrast = chain.fit_contrast(tab["E"], A_n, A_s)
        zh, zv = contrast["zeta_h"], contrast["zeta_v"]
        a2 = [("zeta = 1 (unmodified)", chain.micromechanical_a2(parts, 1.0, 1.0)),
              ("zeta = 0.552 (paper)", chain.micromechanical_a2(parts, chain.PAPER_ZETA, chain.PAPER_ZETA)),
              ("zeta_h = %.3f, zeta_v = %.3f (fitted%s)" % (zh, zv, ", at a bound" if contrast["at_bound"] else ""),
               chain.micromechanical_a2(parts, zh, zv))]
        preds = [(label, chain.predictions(tab, fits, a)) for label, a in a2]
        sphere = assembly == "spheres"
        # Fig. 4a fits all six ratios of the spheres; on clumps (Fig. 4b-c) the power law holds for
        # E_x/E_y only, and the ratios with z are reported apart, as the paper's text does.
        exp = chain.stress_ratio_exponent(tab, chain.ALL_PAIRS if sphere else chain.HORIZONTAL_PAIRS)
        exp_v = None if sphere else chain.stress_ratio_exponent(tab, chain.VERTICAL_PAIRS)
        zetas = chain.zeta_per_state(tab, parts, ref)
        who_rot = "%s; rotations %s" % (who, rot)
        figs = dict(f13=fig13(tab, a2, os.path.join(out, "fig13-a2%s.png" % tag), who_rot),
                    f1415=fig14_15(tab, preds[2][1], os.path.join(out, "fig14-E%s.png" % tag),
                                   os.path.join(out, "fig15-nu%s.png" % tag), assembly,
                                   os.path.join(out, "fig15-nu-parity%s.png" % tag), who_rot),
                    f4=fig4a(exp, os.path.join(out, "fig4a%s.png" % tag),
                             r"$E_i/E_j$, $i \neq j$" if sphere else "$E_x/E_y$, $E_y/E_x$", who_rot,
                             "4a" if sphere else "4b" if assembly == "clump1" else "4c") if exp else None,
                    fz=fig_zeta_zm(tab, zetas, os.path.join(out, "zeta-vs-Zm%s.png" % tag), assembly, who_rot),
                    f3="fig3-E-vs-sigma%s.png" % tag, f11="fig11-K-G-vs-Zm%s.png" % tag)
        figures.modulus_vs_stress(sel, os.path.join(out, figs["f3"]), who_rot)
        figures.scalar_moduli_vs_zm(sel, os.path.join(out, figs["f11"]), who_rot, paper_table2(assembly, tab["Zm"]))
        zm = tab["Zm"]
        lines += ["Zm from %.3f to %.3f (paper, %s); reference (isotropic) state %s."
                  % (zm.min(), zm.max(), "spheres: 5.94-5.99" if sphere else
                     "%s: shown in Fig. 8 only, falling faster at q < 0" % assembly, tab["state"][ref]), "",
                  "### Table 2: K and G (MPa) against Zm, quadratic fits", "",
                  "| | c1 | c2 | c3 | R^2 | at Zm = %.2f |" % zm[ref], "|---|---|---|---|---|---|"]
        low, high, why = chain.rising_range({k: paper[k] for k in ("K", "G")})
        outside = why if not low <= zm[ref] <= high else []
        for name in ("K", "G"):
            c = fits[name]
            pc = paper[name]
            at = np.polyval(pc, zm[ref])
            shown = "(%.1f, extrapolated)" % at if outside else "%.1f" % at
            lines.append("| %s paper | %.1f | %.1f | %.1f | > 0.99 | %s |" % (name, *pc, shown))
            lines.append("| %s ours | %.1f | %.1f | %.1f | %.4f | %.1f |" % (name, *c, np.polyval(c[:3], zm[ref])))
        slopes = chain.table2_slopes(tab, fits, paper, zm[ref])
        lines += ["", "Slopes of the fits at Zm = %.2f (MPa per unit of Zm)%s:" % (
            zm[ref], "; the paper's extrapolated" if outside else ""), "",
            "| | paper | ours, of the quadratic | ours, a straight line over our states | paper / ours (quadratic) |",
            "|---|---|---|---|---|"]
        for name in ("K", "G"):
            sl = slopes[name]
            lines.append("| d%s/dZm | %.1f | %.1f | %.1f | %s |" % (name, sl["paper"], sl["ours"], sl["ours_line"],
                                                                   _fmt(sl["ratio"], "%.2f")))
        lines += _slopes_undetermined(fits, zm)
        lines += ["", "![Fig. 3](%s) ![Fig. 11](%s)" % (figs["f3"], figs["f11"]), "",
                  "The coefficients of a quadratic over a narrow Zm range are ill-conditioned (large, of "
                  "alternating sign, in the paper too); the value at the reference Zm is the comparable number"
                  + ("." if not outside else
                     ", where the paper's fit holds there. Here it does not: the paper's %s, and K and G grow "
                     "with Zm in each of its assemblies (Fig. 11), so its data lie on that side and our Zm = %.2f "
                     "is outside them (its clump Zm is shown in Fig. 8 only; ours counts every member contact, "
                     "docs/clumps.md). Compare the trends and Table B1 instead." % ("; ".join(outside), zm[ref])),
                  "",
                  "### Fig. 13: micromechanical against DEM a_i^2", "",
                  "| zeta | rms of a_i^2 | slope of micromechanical on DEM a_i^2 (r) | E_i relative RMSE (Eq. 21) | "
                  "nu_ij RMSE (Eq. 22) | nu_ij RMSE / mean \\|nu_ij\\| |", "|---|---|---|---|---|---|"]
        floor = chain.nu_floor(tab)
        for (label, a), (_, p) in zip(a2, preds):
            reg = chain.a2_regression(tab["a2_dem"], a)
            lines.append("| %s | %.4f | %.3f (%.4f) | %.4f | %.4f | %.3f |"
                         % (label, float(np.sqrt(np.mean((a - tab["a2_dem"]) ** 2))), reg["slope"], reg["r"],
                            p["E_rel_rmse"], p["nu_rmse"], chain.relative_nu_rmse(tab, p["nu_rmse"])))
        lines += ["| Eq. 22 with each state's own DEM a_i^2 and nu0: the floor | 0 | 1 (1) | | %.4f | %.3f |"
                  % (floor["rmse"], floor["relative"]),
                  "| paper (%s) | | | | %.3f | |" % ("spheres, 0.552" if sphere else assembly + ", its fitted zeta_h, zeta_v",
                                                    paper["nu_rmse"]), "",
                  "The floor: Eq. (22) makes nu_ij a_j^2/a_i^2 one number, nu0, for the six pairs; the DEM's are not one "
                  "number, so even the DEM's own a_i^2 and nu0 leave an RMSE of %.4f (mean \\|nu_ij\\| %.3f), which no "
                  "zeta can beat. %s" % (floor["rmse"], floor["mean_abs"],
                                        "It is above the paper's %.3f: the paper's RMSE is not reachable with our "
                                        "nu_ij." % paper["nu_rmse"] if floor["rmse"] > paper["nu_rmse"] else
                                        "The paper's %.3f is above it." % paper["nu_rmse"]), ""]
        if contrast["at_bound"]:
            lines += _bound_failure(tab, parts, ref, a2, contrast)
        lines += ["![Fig. 13](%s)" % figs["f13"], "",
                  "### Figs 14-15: E_i and nu_ij predicted (Table 2 fits, fitted zeta) against DEM", "",
                  "![Fig. 14](%s)" % figs["f1415"][0], "",
                  "Fig. 15 as the paper draws it, against the state ID (Table C1), and as a parity plot:", "",
                  "![Fig. 15](%s)" % figs["f1415"][1], "", "![Fig. 15, parity](%s)" % figs["f1415"][2], ""]
        trend = chain.zeta_trend(tab, zetas)
        # The paper states its zeta in the text for spheres only; the clumps' pair is in Fig. 13d, f.
        paper_zeta, paper_zeta_short = (("0.552 (both)", "0.552") if sphere else
                                        ("zeta_h != zeta_v, in Fig. 13 only", "its zeta_h, zeta_v"))
        rho = trend["rho"]
        lines += ["### zeta and Zm", "",
                  "| | paper | ours |", "|---|---|---|",
                  "| zeta fitted on the contrast, all states | %s | zeta_h %.3f, zeta_v %.3f (one zeta: %.3f)%s |"
                  % (paper_zeta, zh, zv, contrast["zeta"],
                     "; at a bound of the search (%g-%g): not determined by these states, a failure of the model "
                     "(Fig. 13 above)" % chain.ZETA_BOUNDS if contrast["at_bound"] else ""),
                  "| zeta per state against state %s, mean at the highest Zm (within 0.02) | %s, constant | %s (%s) |"
                  % (tab["state"][ref], paper_zeta_short, _fmt(trend["high"], "%.3f"), _states(trend["n_high"])),
                  "| the same, lowest fifth of the Zm range | %s, constant | %s (%s) |"
                  % (paper_zeta_short, _fmt(trend["low"], "%.3f"), _states(trend["n_low"])),
                  "| Spearman rank correlation of zeta with Zm | (zeta independent of state) | %s |" % _fmt(rho, "%.2f"),
                  "| states whose own zeta is not determined (at a bound of the search, or a contrast that does "
                  "not depend on zeta) | | %d of %d |" % (trend["n_undetermined"], trend["n"]),
                  "", "![zeta against Zm](%s)" % figs["fz"], ""]
        if exp and sphere:
            lines += ["### Fig. 4a: E_i/E_j = (sigma_i/sigma_j)^m", "",
                      "m = %.3f (R^2 %.3f over %d ratios); the paper shows the power law without the value of m."
                      % (exp["m"], exp["r2"], len(exp["log_sigma_ratio"])), "", "![Fig. 4a](%s)" % figs["f4"], ""]
        elif exp:
            lines += ["### Fig. 4%s: E_i/E_j = (sigma_i/sigma_j)^m" % ("b" if assembly == "clump1" else "c"), "",
                      "| ratios | paper | ours: m | ours: R^2 of the power law |", "|---|---|---|---|",
                      "| E_x/E_y against sigma_x/sigma_y | a power law | %.3f | %.3f (%d ratios) |"
                      % (exp["m"], exp["r2"], len(exp["log_sigma_ratio"])),
                      "| E_z/E_x, E_z/E_y and inverses | deviate from it (inherent anisotropy) | %s | %s (%d ratios) |"
                      % (_fmt(exp_v and exp_v["m"], "%.3f"), _fmt(exp_v and exp_v["r2"], "%.3f"),
                         len(exp_v["log_sigma_ratio"]) if exp_v else 0), "",
                      "![Fig. 4](%s)" % figs["f4"], ""]
        elif not sphere:
            lines += ["### Fig. 4%s: E_i/E_j = (sigma_i/sigma_j)^m" % ("b" if assembly == "clump1" else "c"), "",
                      "Not measurable from these states: sigma_x/sigma_y stays within 1 % of 1 in all of them "
                      "(b = 0 only), so E_x/E_y has no stress ratio to follow.", ""]
        lines += paper_figures(sel, out, tag, assembly, who_rot)
        numbers[rot] = dict(states=n, Zm=(float(zm.min()), float(zm.max())), table2=fits, zeta=(zh, zv),
                            nu_floor=floor, slopes=slopes,
                            zeta_common=contrast["zeta"], nu_rmse={l: p["nu_rmse"] for l, p in preds},
                            E_rel_rmse={l: p["E_rel_rmse"] for l, p in preds}, m=exp["m"] if exp else None,
                            m_vertical=exp_v["m"] if exp_v else None, r2_vertical=exp_v["r2"] if exp_v else None,
                            zeta_spearman=rho)
    lines += table_b1(results, paper, own_size, b1_data, other_material)
    if not fig16:
        lines += ["## Fig. 16: one anisotropy in G, E and nu", "",
                  "The paper's Fig. 16 covers spheres (16a) and clump2 (16b) only." if assembly == "clump1" else
                  "Not in this report: it needs a cross-anisotropic study (run_states.py --path cross-anisotropic, "
                  "given with --fig16)%s." % (", which has not been run on clump2 (docs/clumps.md)"
                                              if assembly == "clump2" else ""), ""]
    if fig16:
        free = numbers.get("free") or next(iter(numbers.values()), None)
        f16, numbers["fig16_worst"] = fig16_section(f16_rows, fig16, out, free and free["zeta"], material, own_size,
                                                    assembly)
        lines += f16
    if clumps:
        cl, numbers["clump_ratios"] = clumps_section(clump_rows, clumps, own_size)
        lines += cl
    lines += ["## Departures from the paper", "", "| what | ours | why |", "|---|---|---|"]
    lines += ["| %s | %s | %s |" % d for d in DEPARTURES]
    from trueaniso import atomic
    path = os.path.join(out, "report.md")
    with atomic.atomic_open(path) as f:
        f.write("\n".join(lines) + "\n")
    if getattr(rows, "note", None):
        log("note: %s" % rows.note)
    return path, numbers


# Below this R^2 a quadratic leaves more than a tenth of K's or G's variation over the states
# unexplained: its slope is then set by the scatter, not by a trend in Zm.
SLOPE_R2_FLOOR = 0.9


def _slopes_undetermined(fits, zm):
    """A sentence under the slope table when a fit is too weak for its slope to mean anything."""
    r2 = {name: fits[name][3] for name in ("K", "G")}
    if min(r2.values()) >= SLOPE_R2_FLOOR:
        return []
    return ["", "Over a Zm range of %.3f the quadratics explain R^2 = %.2f of K's and %.2f of G's variation (below "
            "%.1f): these slopes are undetermined by our states, not a departure from the paper's."
            % (zm.max() - zm.min(), r2["K"], r2["G"], SLOPE_R2_FLOOR)]


# Which N_c/V Table B1's prediction uses: statics.rotation_factor's E_kinematic is Eq. (40) of the
# static solve's affine stiffness, (1/V) sum over the contacts (engines/statics/NetworkMatrix.cpp).
B1_DENSITY_SHORT = "the counted N_c/V"
B1_DENSITY = ("Our predicted row (zeta = 1) uses the counted N_c/V: it is Eq. (40) of the kinematic stiffness (1/V) "
              "sum over every contact carrying a normal force of k_n L n L n + k_s (L L delta - L n L n), each "
              "contact with its own branch vector and stiffness (docs/statics.md, section 6), i.e. Eq. (37) with "
              "N_c/V = Z Np/(2V), not Eq. (36)'s Zm Np/(2V), which is larger by Zm/Z (docs/fabric.md).")


def _b1_cells(E):
    """E_i (MPa) with its a_i^2 (Eq. 25) in brackets, as the paper's Table B1 prints them."""
    a2 = hyperelastic.fabric_a2(E)
    return tuple("%.1f (%.3f)" % (e, a) for e, a in zip(E, a2))


def b1_records(directory):
    """{"isotropic": record, "21": record} of the statics records a study directory keeps
    (trueaniso.statics.cached_record: run_study.py writes them, `--statics` solves them from the
    checkpoints), each checked against its schema and against the study of the directory
    (b1_checks); empty for a bare table."""
    from trueaniso import statics
    found, paths = {}, {}
    if os.path.isdir(directory):
        for label, candidates in (("isotropic", (None, "1")), ("21", ("21",))):
            path = next((statics.state_file(directory, c) for c in candidates
                         if os.path.exists(statics.state_file(directory, c))), None)
            if path:
                found[label] = validate.load_json(path, "statics_record", ResultsError)
                paths[label] = path
    if found:
        b1_checks.check(directory, {label: (paths[label], found[label]) for label in found}, read_metadata(directory))
    return found


def _b1_rows(label, st, paper, where="", with_paper=True):
    """Table B1's rows of one state: the paper's (unless `with_paper` is off), then ours, the state
    named with `where` (the size of a study other than the report's)."""
    pred, dem = np.array(st["E_kinematic"]) / 1e6, np.array(st["E_blocked"]) / 1e6
    p = paper["B1"][label]
    name = ("isotropic" if label == "isotropic" else "21 (b = 0.5, sigma_z = 140 kPa)") + where
    gap = lambda a, b: float(np.max(np.abs(hyperelastic.fabric_a2(a) - hyperelastic.fabric_a2(b))))  # noqa: E731
    out = ["| %s | paper predicted (zeta = 1) | %s | %s | %s | %.3f | %.3f |"
           % (name, *_b1_cells(p["pred"]), np.mean(p["pred"]) / np.mean(p["dem"]), gap(p["pred"], p["dem"])),
           "| | paper DEM | %s | %s | %s | | |" % _b1_cells(p["dem"])] if with_paper else ["| %s | | | | | | |" % name]
    out += ["| | ours predicted (zeta = 1) | %s | %s | %s | %.3f | %.3f |"
            % (*_b1_cells(pred), pred.mean() / dem.mean(), gap(pred, dem)),
            "| | ours static solve, rotations blocked | %s | %s | %s | | |" % _b1_cells(dem)]
    if "sigma" in st:
        out.append("| | ours sigma_x, sigma_y, sigma_z (kPa) | %.1f | %.1f | %.1f | | |" % tuple(x / 1e3 for x in st["sigma"]))
    return out


def _b1_ratios(found, paper, size):
    """The sentence of E_i at state 21 over E_i at the isotropic state, rotations blocked, ours (of
    one specimen, named by `size`) beside the paper's."""
    ours = np.array(found["21"]["E_blocked"]) / np.array(found["isotropic"]["E_blocked"])
    theirs = np.array(paper["B1"]["21"]["dem"]) / np.array(paper["B1"]["isotropic"]["dem"])
    return ("E_i at state 21 / E_i at the isotropic state, rotations blocked (E_x, E_y, E_z): ours %s%s, the "
            "paper's %s." % (", ".join("%.3f" % r for r in ours), " (%s)" % size if size else "",
                             ", ".join("%.3f" % r for r in theirs)))


def table_b1(results, paper, own_size=None, others=(), other_material=None):
    """Appendix B / Table B1 at the isotropic state and at state 21: the exact static solve with
    rotations blocked (what a restrained probe measures) against the unmodified (zeta = 1)
    kinematic prediction, from the study's statics records (b1_records). Each $E_i$ with its $a_i^2$
    (Eq. 25), the paper's $a_i^2$ computed the same way from its printed $E_i$. `others`: directories
    of other studies (another size, or another specimen) whose records stand for state 21 where
    the study has none, each shown with its own isotropic state (a ratio between states holds
    within one specimen). `other_material`: {directory: material} of those whose particles are not
    the study's (shown, marked, at the user's word: report --b1-other-material)."""
    other_material = other_material or {}
    out = ["## Table B1: rotations restrained, E_i (MPa) and a_i^2", ""]
    found = b1_records(results) if os.path.isdir(results) else {}
    others = [others] if isinstance(others, str) else list(others or ())
    borrowed = [(d, b1_records(d)) for d in others] if "21" not in found else []
    borrowed = [(d, recs) for d, recs in borrowed if recs]
    if not found and not borrowed:
        return out + ["Not in this study (run_study.py writes the statics records; `python3 -m trueaniso.analysis.report "
                      "DIR --statics` solves them from the state checkpoints).", ""]
    said = ["From this study's statics records%s." % (" (%s)" % own_size if own_size else "")] if found else \
        ["Not in this study's statics records."]
    sizes = []
    for d, _ in borrowed:
        size = study_size(d)
        note = _other_size(size, own_size)
        if size is not None and size == own_size:  # a specimen of the report's size, but not its own
            size, note = "another specimen of %s" % size, " It is not this report's specimen."
        sizes.append(size)
        summary = ((read_metadata(d) or {}).get("specimen") or {}).get("summary") or {}
        state = ": e %.4f, Zm %.3f as prepared" % (summary["void_ratio"], summary["Zm"]) \
            if "void_ratio" in summary and "Zm" in summary else ""
        if d in other_material:
            note += (" Its particles are of another material (%s; this study's: see above), shown at the user's word "
                     "(--b1-other-material): its moduli are not comparable with this study's."
                     % b1_checks._said_material(other_material[d]))
        said.append("%s `%s`%s, beside that specimen's own isotropic state%s.%s" % (
            "This study has no record of state 21: it comes from" if len(sizes) == 1 else "State 21 also from", d,
            " (%s%s)" % (size or "size not recorded", state), " (a ratio between states holds within one specimen "
                                                                 "only)" if len(sizes) == 1 else "", note))
    out += [" ".join(said) + " a_i^2 = E_i^(1/3) / (E_j E_k)^(1/6) (Eq. 25) of each row; the paper prints its "
            "a_i^2 to two decimals, here computed from its printed E_i. " + B1_DENSITY, "",
            "| state | | E_x (a_x^2) | E_y (a_y^2) | E_z (a_z^2) | predicted / DEM, mean E_i | largest \\|a_i^2 "
            "predicted - DEM\\| |", "|---|---|---|---|---|---|---|"]
    shown = set(found)
    for label, st in found.items():
        out += _b1_rows(label, st, paper)
    for (d, recs), size in zip(borrowed, sizes):
        mark = ", other material: G = %.4g GPa, nu = %.3g" % (other_material[d]["shear_modulus"] / 1e9,
                                                               other_material[d]["poisson"]) if d in other_material else ""
        for label, st in recs.items():
            out += _b1_rows(label, st, paper, (", %s" % size if size else "") + mark, with_paper=label not in shown)
            shown.add(label)
    ratios = [_b1_ratios(f, paper, s) for f, s in [(found, own_size)] + [(r, s) for (_, r), s in zip(borrowed, sizes)]
              if len(f) == 2]
    for line in ratios:
        out += ["", line]
    if "21" not in shown:
        out += ["", "State 21: no statics record in this study (no checkpoint of state 21 was kept, or the state "
                "was not solved); docs/departures.md says why where it is known."]
    return out + [""]


def solve_statics(results, log=print):
    """The Table B1 records of a study directory from its checkpoints (states 1 and 21)."""
    from trueaniso import statics, study_dir
    if not os.path.isdir(os.path.join(results, "states")):
        raise ResultsError("%s: --statics needs a study directory with state checkpoints (states/*.npz)" % results)
    from trueaniso import specimen_file, study_checks
    meta = validate.check(read_metadata(results, required=True), "study", os.path.join(results, "metadata.json"),
                          ResultsError)  # the whole study: its checkpoints are checked against it
    done = 0
    for sid in ("1", "21"):
        path = study_dir.checkpoint_path(results, sid)
        if os.path.exists(path):
            # The study's own checks first, as run_states.py applies them: a checkpoint copied in from
            # another study was solved, and Table B1 showed that study's moduli.
            if not os.path.exists(statics.state_file(results, sid)):
                try:
                    ck = specimen_file.read(path)[1]
                except specimen_file.SpecimenFileError as exc:
                    raise ResultsError(study_dir.checkpoint_problem(exc, sid)) from None
                problem = study_checks.checkpoint_problem(meta, ck, sid)
                if problem:
                    raise ResultsError("%s: %s; it is not this study's state %s (remove it; run_states.py or "
                                       "run_study.py reaches it again)" % (path, problem, sid))
            statics.cached_record(results, sid, log=log)
            done += 1
    if not done:
        raise ResultsError("%s: no checkpoint of state 1 or 21 (states/1.npz, states/21.npz)" % results)


def _paper_assembly(text):
    # The study scripts say "sphere" (prepare_specimen.py --assembly sphere), the paper's tables
    # "spheres": both are taken, and anything else is refused in one line.
    name = {"sphere": "spheres"}.get(text, text)
    if name not in chain.PAPER:
        raise argparse.ArgumentTypeError("%s: the paper's assemblies are %s" % (text, ", ".join(sorted(chain.PAPER))))
    return name


def parser():
    from trueaniso import cli
    p = cli.Parser(prog="python3 -m trueaniso.analysis.report", description=cli.description(__doc__))
    p.add_argument("results", help="a results directory (with probes.csv) or a probe table")
    p.add_argument("--out", help="directory for report.md and its figures (when not given: RESULTS/report, or "
                                 "beside the table)")
    p.add_argument("--assembly", default=None, type=_paper_assembly,
                   help="the paper's assembly to compare with: %s (sphere, as the scripts spell it, is spheres; when "
                        "not given: the study's own, from its metadata.json; spheres for a bare table)"
                        % ", ".join(sorted(chain.PAPER)))
    p.add_argument("--shear-modulus", type=cli.positive,
                   help="particle shear modulus (Pa) if not in the study's metadata")
    p.add_argument("--poisson", type=cli.poisson_ratio,
                   help="particle Poisson's ratio if not in the study's metadata")
    p.add_argument("--fig16", help="a cross-anisotropic study (run_states.py --path cross-anisotropic: its directory "
                                   "or probes.csv, or the JSON of python3 -m trueaniso.analysis.cross_anisotropy "
                                   "--out) for Fig. 16")
    p.add_argument("--clumps", help="the JSON of bench/anisotropy_clumps.py --json (clump1, clump2 at "
                                    "their isotropic state) for the clump section")
    p.add_argument("--statics", action="store_true",
                   help="solve the static stiffness of the isotropic state and of state 21 from the study's "
                        "checkpoints (states/1.npz, states/21.npz) where no record exists yet (Table B1)")
    p.add_argument("--b1-data", metavar="DIR", action="append",
                   help="a directory of statics records (statics_state-1.json, statics_state-21.json) and the "
                        "metadata.json of another study, e.g. of another size: Table B1 shows its state 21, "
                        "beside its own isotropic state, where the study has no record of state 21 (repeatable); "
                        "its records must be its study's and its particles this study's material")
    p.add_argument("--seeds", metavar="DIR", nargs="+",
                   help="studies of the same recipe at other seeds (run_study.py or run_states.py directories): the "
                        "report's first section gives each headline as the mean +/- sample standard deviation over "
                        "them and the study; the figures and other tables stay the study's")
    p.add_argument("--b1-other-material", action="store_true",
                   help="show --b1-data of particles of another material than this study's, marked so in Table "
                        "B1, instead of refusing it")
    return p


def main(argv=None):
    from trueaniso import cli
    o = parser().parse_args(argv)
    # Where the report goes, checked before any work: a refusal leaves no empty directory behind.
    out = o.out or (os.path.join(o.results, "report") if os.path.isdir(o.results)
                    else os.path.dirname(table_path(o.results)) or ".")
    problem = cli.output_problem(out, option="--out" if o.out else "the report's directory")
    if problem:
        raise ResultsError(problem)
    try:
        path, _ = build(o.results, o.out, o.assembly, o.shear_modulus, o.poisson,
                        log=lambda m: sys.stderr.write(m + "\n"), fig16=o.fig16, clumps=o.clumps,
                        statics=o.statics, b1_data=o.b1_data, b1_other_material=o.b1_other_material,
                        seeds=o.seeds)
    except (OSError, RuntimeError) as exc:  # a file unreadable, a disk full, a static solve that failed
        raise ResultsError(said(exc)) from None
    cli.work_done()
    print("report: %s" % path)


if __name__ == "__main__":
    from trueaniso import cli
    cli.guarded(main)
