"""Reading a study's probe table (probes.csv) for analysis: the one route every analysis takes.

The table is read by the same code that writes it (trueaniso/results_csv.py), so a row cut short
by an interrupted run is recognised and left out rather than read as numbers, and anything else
wrong with the file is one ``ResultsError`` line, never a traceback.
"""
import os
import sys

_PYSCRIPTS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "pyscripts")
if _PYSCRIPTS not in sys.path:
    sys.path.insert(0, _PYSCRIPTS)
from trueaniso import results_csv  # noqa: E402


class ResultsError(ValueError):
    """A results file that cannot be analysed; the message is one line for the user."""


class Probes(list):
    """The complete rows of a probe table; ``note`` says what was left out, if anything."""
    note = None


def read_probes(path, need=("state", "probe", "E")):
    """Rows of a probe table as dicts of strings, with the columns in `need` present."""
    if not os.path.isfile(path):
        raise ResultsError("%s does not exist (a probe table is written by run_states.py or run_study.py)" % path)
    try:
        table = results_csv.read(path)
    except (results_csv.TableError, UnicodeDecodeError) as exc:
        raise ResultsError("%s is not a readable probe table (%s)" % (path, exc)) from None
    if not table.rows:
        raise ResultsError("%s has no complete rows" % path)
    missing = [c for c in need if c not in table.columns]
    if missing:
        raise ResultsError("%s lacks the columns %s" % (path, ", ".join(missing[:6]) + (" ..." if len(missing) > 6 else "")))
    out = Probes(table.rows)
    if table.torn is not None:
        out.note = ("%s: the last row was cut short (an interrupted run; the next run of the study redoes it) "
                    "and is left out" % path)
    return out


def read_metadata(results, required=False):
    """The metadata.json of a study directory (its fingerprint, specimen, runs), or None for a bare
    table or a directory without one; with `required`, a ResultsError instead of None."""
    import json
    path = os.path.join(results, "metadata.json")
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError) as exc:
        if required:
            raise ResultsError("%s: no readable metadata.json (%s)" % (results, exc)) from None
        return None


def number(row, column, path="probe table"):
    """A float cell, or one clear error naming the row."""
    try:
        return float(row[column])
    except (TypeError, ValueError):
        raise ResultsError("%s: state %s probe %s has %s = %r, not a number"
                           % (path, row.get("state"), row.get("probe"), column, row[column])) from None
