"""The probe table (probes.csv): one row per state and probe, appended as each probe ends.

Rows are appended, flushed and fsynced one at a time, never rewritten from memory, so a row
written is a row kept whatever happens to this run or another. Every row ends with a newline;
a last line without one (a run killed mid-write, a full disk) is a torn row: ``read`` reports it
and never counts it as done, and ``repair`` (under the results directory's lock) drops it by an
atomic rewrite of the complete rows before the next row is appended.
"""
import csv
import io
import os

from . import atomic


def state_id(text):
    """A state's id as every reader of a table takes it: a Table C1 number written '21.0' or ' 21'
    (a table edited by hand or by a spreadsheet) is '21'; any other id is its text without the
    spaces around it. Applied once, where a table is read (``read``), so that no later step meets
    two spellings of one state (a row counted for state '21.0' while the report looks for '21')."""
    text = str(text).strip()
    try:
        value = float(text)
    except ValueError:
        return text
    return str(int(value)) if value.is_integer() and abs(value) < 1e15 else text


class TableError(ValueError):
    """A probe table that cannot be read as one (other than a torn last row)."""


class Table:
    """The complete rows of a probe table and what is wrong with its tail, if anything."""

    def __init__(self, path, columns, rows, torn):
        self.path, self.columns, self.rows, self.torn = path, columns, rows, torn


def read(path):
    """A Table; missing file: no columns, no rows. Raises TableError for a file that is not a
    probe table (no header, a short row before the last line)."""
    if not os.path.exists(path):
        return Table(path, [], [], None)
    with open(path, newline="") as f:
        text = f.read()
    if not text.strip():
        return Table(path, [], [], None)
    torn = None
    lines = text.split("\n")
    if lines[-1] != "":  # the last line has no newline: written only in part
        torn = lines[-1]
        text = "\n".join(lines[:-1]) + ("\n" if len(lines) > 1 else "")
    if not text:  # only a header, and it was cut short
        return Table(path, [], [], torn)
    reader = csv.reader(io.StringIO(text))
    try:
        header = next(reader)
    except StopIteration:
        raise TableError("%s has no header line (it was cut while being created)" % path) from None
    rows = []
    for k, values in enumerate(reader, start=2):
        if len(values) != len(header):
            raise TableError("%s line %d has %d fields for %d columns: the file was edited or damaged"
                             % (path, k, len(values), len(header)))
        row = dict(zip(header, values))
        if "state" in row:
            row["state"] = state_id(row["state"])
        rows.append(row)
    return Table(path, header, rows, torn)


def repair(table, log=print):
    """Drop a torn last row by rewriting the complete ones atomically (the caller holds the lock)."""
    if table.torn is None:
        return table
    log("%s: dropping a row cut short (%d characters of a line; a run was interrupted while writing it); "
        "its probe runs again" % (table.path, len(table.torn)))
    if table.columns:
        atomic.write_csv(table.path, table.rows, table.columns)
    else:
        with atomic.atomic_open(table.path, "w"):
            pass
    return Table(table.path, table.columns, table.rows, None)


def append(path, row, columns):
    """Append one row (the header first if the file is new), flushed and fsynced."""
    new = not os.path.exists(path) or os.path.getsize(path) == 0
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n", extrasaction="raise")
    if new:
        w.writeheader()
    w.writerow(row)
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o666)
    try:
        data = buf.getvalue().encode()
        while data:  # one write in practice; a short write (full disk) raises on the retry
            n = os.write(fd, data)
            data = data[n:]
        os.fsync(fd)
    except OSError as exc:  # a write's error names no file: this one
        if exc.filename:
            raise
        raise OSError(exc.errno, exc.strerror or str(exc), path) from None
    finally:
        os.close(fd)
    if new:
        _fsync_directory(os.path.dirname(os.path.abspath(path)))


def _fsync_directory(directory):
    fd = os.open(directory, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
