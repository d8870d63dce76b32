r"""What a probe table's rows say of themselves, checked before any analysis uses them.

A table that fits its schema (schemas/probes.schema.json) can still be wrong: two column headers
swapped ($\sigma_x$ and $\sigma_z$, E and gamma), a column scaled, a row of one state under another's
id. Every reader of a table (results.read_probes) refuses such a table in one line naming the
file, the line, the state and probe, and the field. Each row is checked against:

- its state's definition: a state's id that defines it (a Table C1 number, ``b<b>_sz<sigma_z>``,
  ``sv<sigma_v>``: stress_states.defined_by_id) must be the row's b and sigma_z goal;
- Eq. (9): its measured normal stresses must be those of its b and sigma_z goal at its path's
  mean stress, within triaxial's HOLD_MISMATCH (2 % of the largest): a probe holds the state it
  was told to, and refuses to start farther from it than that, so no row written is farther;
- its probe's size gamma (Eq. 12): a strain, so a number far below 1 (MAX_GAMMA);
- its modulus (E, or G of a shear probe) within the physical bounds of a packing of its material
  (elastic_bounds.modulus_problem);

and each state probed on x, y and z: its compliance symmetric (reciprocity $\nu_{ij}/E_i = \nu_{ji}/E_j$)
and positive definite (elastic_bounds.compliance_problem).
Columns a table does not have (older tables) are not checked.
"""
import math

from trueaniso import elastic_bounds, stress_states

# Kept here, not imported from triaxial (which loads the compiled module): the probe's own limit.
HOLD_MISMATCH = 0.02
# A probe is a strain of 1e-8 to 1e-5 (triaxial.GAMMA_RANGE); 1e-2 is no longer elastic by far.
MAX_GAMMA = 1e-2
NORMAL = ("x", "y", "z")


class RowProblem(ValueError):
    """One row that no study writes: the message names its line, state, probe and field."""


def _value(r, column):
    text = r.get(column)
    if text in (None, ""):
        return None
    try:
        x = float(text)
    except ValueError:
        return None  # the schema's check names a cell that is no number
    return x if math.isfinite(x) else None


def _where(line, r):
    return "line %d (state %s probe %s)" % (line, r.get("state"), r.get("probe"))


def _close(x, y, rel=1e-9, absolute=0.0):
    return abs(x - y) <= max(rel * max(abs(x), abs(y)), absolute)


def _path(r):
    path = r.get("path") or ("cross-anisotropic" if str(r.get("state", "")).startswith("sv") else "true-triaxial")
    return path if path in stress_states.PATHS else None


def row_problem(line, r, material):
    """Why one row is not what a study writes, or None."""
    where = _where(line, r)
    b, sz = _value(r, "b"), _value(r, "sigma_z_goal")
    defined = stress_states.defined_by_id(r.get("state"))
    path = _path(r)
    if defined is not None and path is not None:
        # sv ids keep sigma_v to 0.1 Pa (triaxial.cross_anisotropic_states)
        tolerance = 0.05 if str(r.get("state")).startswith("sv") else 0.0
        for column, have, want in (("b", b, defined[0]), ("sigma_z_goal", sz, defined[1])):
            if have is not None and not _close(have, want, absolute=tolerance):
                return ("%s: %s = %.12g, but state %s is defined with %s = %.12g (a row of another state, or an "
                        "edited column?)" % (where, column, have, r.get("state"), column, want))
    if b is not None and sz is not None and path is not None:
        try:
            goal = stress_states.path_principal_stresses(path, b, sz)
        except (ValueError, ZeroDivisionError):
            goal = None
        measured = [_value(r, "sigma_" + a) for a in "xyz"]
        if goal is not None and None not in measured:
            scale = max(abs(g) for g in goal)
            for axis, have, want in zip("xyz", measured, goal):
                if abs(have - want) > HOLD_MISMATCH * scale:
                    return ("%s: sigma_%s = %.6g Pa, but Eq. (9) gives %.6g Pa for its b = %g and sigma_z goal %.6g Pa "
                            "on the %s path; a probe holds its state within %g %% (swapped or edited columns?)"
                            % (where, axis, have, want, b, sz, path, 100 * HOLD_MISMATCH))
    gamma = _value(r, "gamma")
    if gamma is not None and not 0 < gamma < MAX_GAMMA:
        return ("%s: gamma = %.6g is no probe's strain (a probe strains by 1e-8 to 1e-5, Eq. 12; swapped or edited "
                "columns?)" % (where, gamma))
    measured = [_value(r, "sigma_" + a) for a in "xyz"]
    mean = sum(measured) / 3.0 if None not in measured else math.nan
    column = "G" if r.get("probe") in ("yz", "xz", "xy") else "E"
    modulus = _value(r, column)
    if modulus is not None:
        problem = elastic_bounds.modulus_problem(modulus, mean, material, column)
        if problem:
            return "%s: %s" % (where, problem)
    return None


def states_problem(rows):
    """Why a state probed on x, y and z (one rotations setting and sign) is no elastic solid, or
    None. rows: [(line, row)]."""
    states = {}
    for line, r in rows:
        if r.get("probe") in NORMAL:
            states.setdefault((r.get("rotations"), r.get("state"), r.get("sign")), {})[r["probe"]] = (line, r)
    for (rotations, sid, _), probes in states.items():
        if len(probes) < 3:
            continue
        E, nu = {}, {}
        try:
            for axis, (_, r) in probes.items():
                E[axis] = float(r["E"])
                for k in ("1", "2"):
                    name = r["nu_%s_name" % k]
                    if not (name.startswith("nu_") and len(name) == 5 and name[3] == axis):
                        raise RowProblem("line %d (state %s probe %s): nu_%s_name = %r is not a ratio of its probe "
                                         "(nu_%s<j>)" % (probes[axis][0], sid, axis, k, name, axis))
                    nu[(name[3], name[4])] = float(r["nu_" + k])
        except (KeyError, ValueError, TypeError) as exc:
            if isinstance(exc, RowProblem):
                return str(exc)
            continue  # a column missing or empty: the schema's and the modulus checks speak for it
        if set(nu) != {(a, b) for a in NORMAL for b in NORMAL if a != b} or \
                not all(math.isfinite(x) and x != 0 for x in E.values()) or not all(map(math.isfinite, nu.values())):
            continue  # a NaN is left out by the schema's check, a zero E refused by the modulus check
        problem = elastic_bounds.compliance_problem(E, nu)
        if problem:
            lines = ", ".join(str(probes[a][0]) for a in NORMAL)
            return "lines %s (state %s, rotations %s, probes x, y, z): %s" % (lines, sid, rotations or "?", problem)
    return None


def table_problem(rows, material):
    """Why the rows (dicts of text, line 2 on) are not a probe table's, or None (module doc)."""
    for line, r in enumerate(rows, start=2):
        problem = row_problem(line, r, material)
        if problem:
            return problem
    return states_problem(list(enumerate(rows, start=2)))
