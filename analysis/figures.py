"""Figures like the paper's, from a probes.csv of pyscripts/run_states.py.

    /usr/bin/python3 -m analysis.figures results/x/probes.csv --out docs/figures
"""
import argparse
import os
import sys

import numpy as np

from . import hyperelastic
from .results import ResultsError, number, read_probes


def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _save(fig, path):
    tmp = path + ".tmp.png"
    fig.savefig(tmp, dpi=130)
    os.replace(tmp, path)


def modulus_vs_stress(rows, path, title="sphere assembly"):
    """Fig. 3: E_i against sigma_i, one series per direction."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    for axis, mark in zip("xyz", "os^"):
        sel = [r for r in rows if r["probe"] == axis]
        s = [float(r["sigma_" + axis]) / 1e3 for r in sel]
        e = [float(r["E"]) / 1e6 for r in sel]
        ax.scatter(s, e, marker=mark, label="E_%s" % axis, alpha=0.8)
    ax.set_xlabel("sigma_i (kPa)")
    ax.set_ylabel("E_i (MPa)")
    ax.set_title("Young's moduli against the stress in their direction\n(%s)" % title, fontsize=10)
    ax.legend()
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)


def scalar_moduli_vs_zm(rows, path):
    """Fig. 11: K and G of the hyperelastic model against Zm, with quadratic fits."""
    plt = _plt()
    states = hyperelastic.states_from_rows(rows)
    z, K, G = [], [], []
    for st in states.values():
        if np.all(np.isfinite(st["E"])) and np.all(np.isfinite(st["nu"][~np.eye(3, dtype=bool)])):
            m = hyperelastic.scalar_moduli(st["E"], st["nu"])
            z.append(st["Zm"])
            K.append(m["K"] / 1e6)
            G.append(m["G"] / 1e6)
    if len(z) < 3:
        return None
    fig, ax = plt.subplots(figsize=(5.5, 4.2))
    out = {}
    for vals, name, mark in ((K, "K", "o"), (G, "G", "s")):
        c, r2 = hyperelastic.quadratic_fit(z, vals)
        xs = np.linspace(min(z), max(z), 50)
        ax.scatter(z, vals, marker=mark, label=name)
        ax.plot(xs, np.polyval(c, xs), label="%s fit, R^2 = %.3f" % (name, r2))
        out[name] = dict(c=c.tolist(), r2=r2)
    ax.set_xlabel("Zm")
    ax.set_ylabel("modulus (MPa)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, path)
    plt.close(fig)
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description="figures from a probes.csv")
    p.add_argument("csv", help="probe table of run_states.py or run_study.py")
    p.add_argument("--out", required=True, help="directory for the PNG files")
    p.add_argument("--title", default="sphere assembly", help="assembly named in the titles")
    o = p.parse_args(argv)
    try:
        rows = read_probes(o.csv, need=("state", "probe", "E", "sigma_x", "sigma_y", "sigma_z", "Zm", "b", "q",
                                        "nu_1", "nu_2", "nu_1_name", "nu_2_name"))
        for r in rows:
            for column in ("E", "sigma_x", "sigma_y", "sigma_z", "Zm", "b", "q", "nu_1", "nu_2"):
                number(r, column, o.csv)
        if rows.note:
            sys.stderr.write("note: %s\n" % rows.note)
        os.makedirs(o.out, exist_ok=True)
        modulus_vs_stress(rows, os.path.join(o.out, "E_vs_sigma.png"), o.title)
        fits = scalar_moduli_vs_zm(rows, os.path.join(o.out, "K_G_vs_Zm.png"))
    except (ResultsError, OSError, ValueError) as exc:
        sys.stderr.write("error: %s\n" % exc)
        sys.exit(2)
    print("figures in %s; K, G fits: %s" % (o.out, fits))


if __name__ == "__main__":
    main()
