"""The rotation factor zeta fitted on the contrast $a_i^2$ (trueaniso.zeta.fit_contrast), from a
study's probe table: the one route for the main job (run_study.py) and the benchmark (bench_zeta.py).

Each state's DEM $E_i$ are its x, y, z probe rows; its micromechanical parts (A_n, A_s of Eq. 37)
are rebuilt from the fabric columns of the row (B, the M components of Appendix A, Nc/V), which
trueaniso.fabric.fabric_row wrote, and the particle material. The rebuild is checked against the
row's own micromechanical moduli (mic_E_*), which pins the material and the columns.
"""
import collections

import numpy as np

from .results import SHEAR_PROBES, ResultsError, read_probes
from trueaniso import fabric, zeta

AXES = "xyz"
DENSITIES = ("eq36", "count")
NEEDED = (["state", "probe", "E", "rotations", "Np", "sigma_x", "sigma_y", "sigma_z", "NcV_eq36", "NcV_count",
           "mic_zeta", "mic_density"] + ["B_%s" % c for c in ("xx", "yy", "zz", "xy", "xz", "yz")]
          + ["M_" + "".join(AXES[k] for k in idx) for idx in fabric.M_COLUMNS] + ["mic_E_" + a for a in AXES])


def read_probe_table(path, complete_only=False, notes=None):
    """{(rotations, state): {axis: row}} in file order. A state without all three probes is an
    error, or left out with complete_only (a study still running, or resumed with fewer axes).
    What was left out of the file (a torn last row) is appended to `notes` if given."""
    rows = read_probes(path, NEEDED)
    if rows.note and notes is not None:
        notes.append(rows.note)
    states = collections.OrderedDict()
    for r in rows:
        if r["probe"] in SHEAR_PROBES:  # shear probes (G_ij) take no part in the E_i contrast
            continue
        per_axis = states.setdefault((r["rotations"], r["state"]), {})
        if r["probe"] not in ("x", "y", "z") or r["probe"] in per_axis:
            raise ResultsError("%s: state %s has a probe %r that is not a single x, y or z probe"
                               % (path, r["state"], r["probe"]))
        per_axis[r["probe"]] = r  # E_i > 0, which Eq. (25)'s roots need: checked by read_probes
    for key in list(states):
        if len(states[key]) != 3:
            if complete_only:
                del states[key]
                continue
            rot, s = key
            raise ResultsError("%s: state %s (rotations %s) lacks the %s probe(s)"
                               % (path, s, rot, ", ".join(a for a in AXES if a not in states[key])))
    return states


def fabric_of_row(r):
    """The fabric dict of a CSV row: B (symmetric) and the M components of Appendix A (the only
    ones Eqs. A1-A9 use; the rest stay 0)."""
    B = np.zeros((3, 3))
    for i in range(3):
        for j in range(i, 3):
            B[i, j] = B[j, i] = float(r["B_" + AXES[i] + AXES[j]])
    M = np.zeros((3, 3, 3, 3))
    for idx in fabric.M_COLUMNS:
        M[idx] = float(r["M_" + "".join(AXES[k] for k in idx)])
    return dict(B=B, M=M, NcV_eq36=float(r["NcV_eq36"]), NcV_count=float(r["NcV_count"]))


def check_rebuild(path, state, f, r, shear_modulus, poisson):
    """The rebuilt prediction must reproduce the row's mic_E_* (same zeta and Nc/V): this pins the
    material and the reconstruction of B and M from the columns."""
    p = fabric.prediction_from(f, shear_modulus, poisson, float(r["mic_zeta"]), r["mic_density"])
    mic = np.array([float(r["mic_E_" + a]) for a in AXES])
    if not np.allclose(p["E"], mic, rtol=1e-9, atol=0):
        raise ResultsError("%s state %s: B, M and the material (shear modulus %g, Poisson's ratio %g) give E = %s, "
                           "the row's mic_E = %s" % (path, state, shear_modulus, poisson, p["E"], mic))


def sources(path, shear_modulus, poisson, complete_only=False, notes=None):
    """One source per rotations value of the table: states, E (n, 3), parts per Nc/V, stresses;
    `notes` as read_probe_table's."""
    out = collections.OrderedDict()
    for (rot, state), per_axis in read_probe_table(path, complete_only, notes).items():
        r = per_axis["z"]
        f = fabric_of_row(r)
        check_rebuild(path, state, f, r, shear_modulus, poisson)
        src = out.setdefault(rot, dict(label="dynamic probes, %s" % path.split("/")[-1], rotations=rot,
                                       N=int(r["Np"]), states=[], E=[], sigma=[], parts={d: [] for d in DENSITIES}))
        src["states"].append(state)
        src["E"].append([float(per_axis[a]["E"]) for a in AXES])
        src["sigma"].append([float(r["sigma_" + a]) for a in AXES])
        for d in DENSITIES:
            src["parts"][d].append(zeta.parts_from_fabric(f, shear_modulus, poisson, d))
    return list(out.values())


def parts_of(src, density="eq36"):
    return tuple(np.array([p[k] for p in src["parts"][density]]) for k in (0, 1))


def fit(path, shear_modulus, poisson, min_states=2, rotations=None):
    """zeta_h, zeta_v over the complete states of a single-rotations table, or of its rows of
    `rotations` (free, restrained) in a mixed one (fit_contrast's dict without its arrays, plus the
    states used, and "notes": what was left out of the file, a torn last row), or None with fewer
    than `min_states` states."""
    notes = []
    found = sources(path, shear_modulus, poisson, complete_only=True, notes=notes)
    if rotations is not None:
        found = [s for s in found if s["rotations"] == rotations]
    if len(found) > 1:
        raise ResultsError("%s mixes rotations %s; fit them one at a time (--rotations)"
                           % (path, [s["rotations"] for s in found]))
    if not found or len(found[0]["states"]) < min_states:
        return None
    src = found[0]
    result = zeta.fit_contrast(np.array(src["E"], dtype=float), *parts_of(src), min_states=min_states)
    out = {k: v for k, v in result.items() if not isinstance(v, np.ndarray)}
    out["states"] = list(src["states"])
    out["notes"] = notes
    return out


def said(contrast):
    """The fit as one line, with its standard errors, and said when it stopped at a bound of the
    search (two states can give zeta_h = 0.000, the bound, +/- 0.19: no calibration).
    run_study.py's line and this module's command print it."""
    bound = ("; at a bound of the search (%g-%g): not determined by these states" % zeta.ZETA_BOUNDS
             if contrast["at_bound"] else "")
    return ("zeta calibrated on the contrast a_i^2 (Eq. 25) over %d states, as the paper's Fig. 13: "
            "zeta_h = %.3f +/- %.3f, zeta_v = %.3f +/- %.3f%s (rms of a_i^2 %.4f; %.4f at the paper's 0.552, "
            "%.4f at 1)" % (contrast["n_states"], contrast["zeta_h"], contrast["se_h"], contrast["zeta_v"],
                            contrast["se_v"], bound, contrast["rms"], contrast["rms_at_paper"], contrast["rms_at_1"]))


def main(argv=None):
    """python3 -m trueaniso.analysis.zeta_contrast DIR: the fit of a study (its directory or probes.csv), the
    material from its metadata.json unless given."""
    import sys
    from trueaniso import cli
    from .results import read_metadata, said as said_error, table_path
    p = cli.Parser(prog="python3 -m trueaniso.analysis.zeta_contrast", description=cli.description(__doc__))
    p.add_argument("results", help="a study's directory (with probes.csv) or its probe table")
    p.add_argument("--shear-modulus", type=cli.positive,
                   help="particle shear modulus (Pa) if not in the study's metadata")
    p.add_argument("--poisson", type=cli.poisson_ratio,
                   help="particle Poisson's ratio if not in the study's metadata")
    p.add_argument("--rotations", choices=("free", "restrained"),
                   help="the rows to fit in a table that holds both (one fit a rotations setting)")
    o = p.parse_args(argv)
    try:
        path = table_path(o.results)
        read_probes(path, NEEDED)  # a file that is no probe table says so before the material is asked for
        import os
        material = ((read_metadata(os.path.dirname(os.path.abspath(path))) or {}).get("specimen") or {}).get("material")
        G = o.shear_modulus if o.shear_modulus is not None else (material or {}).get("shear_modulus")
        nu = o.poisson if o.poisson is not None else (material or {}).get("poisson")
        if G is None or nu is None:
            raise ResultsError("%s records no particle material: give --shear-modulus and --poisson" % o.results)
        contrast = fit(path, float(G), float(nu), rotations=o.rotations)
    except (ResultsError, OSError, ValueError) as exc:
        sys.stderr.write("error: %s\n" % said_error(exc))
        return 2
    if contrast is None:
        sys.stderr.write("error: %s has fewer than 2 states probed on x, y and z%s: nothing to fit\n"
                         % (o.results, "" if o.rotations is None else " with rotations %s" % o.rotations))
        return 2
    for note in contrast["notes"]:  # a fit that left a row out says so
        sys.stderr.write("note: %s\n" % note)
    print(said(contrast))
    return 0


if __name__ == "__main__":
    from trueaniso import cli
    cli.tool(main)
