"""Command-line habits shared by the scripts in pyscripts/.

- ``yade-double -n -x pyscripts/x.py --option value`` or ``/usr/bin/python3 pyscripts/x.py ...``;
- parameters can also come from a yade-batch table line: ``--table FILE --line N`` or the
  PARAM_TABLE=FILE:LINE environment variable that yade-batch sets; explicit options win;
- bad input ends the script before any work with one line ``error: ...`` and exit status 2.
"""
import argparse
import os
import shlex
import sys


class InputError(ValueError):
    """Bad input detected before any work starts."""


def fail(message, status=2):
    sys.stdout.flush()
    sys.stderr.write("error: %s\n" % message)
    sys.stderr.flush()
    # Inside yade-double, sys.exit in a script would drop into YADE's handler; os._exit is final.
    os._exit(status)


class Parser(argparse.ArgumentParser):
    def error(self, message):  # argparse would print usage + message; we want one line
        fail(message)


def script_args():
    """The script's own arguments, under python3 or yade-double (which keeps them in sys.argv)."""
    return sys.argv[1:]


def read_table_line(path, line):
    """One data line of a yade-batch parameter table as {column: value string}."""
    try:
        with open(path) as f:
            rows = [ln for ln in f.read().splitlines() if ln.strip() and not ln.lstrip().startswith(("#", "!"))]
    except OSError as exc:
        raise InputError("cannot read parameter table %s (%s)" % (path, exc.strerror)) from None
    if len(rows) < 2:
        raise InputError("parameter table %s has no data lines" % path)
    header = shlex.split(rows[0])
    if not 1 <= line < len(rows):
        raise InputError("parameter table %s has no data line %d (it has %d)" % (path, line, len(rows) - 1))
    values = shlex.split(rows[line])
    if len(values) != len(header):
        raise InputError("parameter table %s line %d has %d values for %d columns"
                         % (path, line, len(values), len(header)))
    return dict(zip(header, values))


def parse(parser, argv=None):
    """Parse options, filling defaults from a table line first; errors exit with one line."""
    parser.add_argument("--table", help="yade-batch style parameter table")
    parser.add_argument("--line", type=int, default=1, help="data line of --table (1 = first)")
    argv = script_args() if argv is None else argv
    table = None
    probe = argparse.ArgumentParser(add_help=False)
    probe.add_argument("--table")
    probe.add_argument("--line", type=int, default=1)
    known, _ = probe.parse_known_args(argv)
    try:
        if known.table:
            table = read_table_line(known.table, known.line)
        elif os.environ.get("PARAM_TABLE"):
            path, _, line = os.environ["PARAM_TABLE"].rpartition(":")
            table = read_table_line(path, int(line))
        if table:
            dests = {a.dest: a for a in parser._actions}
            for key, value in table.items():
                dest = key.replace("-", "_")
                if dest not in dests:
                    if key in ("description",):
                        continue
                    raise InputError("parameter table column %r is not an option of this script" % key)
                action = dests[dest]
                parser.set_defaults(**{dest: action.type(value) if action.type else value})
    except InputError as exc:
        fail(str(exc))
    return parser.parse_args(argv)


def guarded(main):
    """Run main(); InputError and ValueError from validation become one line and exit 2."""
    try:
        main()
    except (InputError, ValueError) as exc:
        # ValueError: validation inside the library (bad specimen contents, bad arguments to an
        # engine); a traceback would hide the one line the user needs.
        fail(str(exc))
    except KeyboardInterrupt:
        fail("interrupted", 130)


def in_yade():
    return "yade" in sys.modules
