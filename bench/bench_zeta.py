"""The rotation factor zeta by the two definitions side by side (not a test): fitted on the
contrast a_i^2 as the paper does (Fig. 13, trueaniso.zeta) and matched on the magnitude of E_i
(statics.rotation_factor, with Nc/V by Eq. 36 and counted); writes the table into docs/studies/statics.md
between <!-- zeta-contrast --> and <!-- /zeta-contrast -->.

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/bench_zeta.py --states results/default/states \\
        --csv docs/data/table-c1-spheres-4000.csv --csv results/default/probes.csv --doc docs/studies/statics.md

DEM E_i come from (a) exact static solves, rotations free and blocked, at the held-state
checkpoints in --states (N.npz, as pyscripts/run_states.py writes them), and (b) dynamic probes in
each --csv (one row per state and probe axis, with the fabric columns B_ij, M_ijkl, NcV_* that
trueaniso.fabric.fabric_row writes). The micromechanical a_i^2 of a CSV state is rebuilt from its
B and M and the particle material (--shear-modulus, --poisson), checked against the row's mic_E_*.
"""
import datetime
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
import numpy as np  # noqa: E402

from trueaniso.analysis import zeta_contrast  # noqa: E402
from trueaniso.analysis.zeta_contrast import DENSITIES, parts_of  # noqa: E402
from trueaniso import cli, dem, engines, specimen_file, statics, zeta  # noqa: E402

ISOTROPIC = 0.01  # relative spread of the principal stresses below which a state is isotropic


def options(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--states", help="directory of held-state checkpoints N.npz (static solves)")
    p.add_argument("--csv", action="append", default=[], help="probe table (repeatable)")
    p.add_argument("--shear-modulus", type=float, default=18e9, help="particle shear modulus of the CSV runs (Pa)")
    p.add_argument("--poisson", type=float, default=0.15, help="particle Poisson's ratio of the CSV runs")
    p.add_argument("--doc", help="markdown file whose zeta-contrast block is replaced")
    o = cli.parse(p, argv)
    if not o.states and not o.csv:
        raise cli.InputError("give --states and/or --csv: there is nothing to fit")
    if o.states and not os.path.isdir(o.states):
        raise cli.InputError("--states %s is not a directory" % o.states)
    for path in o.csv:
        if not os.path.isfile(path):
            raise cli.InputError("--csv %s does not exist" % path)
    if o.doc and not os.path.isfile(o.doc):
        raise cli.InputError("--doc %s does not exist" % o.doc)
    if not (o.shear_modulus > 0 and -1 < o.poisson < 0.5):
        raise cli.InputError("need --shear-modulus > 0 and -1 < --poisson < 0.5")
    return o


# ---------------------------------------------------------------------------- inputs

def checkpoint_paths(directory):
    paths = {}
    for name in os.listdir(directory):
        stem, ext = os.path.splitext(name)
        if ext == ".npz" and stem.isdigit():
            paths[int(stem)] = os.path.join(directory, name)
    if not paths:
        raise cli.InputError("no held-state checkpoints (N.npz) in %s" % directory)
    return [paths[k] for k in sorted(paths)]


def isotropic(sigma):
    sigma = np.asarray(sigma, dtype=float)
    return bool(np.ptp(sigma) < ISOTROPIC * np.mean(sigma))


# ---------------------------------------------------------------------------- sources

def static_sources(directory):
    """Sources (a): static solves at each checkpoint, rotations free and blocked."""
    free = dict(label="static solves, %s" % directory, rotations="free", states=[], E=[], sigma=[],
                parts={d: [] for d in DENSITIES}, check=[])
    blocked = dict(free, rotations="blocked", E=[], check=None)
    for path in checkpoint_paths(directory):
        scene, _ = specimen_file.load(path)
        dem.refresh(scene)
        r = {rot: statics.static_stiffness(scene, rotations=rot) for rot in (True, False)}
        free["states"].append(os.path.splitext(os.path.basename(path))[0])
        free["N"] = scene.num_bodies
        free["E"].append(r[True]["E"])
        blocked["E"].append(r[False]["E"])
        free["sigma"].append(np.diag(engines.stress(scene)))
        for d in DENSITIES:
            free["parts"][d].append(zeta.parts_from_scene(scene, d))
        # The existing definition, for the cross-check of magnitude_zeta (counted Nc/V is what the
        # static solve's affine parts carry).
        free["check"].append(statics.rotation_factor(scene, free=r[True], blocked=r[False]))
        print("state %s: E_free %s, E_blocked %s MPa" % (free["states"][-1], np.round(r[True]["E"] / 1e6, 1),
                                                          np.round(r[False]["E"] / 1e6, 1)), flush=True)
    blocked.update(N=free["N"], states=free["states"], sigma=free["sigma"], parts=free["parts"])
    return [free, blocked]


# ---------------------------------------------------------------------------- the two definitions

def contrast(src):
    fit = zeta.fit_contrast(src["E"], *parts_of(src))
    # The invariance that makes this definition independent of Nc/V: the counted parts give the same.
    other = zeta.fit_contrast(src["E"], *parts_of(src, "count"))
    fit["density_shift"] = max(abs(other["zeta_h"] - fit["zeta_h"]), abs(other["zeta_v"] - fit["zeta_v"]))
    return fit


def magnitude(src):
    out = {}
    for d in DENSITIES:
        z = [zeta.magnitude_zeta(a, s, E) for (a, s), E in zip(src["parts"][d], src["E"])]
        out[d] = np.array([[q["zeta_h"], q["zeta_v"]] for q in z])
    if src.get("check"):
        ref = np.array([[c["zeta_h"], c["zeta_v"]] for c in src["check"]])
        if not np.allclose(out["count"], ref, atol=1e-9):
            raise RuntimeError("magnitude_zeta disagrees with statics.rotation_factor: %s vs %s" % (out["count"], ref))
    return out


def signed_q_over_p(sigma):
    """Deviatoric stress ratio q/p, q = sqrt(3 J2) signed like Eq. (13) (positive when sigma_z > p)."""
    s = np.asarray(sigma, dtype=float)
    p = s.mean()
    q = np.sqrt(0.5 * ((s[0] - s[1]) ** 2 + (s[1] - s[2]) ** 2 + (s[2] - s[0]) ** 2))
    return np.copysign(q, s[2] - p) / p


def per_state(src, referenced):
    """(q/p, zeta) of one common zeta per anisotropic state, raw or relative to the isotropic state
    (Appendix B's reference point), the common fit over those states, and the isotropic state's
    a_i^2 (DEM, micromechanical at zeta = 1); None when a reference is asked for and there is none."""
    A_n, A_s = parts_of(src)
    iso = [k for k, sig in enumerate(src["sigma"]) if isotropic(sig)]
    if referenced and not iso:
        return None
    ref = (src["E"][iso[0]], A_n[iso[0]], A_s[iso[0]]) if referenced else None
    keep = [k for k in range(len(src["E"])) if k not in iso]
    out = [(signed_q_over_p(src["sigma"][k]),
            zeta.fit_common([src["E"][k]], [A_n[k]], [A_s[k]], reference=ref)["zeta"]) for k in keep]
    overall = zeta.fit_common(src["E"][keep], A_n[keep], A_s[keep], min_states=2, reference=ref)
    iso_a = (zeta.a_squared(ref[0]), zeta.predicted_a_squared(ref[1], ref[2], 1.0, 1.0)) if ref else None
    return out, overall, iso_a


# ---------------------------------------------------------------------------- tables

BANDS = ((-np.inf, -0.4), (-0.4, -0.2), (-0.2, 0.0), (0.0, 0.2), (0.2, 0.4), (0.4, np.inf))


def mean_sd(v):
    v = np.asarray(v)
    return "%.3f ± %.3f" % (np.mean(v), np.std(v, ddof=1) if len(v) > 1 else 0.0)


def main_row(src, fit, mag):
    cells = [src["label"], src["rotations"], "%d" % src["N"], "%d" % fit["n_states"],
             "%.3f ± %.3f" % (fit["zeta_h"], fit["se_h"]), "%.3f ± %.3f" % (fit["zeta_v"], fit["se_v"]),
             "%.4f" % fit["rms"], "%.3f ± %.3f" % (fit["zeta"], fit["se"]), "%.4f" % fit["rms_common"],
             "%.4f" % fit["rms_at_1"], "%.4f" % fit["rms_at_paper"]]
    cells += ["%s, %s" % (mean_sd(mag[d][:, 0]), mean_sd(mag[d][:, 1])) for d in DENSITIES]
    return "| " + " | ".join(cells) + " |"


def band_row(src, referenced):
    got = per_state(src, referenced)
    if got is None:
        return None
    states, overall, iso_a = got
    cells = []
    for lo, hi in BANDS:
        z = [v for qp, v in states if (lo < qp <= hi if hi <= 0 else lo <= qp < hi)]
        cells.append("%.2f (%d)" % (np.median(z), len(z)) if z else "-")
    return "| %s | %s | %s | %s | %.3f ± %.3f |" % (
        src["label"], src["rotations"],
        "isotropic state: DEM %s, mic. %s" % tuple(", ".join("%.3f" % v for v in a) for a in iso_a)
        if referenced else "none (a_i^2 = 1)",
        " | ".join(cells), overall["zeta"], overall["se"])


MAIN_HEADER = [
    "| source | rotations | N | states | **zeta_h** ± se | **zeta_v** ± se | rms a^2 at fit "
    "| common zeta ± se | rms at common | rms at zeta = 1 | rms at 0.552 "
    "| magnitude zeta_h, zeta_v, Nc/V Eq. 36 (mean ± sd) | magnitude zeta_h, zeta_v, Nc/V counted |",
    "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
BAND_HEADER = [
    "| source | rotations | reference point | q/p < -0.4 | -0.4 to -0.2 | -0.2 to 0 | 0 to 0.2 | 0.2 to 0.4 "
    "| > 0.4 | all anisotropic states: common zeta ± se |",
    "|---|---|---|---|---|---|---|---|---|---|"]


def main(o):
    t0 = time.time()
    sources, notes = [], []
    for path in o.csv:  # read and check every table before the (slower) static solves
        sources += zeta_contrast.sources(path, o.shear_modulus, o.poisson, notes=notes)
    for note in notes:  # a torn last row is left out: say so
        sys.stderr.write("note: %s\n" % note)
    if o.states:
        sources = static_sources(o.states) + sources
    lines, bands, shifts = list(MAIN_HEADER), list(BAND_HEADER), []
    for src in sources:
        src["E"] = np.array(src["E"], dtype=float)
        fit, mag = contrast(src), magnitude(src)
        shifts.append(fit["density_shift"])
        lines.append(main_row(src, fit, mag))
        print(lines[-1], flush=True)
        bands += [r for r in (band_row(src, False), band_row(src, True)) if r]
        print("\n".join(bands[-2:]), flush=True)
    wall = time.time() - t0
    head = ("Machine: %s. Run %s, %.0f s wall (static solves included). Command: `OMP_NUM_THREADS=%s %s`."
            % (_bench.machine(), datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), wall,
               os.environ.get("OMP_NUM_THREADS", "unset"), " ".join(["/usr/bin/python3"] + sys.argv)))
    notes = ("Contrast fits use the Nc/V of Eq. (36); with the counted Nc/V the fitted zeta_h, zeta_v move by at "
             "most %.1e (the fit's tolerance: Eq. 25 ignores a common factor of the E_i). se: standard error "
             "from the fit's Jacobian, two independent a_i^2 per state. Magnitude: per-state roots of "
             "`statics.rotation_factor` (E_i(zeta) of Eq. 40 = DEM E_i, zeta_h for (E_x + E_y)/2), mean ± sd "
             "over the same states." % max(shifts))
    band_notes = ("Per-state contrast zeta (one common zeta fitted to each anisotropic state alone), median "
                  "(number of states) per band of the signed stress ratio q/p (q > 0 when sigma_z > p); isotropic "
                  "states left out. Reference point: the a_i^2 of each state divided by those of the isotropic "
                  "state, DEM and micromechanical alike (Appendix B's (x0, y0)).")
    if o.doc:
        block = "\n\n".join([head, notes, "\n".join(lines), band_notes, "\n".join(bands)])
        _bench.replace_block(o.doc, "zeta-contrast", block)
    print(head)


if __name__ == "__main__":
    cli.guarded(lambda: main(options()))
