r"""The paper's Fig. 16 measures on a cross-anisotropic path (run_states.py --path cross-anisotropic):
per state, $E_h$, $E_v$, the shear moduli $G_{vh}$ and $G_{hh}$, and the anisotropy ratios of Eq. (24).

    /usr/bin/python3 pyscripts/trueaniso/analysis/cross_anisotropy.py results/fig16/probes.csv [--out fig16.json] [--figure fig16.png]

With $z$ vertical: $E_h$ is the mean of $E_x$ and $E_y$, $G_{vh}$ the mean of the two vertical planes'
$G_{yz}$ and $G_{xz}$, $G_{hh} = G_{xy}$. By Eq. (23), $G_{ij} = G a_i^2 a_j^2$, so
$G_{hh}/G_{vh} = a_h^2/a_v^2$, the ratio Eq. (24) equates with $(E_h/E_v)^{0.5}$ and with
$\nu_{hv}/\nu_{hh}$ (Eq. 22). Eq. (24) prints $G_{hh}/G_{vv}$; with $G_{vv} = G a_v^4$ that ratio
would be $(a_h^2/a_v^2)^2$, so it is read as $G_{hh}/G_{vh}$ (docs/cell.md). The micromechanical
prediction $a_h^2/a_v^2$ is $(E_h/E_v)^{0.5}$ of the fabric columns mic_E_* (Eqs. 35-37 with the
row's $\zeta$, then Eq. 25).
"""
import math
import os
import sys

if __package__ in (None, ""):  # run as a file: imported as trueaniso.analysis.cross_anisotropy all the same (PEP 366)
    sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    __package__ = "analysis"
from .results import SHEAR_PROBES, ResultsError, number, read_probes  # noqa: E402

NORMAL = ("x", "y", "z")
SHEAR = SHEAR_PROBES


def cross_anisotropic_moduli(E, G, nu=None):
    r"""The measures of one state from E {"x", "y", "z"}, G {"yz", "xz", "xy"} and optionally nu
    {"xy", "yx", "xz", "yz"} ($\nu_{ij} = -\Delta\varepsilon_j/\Delta\varepsilon_i$ of a probe on $i$, Eq. 11).

    G_vh_split $= \lvert G_{yz} - G_{xz} \rvert / G_{vh}$ measures the departure from cross-anisotropy (0
    for a cross-anisotropic medium)."""
    E_h = 0.5 * (E["x"] + E["y"])
    G_vh = 0.5 * (G["yz"] + G["xz"])
    out = dict(E_h=E_h, E_v=E["z"], G_vh=G_vh, G_hh=G["xy"], G_vh_split=abs(G["yz"] - G["xz"]) / G_vh,
               G_ratio=G["xy"] / G_vh, E_ratio_root=math.sqrt(E_h / E["z"]))
    if nu is not None:
        # Eq. (22): nu_ij = c a_i^2 / a_j^2: nu_hh = c, nu_hv = c a_h^2 / a_v^2
        nu_hh = 0.5 * (nu["xy"] + nu["yx"])
        nu_hv = 0.5 * (nu["xz"] + nu["yz"])
        out.update(nu_hh=nu_hh, nu_hv=nu_hv, nu_ratio=nu_hv / nu_hh)
    return out


# sigma_x and sigma_y of a cross-anisotropic state are one horizontal stress: the servo holds each
# within 100 Pa of 100 kPa (0.1 %); 1 % leaves room for a held state's drift and refuses any Table C1
# state with b between 0 and 1 (their horizontal stresses differ by 4 % or more).
HORIZONTAL_TOLERANCE = 0.01


def states(path):
    """[{state, sigma_v, sigma_h, measures...}] of the states with all six probes, in file order."""
    rows = read_probes(path, ("state", "probe", "E", "G", "sigma_x", "sigma_y", "sigma_z", "nu_1", "nu_2",
                              "nu_1_name", "nu_2_name"))
    if rows.note:  # rows left out (a NaN cell, a torn last row) are said, as the report and figures say them
        print("note: %s" % rows.note, file=sys.stderr)
    per = {}
    for r in rows:
        per.setdefault(r["state"], {})[r["probe"]] = r
    out = []
    for sid, probes in per.items():
        if not all(a in probes for a in NORMAL + SHEAR):
            continue
        E = {a: number(probes[a], "E", path) for a in NORMAL}
        G = {a: number(probes[a], "G", path) for a in SHEAR}
        nu = {}
        for a in NORMAL:
            for k in ("nu_1", "nu_2"):
                nu[probes[a][k + "_name"][3:]] = number(probes[a], k, path)
        r = probes["z"]
        sx, sy = number(r, "sigma_x", path), number(r, "sigma_y", path)
        if abs(sx - sy) > HORIZONTAL_TOLERANCE * 0.5 * abs(sx + sy):
            # A true-triaxial state (21: 60 and 100 kPa) is no point of Fig. 16, sigma_h their mean:
            # its x and y are not one horizontal direction.
            raise ResultsError("%s: state %s is not cross-anisotropic: sigma_x %.1f and sigma_y %.1f kPa differ (Fig. 16 "
                               "needs sigma_x = sigma_y: run_states.py --path cross-anisotropic)"
                               % (path, sid, sx / 1e3, sy / 1e3))
        m = cross_anisotropic_moduli(E, G, nu)
        m.update(state=sid, sigma_v=number(r, "sigma_z", path),
                 sigma_h=0.5 * (number(r, "sigma_x", path) + number(r, "sigma_y", path)))
        if "mic_E_x" in r and r["mic_E_x"] != "":
            mic_h = 0.5 * (number(r, "mic_E_x", path) + number(r, "mic_E_y", path))
            m["predicted_ratio"] = math.sqrt(mic_h / number(r, "mic_E_z", path))
            if r.get("mic_zeta", "") != "":
                m["predicted_zeta"] = number(r, "mic_zeta", path)
        out.append(m)
    if not out:
        raise ResultsError("%s has no state with all six probes (x, y, z, yz, xz, xy)" % path)
    return sorted(out, key=lambda m: m["sigma_v"])


def predicted_ratios(path, shear_modulus, poisson, zeta_h, zeta_v):
    """{state: $a_h^2/a_v^2$} of the micromechanical prediction at (zeta_h, zeta_v), from the
    fabric columns of a cross-anisotropic study's probe table (Eqs. 35-37 in the directional form
    of trueaniso.zeta, Eq. 40, then Eq. 25 as `states` takes it: $(E_h/E_v)^{0.5}$ of the mic_E_* columns)."""
    from . import zeta_contrast
    from trueaniso import zeta
    found = zeta_contrast.sources(path, shear_modulus, poisson, complete_only=True)
    src = next((f for f in found if f["rotations"] == "free"), found[0] if found else None)
    out = {}
    if src is not None:
        E = zeta.young_moduli(*zeta_contrast.parts_of(src), zeta_h, zeta_v)
        for sid, (Ex, Ey, Ez) in zip(src["states"], E):
            out[sid] = math.sqrt(0.5 * (Ex + Ey) / Ez)
    return out


def figure(rows, path, predictions=None, who=None):
    """Fig. 16: the anisotropy ratios against sigma_v / sigma_h. `predictions`: [(label, [$a_h^2/a_v^2$ per
    row][, line style])], the micromechanical curves, each labelled with its zeta; by
    default the rows' own predicted_ratio, at the zeta of the table's micromechanical columns.
    `who`: what the figure is of (figures.who_said), in its title."""
    from .figures import _finish, _plt, entitle, legend_outside
    plt = _plt()
    sr = [m["sigma_v"] / m["sigma_h"] for m in rows]
    fig, ax = plt.subplots(figsize=(8.4, 4.6))
    ax.plot(sr, [m["G_ratio"] for m in rows], "o-", label="$G_{hh}/G_{vh}$ (shear probes)")
    ax.plot(sr, [m["E_ratio_root"] for m in rows], "s-", label="$(E_h/E_v)^{0.5}$")
    if "nu_ratio" in rows[0]:
        ax.plot(sr, [m["nu_ratio"] for m in rows], "^-", label=r"$\nu_{hv}/\nu_{hh}$")
    if predictions is None and "predicted_ratio" in rows[0]:
        z = rows[0].get("predicted_zeta")
        predictions = [("$a_h^2/a_v^2$ predicted, " + (r"$\zeta$ = %g" % z if z is not None
                                                         else r"$\zeta$ of the table's columns"),
                        [m["predicted_ratio"] for m in rows])]
    for curve, style in zip(predictions or (), ("k--", "k:", "k-.")):
        ax.plot(sr, curve[1], curve[2] if len(curve) > 2 else style, label=curve[0])
    ax.set_xlabel(r"$\sigma_v/\sigma_h$ (-)")
    ax.set_ylabel("anisotropy ratio (-)")
    entitle(fig, r"Fig. 16: one anisotropy in $G$, $E$ and $\nu$? ($\sigma_h = 100$ kPa)", who)
    legend_outside(ax)
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)  # as --out's JSON (trueaniso.atomic)
    _finish(plt, fig, path)


def main(argv=None):
    from trueaniso import cli
    p = cli.Parser(prog="python3 -m trueaniso.analysis.cross_anisotropy", description=cli.description(__doc__))
    p.add_argument("probes", help="probes.csv of a cross-anisotropic study")
    p.add_argument("--out", help="JSON file for the per-state measures")
    p.add_argument("--figure", help="PNG of the ratios against sigma_v / sigma_h")
    o = p.parse_args(argv)
    from trueaniso import atomic
    try:
        # Where the outputs go, checked before any work: a missing directory is refused at once, not at the end.
        for option, path in (("--out", o.out), ("--figure", o.figure)):
            problem = path is not None and cli.output_problem(path, directory=False, option=option)
            if problem:
                raise ResultsError(problem)
        rows = states(o.probes)
    except ResultsError as exc:
        print("error: %s" % exc, file=sys.stderr)
        return 2
    for m in rows:
        print("%-8s sigma_v %6.1f kPa  G_vh %7.1f MPa  G_hh %7.1f MPa  G_hh/G_vh %.4f  (E_h/E_v)^0.5 %.4f  split %.4f"
              % (m["state"], m["sigma_v"] / 1e3, m["G_vh"] / 1e6, m["G_hh"] / 1e6, m["G_ratio"], m["E_ratio_root"],
                 m["G_vh_split"]))
    if o.out:
        atomic.write_json(o.out, rows)
    if o.figure:
        figure(rows, o.figure)
    return 0


if __name__ == "__main__":
    from trueaniso import cli
    cli.tool(main)
