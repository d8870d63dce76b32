"""Figures like the paper's, from a probes.csv of pyscripts/run_states.py. Run as a tool::

    /usr/bin/python3 -m trueaniso.analysis.figures results/x/probes.csv --out docs/figures
"""
import os
import sys

import numpy as np

from . import hyperelastic
from .results import ResultsError, number, read_metadata, read_probes, said

__all__ = ["modulus_vs_stress", "scalar_moduli_vs_zm"]


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _save(fig, path):
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=130)
    os.replace(tmp, path)


def _finish(plt, fig, path):
    """Lay out, write atomically and close a figure."""
    if not fig.get_constrained_layout():
        fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def entitle(fig, question, who=None, detail=None):
    """A figure's title: the question it answers (the paper's figure named in it), the numbers that
    answer it (`detail`), then what it is of (`who`: assembly, particle count, seed), so that a figure
    copied out of its report still says which study it shows."""
    fig.suptitle("\n".join(t for t in (question, detail, who) if t), fontsize=9)


def legend_outside(ax, **kw):
    """The legend right of the axes, where it covers no point of the data."""
    kw.setdefault("fontsize", 7)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **kw)


def legend_above(ax, ncol=2, **kw):
    """The legend above the axes (a panel of a row, whose right is the next panel)."""
    kw.setdefault("fontsize", 7)
    return ax.legend(loc="lower center", bbox_to_anchor=(0.5, 1.02), borderaxespad=0.0, ncol=ncol, **kw)


def plain_ticks(axis, n=5):
    """Ticks at plain numbers, about `n` of them, on a log axis of a narrow range: the log scale's
    own ticks fall at powers of ten and leave such an axis one labelled tick (a ratio of 0.5-2)."""
    from matplotlib import ticker
    axis.set_major_locator(ticker.MaxNLocator(n))
    axis.set_major_formatter(ticker.FormatStrFormatter("%g"))
    axis.set_minor_formatter(ticker.NullFormatter())


def who_said(assembly=None, n=None, seed=None):
    """'4000 spheres, seed 1' for a figure's title; what is not recorded said so."""
    kind = {"sphere": "spheres", "spheres": "spheres", None: "particles"}.get(assembly, "%s clumps" % assembly)
    size = "%d %s" % (n, kind) if n else "%s (particle count not recorded)" % kind
    return "%s, %s" % (size, "seed %s" % seed if seed is not None else "seed not recorded")


def study_who(source, assembly=None):
    """What a figure is of, for its title (`who_said`): the assembly, particle count and seed its
    study's metadata.json records (a study directory or its probes.csv); a bare table or a JSON of
    measures records neither count nor seed, and says so (`assembly` names what the caller knows)."""
    d = source if os.path.isdir(source) else os.path.dirname(os.path.abspath(source))
    meta = read_metadata(d) if os.path.exists(os.path.join(d, "metadata.json")) else None
    if meta is None:
        return who_said(assembly)
    spec = meta.get("specimen") or {}
    return who_said((meta.get("fingerprint") or {}).get("assembly", "sphere"),
                    (spec.get("summary") or {}).get("n"), spec.get("seed"))


def modulus_vs_stress(rows, path, who=None):
    r"""Fig. 3: each Young's modulus $E_i$ against the stress $\sigma_i$ in its direction, one series per axis.

    Args:
        rows: rows of probes.csv (`results.read_probes`).
        path: the PNG to write (atomically).
        who: what the figure is of (assembly, particle count, seed: `who_said`, `study_who`), under its
            question.

    Example:
        >>> import os, tempfile
        >>> from trueaniso.analysis import figures, results
        >>> png = os.path.join(tempfile.mkdtemp(), "fig3.png")
        >>> figures.modulus_vs_stress(results.read_probes("docs/data/spheres-53004-s1"), png)
        >>> os.path.getsize(png) > 10000
        True
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for axis, mark in zip("xyz", "os^"):
        sel = [r for r in rows if r["probe"] == axis]
        s = [float(r["sigma_" + axis]) / 1e3 for r in sel]
        e = [float(r["E"]) / 1e6 for r in sel]
        ax.scatter(s, e, marker=mark, label="$E_%s$" % axis, alpha=0.8)
    ax.set_xlabel(r"$\sigma_i$ (kPa)")
    ax.set_ylabel(r"$E_i$ (MPa)")
    entitle(fig, "Fig. 3: does each $E_i$ rise with the stress $\\sigma_i$ in its direction?", who)
    legend_outside(ax, fontsize=8)
    _finish(plt, fig, path)


def scalar_moduli_vs_zm(rows, path, who=None, paper=None):
    """Fig. 11: K and G of the hyperelastic model against Zm, with their quadratic fits (Table 2).

    Args:
        rows: rows of probes.csv (`results.read_probes`).
        path: the PNG to write (atomically).
        who: what the figure is of (`who_said`), in its title.
        paper: the paper's Table 2 for the assembly, ``{"K": (c1, c2, c3), "G": ..., "zm": (low, high),
            "note": text}`` (MPa), drawn dashed over the Zm range `zm` (the paper's data, where known;
            else ours) beside our fits, `note` under the title.

    Returns:
        dict: the fits drawn, ``{"K": {"c": [c1, c2, c3], "r2": R^2}, "G": {...}}`` (MPa), and
        with `paper` ``"paper": {"K": (Zm, K), "G": (Zm, G)}``, the paper's curves as drawn.

    Example:
        >>> import os, tempfile
        >>> from trueaniso.analysis import figures, results
        >>> png = os.path.join(tempfile.mkdtemp(), "fig11.png")
        >>> fits = figures.scalar_moduli_vs_zm(results.read_probes("docs/data/spheres-53004-s1"), png)
        >>> print("R^2 of K: %.3f, of G: %.3f" % (fits["K"]["r2"], fits["G"]["r2"]))
        R^2 of K: 0.892, of G: 0.923
        >>> os.path.getsize(png) > 10000
        True
    """
    plt = _plt()
    states = hyperelastic.states_from_rows(rows)
    z, K, G = [], [], []
    for st in states.values():
        if np.all(np.isfinite(st["E"])) and np.all(np.isfinite(st["nu"][~np.eye(3, dtype=bool)])):
            m = hyperelastic.scalar_moduli(st["E"], st["nu"])
            z.append(st["Zm"])
            K.append(m["K"] / 1e6)
            G.append(m["G"] / 1e6)
    if not hyperelastic.quadratic_fittable(z):
        return None
    fig, ax = plt.subplots(figsize=(6.8, 4.4))
    out = {}
    xs = np.linspace(min(z), max(z), 50)
    for vals, name, mark in ((K, "K", "o"), (G, "G", "s")):
        c, r2 = hyperelastic.quadratic_fit(z, vals)
        dots = ax.scatter(z, vals, marker=mark, label="$%s$, ours" % name)
        ax.plot(xs, np.polyval(c, xs), color=dots.get_facecolor()[0], label="$%s$ fit, $R^2$ = %.3f" % (name, r2))
        out[name] = dict(c=c.tolist(), r2=r2)
        if paper:
            zp = np.linspace(*(paper.get("zm") or (min(z), max(z))), 50)
            ys = np.polyval(paper[name], zp)
            ax.plot(zp, ys, "--", color=dots.get_facecolor()[0], label="$%s$, paper's Table 2" % name)
            out.setdefault("paper", {})[name] = (zp, ys)
    ax.set_xlabel(ZM_LABEL)
    ax.set_ylabel("$K$, $G$ (MPa)")
    entitle(fig, "Fig. 11: do $K$ and $G$ follow the paper's quadratics in $Z_m$ (Table 2)?", who,
            paper.get("note") if paper else None)
    legend_outside(ax)
    _finish(plt, fig, path)
    return out


def _by_state(rows):
    """One row per state (its z probe's, else the first normal probe's): the state's own columns."""
    out = {}
    for r in rows:
        if r["probe"] in ("x", "y", "z") and (r["state"] not in out or r["probe"] == "z"):
            out[r["state"]] = r
    return list(out.values())


def _b_groups(states):
    """{b: [states sorted by q]}: the constant-b paths, as the paper's Figs 5, 6 and 8 draw them."""
    groups = {}
    for st in states:
        groups.setdefault(round(float(st["b"]), 3), []).append(st)
    return {b: sorted(v, key=lambda st: float(st["q"])) for b, v in sorted(groups.items())}


def poisson_vs_q(rows, path, who=None):
    r"""Fig. 5: $\nu_{zx}$, $\nu_{xz}$ | $\nu_{zy}$, $\nu_{yz}$ | $\nu_{xy}$, $\nu_{yx}$ against q, one line per b. Returns
    {b: (q, nu (n, 3, 3))} in kPa and ratios."""
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), layout="constrained")
    out = {}
    pairs = (((2, 0), (0, 2)), ((2, 1), (1, 2)), ((0, 1), (1, 0)))
    for b, sts in _b_groups(hyperelastic.states_from_rows(rows).values()).items():
        q = np.array([st["q"] for st in sts]) / 1e3
        nu = np.array([st["nu"] for st in sts])
        out[b] = (q, nu)
        for ax, ((i, j), (k, m)) in zip(axes, pairs):
            line, = ax.plot(q, nu[:, i, j], "o-", ms=3, label="b = %.2f" % b)
            ax.plot(q, nu[:, k, m], "s--", ms=3, color=line.get_color())
    for ax, ((i, j), (k, m)) in zip(axes, pairs):
        ax.set_title(r"$\nu_{%s%s}$ (solid), $\nu_{%s%s}$ (dashed)" % ("xyz"[i], "xyz"[j], "xyz"[k], "xyz"[m]),
                     fontsize=9)
        ax.set_xlabel("$q$ (kPa)")
        ax.set_ylabel(r"$\nu_{%s%s}$, $\nu_{%s%s}$ (-)" % ("xyz"[i], "xyz"[j], "xyz"[k], "xyz"[m]))
    entitle(fig, "Fig. 5: does each $\\nu_{ij}$ follow its stress ratio along the paths of constant $b$?", who)
    legend_outside(axes[2])
    _finish(plt, fig, path)
    return out


def stress_ratios_vs_q(rows, path, who=None):
    r"""Fig. 6: $\sigma_z/\sigma_x$, $\sigma_z/\sigma_y$, $\sigma_x/\sigma_y$ against q, one line per b."""
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4.2), layout="constrained")
    out = {}
    for b, sts in _b_groups(_by_state(rows)).items():
        q = np.array([float(st["q"]) for st in sts]) / 1e3
        sig = np.array([[float(st["sigma_" + a]) for a in "xyz"] for st in sts])
        ratios = np.stack([sig[:, 2] / sig[:, 0], sig[:, 2] / sig[:, 1], sig[:, 0] / sig[:, 1]], axis=1)
        out[b] = (q, ratios)
        for k, ax in enumerate(axes):
            ax.plot(q, ratios[:, k], "o-", ms=3, label="b = %.2f" % b)
    for ax, name in zip(axes, (r"$\sigma_z/\sigma_x$", r"$\sigma_z/\sigma_y$", r"$\sigma_x/\sigma_y$")):
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("$q$ (kPa)")
        ax.set_ylabel(name + " (-)")
    entitle(fig, "Fig. 6: which stress ratios do the paths of constant $b$ reach?", who)
    legend_outside(axes[2])
    _finish(plt, fig, path)
    return out


PAPER_ZM_SPHERES = (5.94, 5.99)  # section 4.1 / Fig. 8a: the sphere assembly's Zm over the 39 states


def zm_vs_q(rows, path, band=PAPER_ZM_SPHERES, who=None):
    """Fig. 8: Zm against q, one line per b, the paper's band shaded; Zm counted with a gap
    tolerance of 1e-3 (r1 + r2) as open markers when the table has it."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7.4, 4.4))
    if band:
        ax.axhspan(*band, color="0.85", label="paper, spheres (%.2f-%.2f)" % band)
    out, gap = {}, False
    for b, sts in _b_groups(_by_state(rows)).items():
        q = np.array([float(st["q"]) for st in sts]) / 1e3
        zm = np.array([float(st["Zm"]) for st in sts])
        out[b] = (q, zm)
        line, = ax.plot(q, zm, "o-", ms=3, label="b = %.2f" % b)
        if sts[0].get("Zm_gap1e-3", "") != "":
            gap = True
            ax.plot(q, [float(st["Zm_gap1e-3"]) for st in sts], "o:", ms=3, mfc="none", color=line.get_color())
    if gap:  # the open markers, said once in the legend
        ax.plot([], [], "o:", ms=3, mfc="none", color="0.4", label="$Z_m$, contacts within a gap of\n"
                "$10^{-3}(r_1 + r_2)$ counted")
    ax.set_xlabel("$q$ (kPa)")
    ax.set_ylabel(ZM_LABEL)
    entitle(fig, "Fig. 8: does $Z_m$ stay within the paper's %.2f-%.2f along the paths?" % band if band else
            "Fig. 8: does $Z_m$ fall faster at $q$ < 0 than at $q$ > 0, as the paper's does?", who)
    legend_outside(ax)
    _finish(plt, fig, path)
    return out


# What Figs 9, 10 and 12 plot of each fabric tensor, with its unit. H (Eq. 16, m^2) is shown as
# H_ii / tr H, the share of each direction, which does not depend on the particle size; B and M
# (Eqs. 33-34) are <rbar^(1/3) N^(1/3) L L> and <rbar^(1/3) N^(1/3) L n L n>: m^(1/3) N^(1/3) m^2.
FABRIC_LABELS = dict(R=r"$R_{ii}$ (-)", H=r"$H_{ii}/\mathrm{tr}\,H$ (-)",
                     B=r"$B_{ii}$ (m$^{7/3}$ N$^{1/3}$)", M=r"$M_{iiii}$ (m$^{7/3}$ N$^{1/3}$)")
ZM_LABEL = "$Z_m$ (-)"


FABRIC_QUESTIONS = dict(
    R="Fig. 9: do the contact normals' $R_{ii}$ stay close to 1/3 as $\\sigma_i$ changes?",
    H="Fig. 10: does the branch fabric's share $H_{ii}/\\mathrm{tr}\\,H$ change with $\\sigma_i$?",
    B="Fig. 12: do the $B_{ii}$ rise with $\\sigma_i$ in one trend for the three directions?",
    M="Fig. 12: do the $M_{iiii}$ rise with $\\sigma_i$ in one trend for the three directions?")


def fabric_vs_stress(rows, path, name, who=None):
    """Figs 9, 10, 12: the diagonal of a fabric tensor of the rows (R, B: name_ii; H: H_ii / tr H;
    M: M_iiii) against the stress in the same direction, one series per direction. Returns {axis:
    (sigma in kPa, values)}, the values as plotted."""
    plt = _plt()
    states = _by_state(rows)
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    out = {}
    trace = np.array([sum(float(st["H_" + a * 2]) for a in "xyz") for st in states]) if name == "H" else 1.0
    for axis, mark in zip("xyz", "os^"):
        col = name + "_" + axis * (4 if name == "M" else 2)
        s = np.array([float(st["sigma_" + axis]) for st in states]) / 1e3
        v = np.array([float(st[col]) for st in states]) / trace
        out[axis] = (s, v)
        ax.scatter(s, v, marker=mark, label="$%s_{%s}$" % (name, axis * (4 if name == "M" else 2))
                   + (r"$/\mathrm{tr}\,H$" if name == "H" else ""), alpha=0.8)
    ax.set_xlabel(r"$\sigma_i$ (kPa)")
    ax.set_ylabel(FABRIC_LABELS[name])
    entitle(fig, FABRIC_QUESTIONS[name], who)
    legend_outside(ax, fontsize=8)
    _finish(plt, fig, path)
    return out


def main(argv=None):
    from trueaniso import cli
    p = cli.Parser(prog="python3 -m trueaniso.analysis.figures", description="figures from a probes.csv")
    p.add_argument("csv", help="probe table of run_states.py or run_study.py")
    p.add_argument("--out", required=True, help="directory for the PNG files")
    p.add_argument("--title", help="what the figures are of, in their titles (default: the assembly, particle count "
                                   "and seed of the study's metadata.json beside the table)")
    o = p.parse_args(argv)
    try:
        problem = cli.output_problem(o.out)  # before any work: a refusal at the end would lose it
        if problem:
            raise ResultsError(problem)
        rows = read_probes(o.csv, need=("state", "probe", "E", "sigma_x", "sigma_y", "sigma_z", "Zm", "b", "q",
                                        "nu_1", "nu_2", "nu_1_name", "nu_2_name"))
        # The figures are of the normal probes (E, Poisson ratios); a shear probe's row (yz, xz, xy:
        # G, no E) is a valid row they do not use, and its empty E must not refuse the whole table.
        normal = [r for r in rows if r["probe"] in ("x", "y", "z")]
        if not normal:
            raise ResultsError("%s has no rows of normal probes (x, y, z), which the figures plot" % o.csv)
        for r in normal:
            for column in ("E", "sigma_x", "sigma_y", "sigma_z", "Zm", "b", "q", "nu_1", "nu_2"):
                number(r, column, o.csv)
        if rows.note:
            sys.stderr.write("note: %s\n" % rows.note)
        os.makedirs(o.out, exist_ok=True)
        who = o.title or study_who(o.csv)
        modulus_vs_stress(rows, os.path.join(o.out, "E_vs_sigma.png"), who)
        fits = scalar_moduli_vs_zm(rows, os.path.join(o.out, "K_G_vs_Zm.png"), who)
    except (ResultsError, OSError, ValueError) as exc:
        sys.stderr.write("error: %s\n" % said(exc))
        return 2
    # No fit (fewer than three complete states with distinct Zm) is said in words: 'K, G fits: None'.
    print("figures in %s; K, G fits: %s" % (o.out, fits if fits else "none (Fig. 11 needs 3 states probed on x, y "
                                                                    "and z with distinct Zm; no K_G_vs_Zm.png)"))
    return 0


if __name__ == "__main__":
    from trueaniso import cli
    cli.tool(main)
