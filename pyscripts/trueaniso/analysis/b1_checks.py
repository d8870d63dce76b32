"""Table B1's statics records checked against the study they sit in, before the report shows them.

A record (statics_state-ID.json, statics_isotropic.json: trueaniso.statics.state_record) names its
study (`study`: the specimen's checksum, the particles' material, their number, the state's id and
definition; statics.identity), and each must be the study's of its directory: its metadata.json's
specimen, material, size and state. A record that names none (written before records carried it)
is tied to its study by its stresses instead, which are its state's row of probes.csv (or, for the
specimen's own record, specimen_state.json) to the last digit: the solve and the row read the same
checkpoint. Every record's stresses must also be its state's (Eq. 9, within the 2 % a probe
holds) and its moduli those a packing of its material can have (elastic_bounds). So records of
states 1 and 21 swapped, a 300-sphere record in a 4000-sphere study's directory or an E_blocked of
1e30 Pa are refused in one line naming the file and the field, not printed in Table B1.

A record borrowed from another study (report --b1-data) passes the same checks against its own
directory, and its particles' material must be the report's study's: one of another material is
refused, or shown so marked when the user asks for it (--b1-other-material).
"""
import json
import math
import os

from trueaniso import elastic_bounds, results_csv, stress_states

from .results import PAPER_MATERIAL, ResultsError
from .row_checks import HOLD_MISMATCH

MODULI = ("E_blocked", "E_free", "E_kinematic")
# The same stresses to the last digit (written by one Python from one float): kept away from 0 only
# so that a record rounded by a JSON writer of another language still ties.
SAME_STRESS = 1e-12
MATERIAL_KEYS = ("shear_modulus", "poisson", "density")


def _said_material(m):
    return "G = %.6g Pa, nu = %.4g" % (m["shear_modulus"], m["poisson"])


def same_material(a, b):
    """Whether two materials (shear_modulus, poisson[, density]) are one: every key both give."""
    return all(math.isclose(float(a[k]), float(b[k]), rel_tol=1e-12) for k in MATERIAL_KEYS if k in a and k in b)


def _definition(label, meta):
    """(b, sigma_z, path) of the record's state from its study's metadata, else from its id."""
    path = ((meta or {}).get("fingerprint") or {}).get("path", "true-triaxial")
    d = ((meta or {}).get("states") or {}).get(label)
    if d is not None:
        return float(d["b"]), float(d["sigma_z"]), path
    defined = stress_states.defined_by_id(label)
    return (defined[0], defined[1], path) if defined else None


def _row_stresses(directory, label):
    """sigma_x, y, z of the state's first row of probes.csv in `directory`, or None."""
    try:
        rows = results_csv.read(os.path.join(directory, "probes.csv")).rows
    except (results_csv.TableError, OSError, UnicodeDecodeError):
        return None
    for r in rows:
        if r.get("state") == label:
            try:
                return [float(r["sigma_" + a]) for a in "xyz"]
            except (KeyError, ValueError):
                return None
    return None


def _specimen_stresses(directory):
    try:
        with open(os.path.join(directory, "specimen_state.json")) as f:
            st = json.load(f)
        return [float(st["sigma_" + a]) for a in "xyz"]
    except (OSError, ValueError, KeyError, TypeError):
        return None


def record_problem(path, label, record, directory, meta):
    """Why the record in `path` (Table B1's `label`: 'isotropic' or '21') is not its study's, or
    None. `meta`: the metadata.json of `directory` (None for a directory without one)."""
    state_id = "isotropic" if os.path.basename(path) == "statics_isotropic.json" else \
        os.path.basename(path)[len("statics_state-"):-len(".json")]
    sigma = record.get("sigma")
    material = ((meta or {}).get("specimen") or {}).get("material") or \
        (record.get("study") or {}).get("material") or PAPER_MATERIAL
    # Its moduli: those of a packing of its material, at its stress (else at the state's).
    definition = None if state_id == "isotropic" else _definition(state_id, meta)
    if sigma:
        mean = sum(sigma) / 3.0
    elif definition is not None:
        mean = sum(stress_states.path_principal_stresses(definition[2], definition[0], definition[1])) / 3.0
    else:
        mean = math.nan
    for key in MODULI:
        for axis, value in zip("xyz", record.get(key) or ()):
            problem = elastic_bounds.modulus_problem(value, mean, material, "%s[%s]" % (key, axis))
            if problem:
                return "%s: %s" % (path, problem)
    # Its stresses: its state's.
    if sigma and definition is not None:
        goal = stress_states.path_principal_stresses(definition[2], definition[0], definition[1])
        scale = max(abs(g) for g in goal)
        for axis, have, want in zip("xyz", sigma, goal):
            if abs(have - want) > HOLD_MISMATCH * scale:
                return ("%s: sigma[%s] = %.6g Pa, but state %s is at %.6g Pa (Eq. 9, b = %g, sigma_z = %.6g Pa): it is "
                        "the record of another state" % (path, axis, have, state_id, want, definition[0], definition[1]))
    elif sigma and state_id == "isotropic" and max(sigma) - min(sigma) > HOLD_MISMATCH * max(abs(x) for x in sigma):
        return ("%s: sigma = (%s) Pa is not an isotropic state: it is the record of another state"
                % (path, ", ".join("%.6g" % x for x in sigma)))
    study = record.get("study")
    if study is not None:
        return _identity_problem(path, state_id, study, meta, directory)
    # A record that names no study: tied by its stresses to the row of its state.
    theirs = _specimen_stresses(directory) if state_id == "isotropic" else _row_stresses(directory, state_id)
    if theirs is None:
        return ("%s names no study (written before records did) and %s has no %s to tie it to: it cannot be shown as "
                "this study's; solve it again (remove it, then `report DIR --statics`, or run_study.py)"
                % (path, directory, "specimen_state.json" if state_id == "isotropic" else
                   "row of state %s in probes.csv" % state_id))
    if sigma is None or not all(math.isclose(a, b, rel_tol=SAME_STRESS, abs_tol=0) for a, b in zip(sigma, theirs)):
        return ("%s names no study, and its stresses (%s) Pa are not those of %s (%s) Pa: it is not this study's "
                "record of state %s" % (path, ", ".join("%.12g" % x for x in sigma or ()),
                                       "specimen_state.json" if state_id == "isotropic" else
                                       "state %s's row of probes.csv" % state_id,
                                       ", ".join("%.12g" % x for x in theirs), state_id))
    return None


def _identity_problem(path, state_id, study, meta, directory):
    if meta is None:
        return None  # nothing to compare with: the report says the study is unrecorded
    fp, spec = meta.get("fingerprint") or {}, meta.get("specimen") or {}
    if fp.get("specimen") and study.get("specimen") != fp["specimen"]:
        return ("%s: study.specimen %s... is not the specimen of the study in %s (%s...): a record of another study"
                % (path, str(study.get("specimen"))[:12], directory, fp["specimen"][:12]))
    if spec.get("material") and not same_material(study.get("material") or {}, spec["material"]):
        return ("%s: study.material (%s) is not the material of the study in %s (%s): a record of another study"
                % (path, _said_material(study["material"]), directory, _said_material(spec["material"])))
    n = (spec.get("summary") or {}).get("n")
    if n is not None and study.get("n") != n:
        return ("%s: study.n = %s particles, but the study in %s has %s: a record of another study"
                % (path, study.get("n"), directory, n))
    state = study.get("state") or {}
    if str(state.get("id")) != state_id:
        return "%s: study.state.id = %s: it is the record of state %s, not of %s" % (path, state.get("id"), state.get("id"),
                                                                                  state_id)
    if state_id != "isotropic":
        d = (meta.get("states") or {}).get(state_id)
        if d is not None and not (math.isclose(float(state.get("b", math.nan)), float(d["b"]), rel_tol=1e-12, abs_tol=1e-15)
                                  and math.isclose(float(state.get("sigma_z", math.nan)), float(d["sigma_z"]),
                                                   rel_tol=1e-12)):
            return ("%s: study.state is b = %s, sigma_z = %s Pa, but the study in %s defines state %s as b = %s, "
                    "sigma_z = %s Pa" % (path, state.get("b"), state.get("sigma_z"), directory, state_id, d["b"],
                                         d["sigma_z"]))
    return None


def borrowed_material_problem(directory, meta, material, where):
    """Why the records of `directory` (another study, its metadata.json `meta`) cannot stand beside
    the report's study of `material` (from `where`), or None."""
    theirs = ((meta or {}).get("specimen") or {}).get("material")
    if theirs is None:
        return ("%s records no particle material (its metadata.json): its records cannot be compared with this "
                "study's" % directory)
    if not same_material(theirs, material):
        return ("%s is a study of particles of %s, this report's of %s (%s): its moduli are of another material; "
                "give --b1-other-material to show them anyway, marked so in Table B1"
                % (directory, _said_material(theirs), _said_material(material), where))
    return None


def check(directory, records, meta):
    """Raise ResultsError for the first record of `records` ({label: (path, record)}) that is not
    its study's."""
    for label, (path, rec) in records.items():
        problem = record_problem(path, label, rec, directory, meta)
        if problem:
            raise ResultsError(problem)
