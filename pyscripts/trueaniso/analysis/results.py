"""Reading a study's probe table (probes.csv) for analysis: the one route every analysis takes.

The table is read by the same code that writes it (trueaniso/results_csv.py), so a row cut short
by an interrupted run is recognised and left out rather than read as numbers, and anything else
wrong with the file is one ``ResultsError`` line, never a traceback.
"""
import math
import os

from trueaniso import results_csv, study_checks, validate

from . import row_checks

__all__ = ["read_probes", "read_metadata", "ResultsError"]

# The paper's particles (section 2.1): the material a table's moduli are bounded with when no
# metadata.json says its own.
PAPER_MATERIAL = dict(shear_modulus=18e9, poisson=0.15)


class ResultsError(ValueError):
    """A results file that cannot be analysed; the message is one line for the user."""


def said(exc):
    """An error as the tools' one line: an OSError by its file and its reason ('/x/report: Read-only
    file system'), not Python's '[Errno 30] Read-only file system: ...'."""
    if isinstance(exc, OSError) and exc.strerror:
        return "%s: %s" % (exc.filename, exc.strerror) if exc.filename else exc.strerror
    return str(exc)


class Probes(list):
    """The complete rows of a probe table; ``note`` says what was left out, if anything."""
    note = None


SHEAR_PROBES = ("yz", "xz", "xy")


def table_path(path):
    """A probe table's path: the file given, or a study directory's probes.csv."""
    if os.path.isdir(path):
        inside = os.path.join(path, "probes.csv")
        if not os.path.isfile(inside):
            raise ResultsError("%s is a directory without probes.csv (a study's probe table, written by "
                               "run_states.py or run_study.py)" % path)
        return inside
    if not os.path.isfile(path):
        raise ResultsError("%s does not exist (a probe table is written by run_states.py or run_study.py)" % path)
    return path


def _check_rows(path, rows, columns):
    """One row a probe, and its modulus a positive number: a table appended twice was analysed as
    it came, and a NaN or negative E changed the fits and the reversals without a word (an outside
    try); the report alone refused them, and named no row."""
    seen = {}
    for line, r in enumerate(rows, start=2):  # line 1 is the header
        key = (r.get("rotations"), r.get("state"), r.get("probe"), r.get("sign"))
        if key in seen:
            raise ResultsError("%s: state %s probe %s (rotations %s) is in lines %d and %d: one row a probe "
                               "(a table appended twice?)" % (path, r.get("state"), r.get("probe"),
                                                             r.get("rotations") or "?", seen[key], line))
        seen[key] = line
        shear = r.get("probe") in SHEAR_PROBES
        modulus = "G" if shear else "E"
        if modulus in columns:
            try:
                value = number(r, modulus, path)
            except ResultsError as exc:
                raise ResultsError("%s (line %d)" % (exc, line)) from None
            if not (math.isfinite(value) and value > 0):
                raise ResultsError("%s: state %s probe %s has %s = %r, not a positive number (line %d)"
                                   % (path, r.get("state"), r.get("probe"), modulus, r[modulus], line))
        for ratio in () if shear else ("nu_1", "nu_2"):  # a NaN Poisson's ratio passed every tool
            if ratio in columns and r.get(ratio, "") != "":
                try:
                    ok = math.isfinite(float(r[ratio]))
                except ValueError:
                    ok = False
                if not ok:
                    raise ResultsError("%s: state %s probe %s has %s = %r, not a finite number (line %d)"
                                       % (path, r.get("state"), r.get("probe"), ratio, r[ratio], line))


def read_probes(path, need=("state", "probe", "E"), material=None):
    """The rows of a study's probe table, checked, for analysis (module doc).

    Each row is checked against what it says of itself (`row_checks`: its stresses against its
    state's definition by Eq. 9, its moduli against the material's bounds, each state's
    reciprocity), not only against the table's schema.

    Args:
        path: the table (probes.csv) or a study directory holding it.
        need: columns the table must have.
        material: dict with ``shear_modulus`` (Pa) and ``poisson`` of the particles, whose bounds the
            moduli are held to (None: the study's metadata.json's, else the paper's particles).

    Returns:
        Probes: a list of rows, each a dict of text by column (reference/formats/probes-csv), state
        ids normalised (``21.0`` is ``21``); its ``note`` says what was left out (a row cut short,
        rows with a NaN cell), or is None.

    Raises:
        ResultsError: a missing or unreadable table, a missing column, a probe in two rows, a modulus
            that is not a positive number, rows of another specimen than the study's, a row that
            disagrees with its state or the material; in one line naming file, line and field.

    Example:
        >>> from trueaniso.analysis import results
        >>> rows = results.read_probes("docs/data/spheres-53004-s1")
        >>> r = next(r for r in rows if r["state"] == "21" and r["probe"] == "z")
        >>> print("%d rows; state 21: E_z = %.0f MPa" % (len(rows), float(r["E"]) / 1e6))
        117 rows; state 21: E_z = 345 MPa
    """
    path = table_path(path)
    try:
        table = results_csv.read(path)
    except (results_csv.TableError, UnicodeDecodeError) as exc:
        raise ResultsError("%s is not a readable probe table (%s)" % (path, exc)) from None
    if not table.rows:
        raise ResultsError("%s has no complete rows" % path)
    missing = [c for c in need if c not in table.columns]
    if missing:
        raise ResultsError("%s lacks the columns %s" % (path, ", ".join(missing[:6]) + (" ..." if len(missing) > 6 else "")))
    _check_rows(path, table.rows, table.columns)
    meta = None
    if os.path.basename(path) == "probes.csv":  # a study's table: its rows are the study's states
        meta = read_metadata(os.path.dirname(os.path.abspath(path)))
        problem = meta and study_checks.rows_problem(meta, table.rows)
        if problem:
            raise ResultsError("%s: %s" % (path, problem))
    # A table away from its metadata.json (renamed, copied) still holds one specimen's rows.
    mixed = study_checks.mixed_specimens_problem(table.rows)
    if mixed:
        raise ResultsError("%s: %s" % (path, mixed))
    if material is None:
        material = ((meta or {}).get("specimen") or {}).get("material") or PAPER_MATERIAL
    problem = row_checks.table_problem(table.rows, material)
    if problem:
        raise ResultsError("%s: %s" % (path, problem))
    kept, notes = _fitting_rows(path, table.rows)
    out = Probes(kept)
    if table.torn is not None:
        notes.insert(0, "%s: the last row was cut short (an interrupted run; the next run of the study redoes it) "
                        "and is left out" % path)
    out.note = "; ".join(notes) or None
    return out


def _non_finite(text):
    try:
        return not math.isfinite(float(text))
    except (TypeError, ValueError):
        return False


def _fitting_rows(path, rows):
    """(rows that fit schemas/probes.schema.json, notes on those left out). A row with a NaN or
    infinite cell (not its modulus: _check_rows refuses that) is left out and said, naming its line
    and column: one such cell made the fits fail with a LinAlgError. Anything else that does not
    fit (a text where a number belongs, an unknown probe axis) is refused, naming the same."""
    kept, left = [], []
    for line, r in enumerate(rows, start=2):
        found = validate.problem(r, "probes")
        if found is None:
            kept.append(r)
            continue
        field, what = found
        if _non_finite(r.get(field)):
            left.append("line %d (state %s probe %s: %s = %s)" % (line, r.get("state"), r.get("probe"), field,
                                                                   r.get(field)))
            continue
        raise ResultsError("%s: line %d: %s: %s" % (path, line, field, what))
    if left and not kept:
        raise ResultsError("%s: every row has a NaN or infinite cell (%s)" % (path, left[0]))
    if not left:
        return kept, []
    shown = ", ".join(left[:5]) + (" ..." if len(left) > 5 else "")
    return kept, ["%s: %d row%s with a NaN or infinite cell left out: %s"
                  % (path, len(left), "" if len(left) == 1 else "s", shown)]


def read_metadata(results, required=False):
    """The metadata.json of a study directory (its fingerprint, states, specimen, runs), checked.

    One that is there but cannot be read (empty, truncated, not JSON) is refused always, as
    run_states.py refuses it: it holds what the study is (its assembly, material, states), and taken
    as absent it would make a clump1 study a bare table of spheres.

    Args:
        results: the study directory.
        required: raise `ResultsError` instead of returning None when there is none.

    Returns:
        dict or None: None for a directory without one.

    Raises:
        ResultsError: a metadata.json that cannot be read, or none with `required`.

    Example:
        >>> from trueaniso.analysis import results
        >>> meta = results.read_metadata("docs/data/spheres-53004-s1")
        >>> meta["fingerprint"]["assembly"], len(meta["states"])
        ('sphere', 39)
    """
    import json
    from trueaniso.options import flag
    required = flag("read_metadata", "required", required)
    path = os.path.join(results, "metadata.json")
    if not os.path.exists(path):
        if required:
            raise ResultsError("%s: no metadata.json (a study's, written by run_states.py or run_study.py)" % results)
        return None
    try:
        with open(path) as f:
            meta = json.load(f)
    except (OSError, ValueError) as exc:
        raise ResultsError("%s is unreadable (%s): what the study is (its assembly, material and states) cannot be "
                           "read; restore it from the run that wrote it, or analyse probes.csv copied elsewhere as a "
                           "bare table" % (path, exc)) from None
    # A metadata.json that parses but does not fit its schema is refused, not taken for a bare
    # table: its states and specimen are what the rows are checked against. Each field is taken
    # as optional here: the analysis uses what is there.
    return validate.check(meta, "study", path, ResultsError, required=False)


def number(row, column, path="probe table"):
    """A float cell, or one clear error naming the row."""
    try:
        return float(row[column])
    except (TypeError, ValueError):
        raise ResultsError("%s: state %s probe %s has %s = %r, not a number"
                           % (path, row.get("state"), row.get("probe"), column, row[column])) from None
