"""yade-batch parameter tables, read the way YADE reads them.

A table (``yade-batch TABLE SCRIPT.py``) has one column per parameter and one line per run:

    # comments and blank lines are allowed anywhere (and still count as lines)
    ids    probes!   out              description
    '1'    'z'       'results/b1'     iso
    '5'    =         'results/b5'     comp

- a job gets ``YADE_BATCH=TABLE:LINE`` where LINE is the line number as a text editor shows it
  (the heading is line 1 above the blank and comment lines, data lines keep their numbers);
- ``=`` repeats the value of the line above; ``*`` keeps the script's default;
- a heading ending in ``!`` marks the columns that make the job's description (the ``!`` is not part
  of the name); a heading starting with ``!`` (``!THREADS``, ``!EXEC``, ...) is for yade-batch itself
  and is not a parameter; a ``description`` column names the job;
- every value is a Python expression (YADE evaluates it with the math module in scope), so strings
  are quoted: ``'results/b1'``; ``False``, ``0`` and ``'no'`` are all "off" for a flag.

Under yade-double the line is read by ``yade.utils.readParamsFromTable`` itself (so ``O.tags`` and
``yade.params.table`` are set as YADE users expect); under plain python3 by ``read_line`` below,
which follows the same rules (``tests/py/test_param_table.py`` compares the two).
"""
import math
import re

from .refusal import InputError

KEEP_DEFAULT = "*"
REPEAT = "="


def _lines(path):
    try:
        with open(path) as f:
            raw = f.read().split("\n")
    except OSError as exc:
        raise InputError("cannot read parameter table %s (%s)" % (path, exc.strerror)) from None
    # Line numbers as in a text editor; '#' starts a comment anywhere (TableParamReader does the same).
    return {k + 1: re.sub(r"\s*#.*", "", text).split() for k, text in enumerate(raw)}


def columns_and_values(path):
    """(headings as written, {line number: [raw value strings]}) with '=' resolved."""
    lines = {k: v for k, v in _lines(path).items() if v}
    if not lines:
        raise InputError("parameter table %s is empty" % path)
    first = min(lines)
    head = lines.pop(first)
    values, previous = {}, None
    for k in sorted(lines):
        row = lines[k]
        if len(row) != len(head):
            raise InputError("parameter table %s line %d has %d values for %d columns"
                             % (path, k, len(row), len(head)))
        if previous is None and REPEAT in row:
            raise InputError("parameter table %s line %d: '=' repeats the line above, and there is none" % (path, k))
        values[k] = [previous[i] if v == REPEAT else v for i, v in enumerate(row)]
        previous = values[k]
    return head, values


def parameter_columns(head, path="the parameter table"):
    """{column as written: parameter name}: '!'-prefixed columns and 'description' are not
    parameters; a trailing '!' only marks a description column. A parameter named twice is
    refused, not decided by its last column without a word (`out out`)."""
    out = {}
    for h in head:
        if h.startswith("!") or h == "description":
            continue
        name = h[:-1] if h.endswith("!") else h
        if name in out.values():
            raise InputError("%s names the parameter %r in two columns" % (path, name))
        out[h] = name
    return out


def evaluate(text, where):
    """A table value as YADE evaluates it (a Python expression, math in scope)."""
    try:
        return eval(text, dict(math.__dict__))  # noqa: S307 - YADE's own convention for table values
    except Exception:
        raise InputError("%s: %s is not a Python value; YADE evaluates table values, so quote strings "
                         "(e.g. '%s')" % (where, text, text)) from None


def read_line(path, line):
    """{parameter name: value} of one line (YADE numbering); '*' values are left out (defaults)."""
    head, values = columns_and_values(path)
    if line not in values:
        raise InputError("parameter table %s has no data on line %d (data lines: %s)"
                         % (path, line, ", ".join(str(k) for k in sorted(values)) or "none"))
    names = parameter_columns(head, path)
    out = {}
    for h, text in zip(head, values[line]):
        if h in names and text != KEEP_DEFAULT:
            out[names[h]] = evaluate(text, "parameter table %s line %d column %s" % (path, line, h))
    return checked(out, path, line)


def checked(values, path, line):
    """`values` when they fit schemas/param_table.schema.json (numbers, texts, flags, lists of
    them; an infinite number, as in --path-rate inf, is taken as its text); else one InputError
    naming the line and the column."""
    from . import validate
    plain = {k: repr(v) if isinstance(v, float) and not math.isfinite(v) else v for k, v in values.items()}
    found = validate.problem(plain, "param_table")
    if found:
        field, what = found
        raise InputError("parameter table %s line %d: column %s: %s" % (path, line, field, what))
    return values


def read_line_in_yade(path, line, defaults):
    """The same through ``yade.utils.readParamsFromTable`` (sets O.tags and yade.params.table)."""
    from yade import utils
    head, values = columns_and_values(path)  # our checks first: they give one clear line
    if line not in values:
        raise InputError("parameter table %s has no data on line %d (data lines: %s)"
                         % (path, line, ", ".join(str(k) for k in sorted(values)) or "none"))
    names = parameter_columns(head, path)
    for h, text in zip(head, values[line]):
        if h in names and text != KEEP_DEFAULT:
            evaluate(text, "parameter table %s line %d column %s" % (path, line, h))
    utils.readParamsFromTable(tableFileLine="%s:%d" % (path, line), noTableOk=False, unknownOk=True, **defaults)
    import yade.params.table as table
    out = {}
    for h, text in zip(head, values[line]):
        if h in names and text != KEEP_DEFAULT:
            # YADE drops a trailing '!' from the headings unless the table has a description column.
            out[names[h]] = getattr(table, h) if h != names[h] and hasattr(table, h) else getattr(table, names[h])
    return checked(out, path, line)
