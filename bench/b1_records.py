"""Table B1's statics records of a study measured by `clump_recipe_variants.py --study`, in the form
a study keeps them (statics_state-1.json, statics_state-21.json: trueaniso.statics.state_record),
so that `trueaniso.analysis.report --b1-data DIR` reads them as it reads a study's own.

The study's statics.json holds each state's static E_i with rotations restrained (E_blocked) and
free, and its stresses; the kinematic (zeta = 1) prediction E_kinematic is the micromechanical
prediction of the state's probes.csv row at the counted contact density, which is the static
solve's affine stiffness (a test checks the two on a committed study). The study's metadata.json is
copied beside the records: it says what specimen they are of, and its size.

    /usr/bin/python3 bench/b1_records.py docs/data/clump-recipes/state21-recipe-s1 \
        --out docs/data/b1-clump2-1000-s1
"""
import json
import os
import shutil
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)

import numpy as np  # noqa: E402

from trueaniso import cli  # noqa: E402

STATES = ("1", "21")


def kinematic_moduli(row, material):
    """E_x, E_y, E_z of the kinematic (zeta = 1) prediction from a probes.csv row's fabric, at the
    counted contact density (Nc/V), as the static solve's affine stiffness gives them."""
    from trueaniso.analysis import zeta_contrast
    from trueaniso import fabric
    f = zeta_contrast.fabric_of_row(row)
    return [float(x) for x in fabric.prediction_from(f, material["shear_modulus"], material["poisson"], 1.0,
                                                     "count")["E"]]


def identity(meta, sid):
    """The record's study, as trueaniso.statics.identity writes it, from the study's metadata.json."""
    spec, d = meta["specimen"], meta["states"][sid]
    return dict(specimen=meta["fingerprint"]["specimen"], n=int(spec["summary"]["n"]),
                material={k: float(spec["material"][k]) for k in ("shear_modulus", "poisson", "density")},
                state=dict(id=sid, b=float(d["b"]), sigma_z=float(d["sigma_z"]),
                           path=meta["fingerprint"].get("path", "true-triaxial")))


def records(study):
    """{state: record} for states 1 and 21 of the study: E_blocked, E_free and sigma from its
    statics.json, E_kinematic from its probes.csv; refused where the two are not of one state."""
    from trueaniso.analysis import report
    from trueaniso.analysis.results import ResultsError, read_probes
    with open(os.path.join(study, "statics.json")) as f:
        measured = json.load(f)
    material, _ = report._material(study)
    if material is None:
        raise ResultsError("%s: its metadata.json records no material" % study)
    rows = read_probes(os.path.join(study, "probes.csv"), need=["state", "sigma_x", "sigma_y", "sigma_z"])
    from trueaniso.analysis.results import read_metadata
    meta = read_metadata(study, required=True)
    out = {}
    for sid in STATES:
        st = measured[sid]
        row = next((r for r in rows if r["state"] == sid), None)
        if row is None:
            raise ResultsError("%s: probes.csv has no row of state %s" % (study, sid))
        sigma = [float(row["sigma_" + a]) for a in "xyz"]
        if not np.allclose(sigma, st["sigma"], rtol=1e-12, atol=0):
            raise ResultsError("%s: state %s has stresses %s in statics.json but %s in probes.csv"
                               % (study, sid, st["sigma"], sigma))
        out[sid] = dict(E_blocked=st["E_restrained"], E_free=st["E_free"], E_kinematic=kinematic_moduli(row, material),
                        sigma=st["sigma"], rattlers=st["rattlers_free"], study=identity(meta, sid))
    return out


def main(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("study", help="a run_states.py study with the statics.json of clump_recipe_variants.py --study")
    p.add_argument("--out", required=True, help="directory for statics_state-1.json, statics_state-21.json "
                                                "and the study's metadata.json")
    o = cli.parse(p, argv)
    from trueaniso import atomic, validate
    recs = records(o.study)
    os.makedirs(o.out, exist_ok=True)
    for sid, rec in recs.items():
        path = os.path.join(o.out, "statics_state-%s.json" % sid)
        atomic.write_json(path, rec)
        validate.load_json(path, "statics_record")
    shutil.copy(os.path.join(o.study, "metadata.json"), os.path.join(o.out, "metadata.json"))
    print(", ".join(os.path.join(o.out, "statics_state-%s.json" % sid) for sid in STATES))


if __name__ == "__main__":
    cli.guarded(main)
