"""Command-line habits shared by the scripts in pyscripts/.

- ``yade-double -n -x pyscripts/x.py --option value`` or ``/usr/bin/python3 pyscripts/x.py ...``;
- ``yade-batch TABLE pyscripts/x.py``: parameters come from the table line named by YADE_BATCH,
  read the YADE way (trueaniso/param_table.py); ``--table FILE --line N`` does the same by hand.
  Options given on the command line win over the table;
- ``--help`` shows every option with its help text and its default;
- bad input ends the script before any work with one line ``error: ...`` and exit status 2.
"""
import argparse
import math
import os
import re
import signal
import sys
import threading

from . import options as options_module, param_table
from .refusal import InputError, Refusal

__all__ = ["InputError", "Refusal", "Parser", "parse", "fail", "guarded", "tool", "release_start_guard", "in_yade",
           "description"]


_guarding = False  # a script runs under guarded(): its exit line comes from fail()
_after_line = []  # work for fail() to do once its line is out (after_exit_line)


def after_exit_line(work):
    """`work()` after the exit line of a script that ends in fail(), or at once outside one (the
    library called from Python): bookkeeping a kill may cut short must not delay the line. mpiexec
    ends its ranks with SIGTERM and soon after SIGKILL, within the milliseconds of a file written
    and synced (test_mpi.py's Ctrl-C test)."""
    if _guarding:
        _after_line.append(work)
    else:
        work()


def fail(message, status=2):
    try:
        sys.stdout.flush()
        sys.stderr.write("error: %s\n" % message)
        sys.stderr.flush()
    except OSError:  # a closed pipe: the status still says it
        pass
    for work in _after_line:
        try:
            work()
        except BaseException:  # a second signal, a full disk: the line and the status stand
            pass
    # Inside yade-double, sys.exit in a script would drop into YADE's handler; os._exit is final.
    os._exit(status)


class _Formatter(argparse.RawDescriptionHelpFormatter):
    """The default after every help text that has one (not for on/off flags, nor None); the
    description keeps its line breaks."""

    def _get_help_string(self, action):
        text = action.help
        shown = action.default not in (None, argparse.SUPPRESS) and action.nargs != 0
        if shown and "%(default)" not in text:
            text += " (default: %(default)s)"
        return text


class Parser(argparse.ArgumentParser):
    def __init__(self, *args, **kw):
        kw.setdefault("formatter_class", _Formatter)
        super().__init__(*args, **kw)

    def add_argument(self, *args, **kw):
        # Every option says what it does in --help (the defaults are added by the formatter).
        if not kw.get("help") and args != ("-h", "--help"):
            raise TypeError("option %s has no help text" % "/".join(args))
        return super().add_argument(*args, **kw)

    def error(self, message):  # argparse would print usage + message; we want one line
        if message.endswith("expected one argument"):
            # argparse reads a value that starts with '-' (--states -0.1:1e5) as the next option
            message += " (a value that starts with '-' goes as --option=VALUE)"
        fail(message)


def add_threads_option(parser, study=False, continues="the study --out holds (a study continues at its own count, "
                                                    "which its last bits depend on)", mpi=False):
    """--threads, as every script that runs the engines offers it (0: all cores). A script that
    continues work (study=True) leaves it None when not given, for resolve_threads; `continues`
    names the work whose count it then takes."""
    from . import resources
    parser.add_argument("--threads", type=count, default=None if study else 0,
                        # 0 is OpenMP's own count: OMP_NUM_THREADS when set (the MPI recipe sets it to 1),
                        # which the help says, since 'all cores' would be recorded as 1
                        help="OpenMP threads of the engines: 0 = OpenMP's count (OMP_NUM_THREADS when set, else "
                             "all %d cores%s), at most %d (%d x the cores)%s"
                             % (resources.cores(), "; one a worker under --mpi" if mpi else "",
                                resources.max_threads(), resources.THREADS_PER_CORE,
                                "; when not given: the count of %s, else 0" % continues if study else ""))


def resolve_threads(o, study=True, preparation=None):
    """--threads of a script that continues work when not given: the count of the work --out
    holds (its bits depend on it), so that a rerun continues it instead of being refused for a
    thread count the user never chose; else 0 (all cores). Says which. The work: the study in
    the directory --out (study=True; recorded in its metadata), or else the interrupted
    preparation whose checkpoint is `preparation` (prep_checkpoint). --force-new starts a study
    afresh: 0. (prepare_specimen.py's --force redoes a finished specimen; an interrupted
    preparation of the same settings still resumes, so its count is still adopted.)"""
    from . import prep_checkpoint, study_dir
    fresh = getattr(o, "force_new", False)
    continued = None
    if o.threads is None and not fresh:
        if study:
            o.threads = study_dir.threads_of(o.out)
            continued = "its study" if o.threads else None
        if o.threads is None and preparation is not None:
            o.threads = prep_checkpoint.saved_threads(preparation)  # refuses an unreadable checkpoint
            # "unfinished", not "interrupted": it may be running in another process, which the lock
            # then refuses (a second run_study.py during the first one's preparation).
            continued = "its unfinished preparation" if o.threads else None
    o.threads = o.threads or 0
    if o.threads == 0:
        _check_openmp_count()
    if continued:
        # Said as a fact about the work, not as "continuing": a check after it may still refuse the
        # run (another --mu, say), and "continuing ..." would then read as the opposite.
        print("%s: --threads not given: %s ran at %d engine thread%s, so this run does too"
              % (o.out, continued, o.threads, "" if o.threads == 1 else "s"), flush=True)
    return o.threads


def _check_openmp_count():
    """--threads 0 takes OMP_NUM_THREADS: held to --threads' own limit, which it would pass by
    otherwise (a study at 16 threads on 2 cores, which no --threads could then continue)."""
    from . import resources
    text = resources.openmp_threads_env() or ""
    if text.isdigit() and int(text) > resources.max_threads():
        raise InputError("OMP_NUM_THREADS=%s, the count --threads 0 takes, is above %d (%d x this machine's %d "
                         "cores; more threads only slow the contact loops down): set it lower, or give --threads"
                         % (text, resources.max_threads(), resources.THREADS_PER_CORE, resources.cores()))


def add_path_rate_option(parser):
    parser.add_argument("--path-rate", type=positive_or_inf, default=None,
                        help="servo's path rate while states are reached, in Pa per step of the smallest-inertia time "
                             "step rule (a rule with a longer step, per-axis, moves it further a step: the same rate "
                             "in time); inf: the whole load at once; when not given: the rate of the study --out "
                             "holds, else 2 (docs/state-speed.md: what a faster rate changes)")


# The time step rules (dem.TIME_STEP_RULES; docs/time-step.md). A study's states and probes take
# DEFAULT_TIME_STEP; a preparation DEFAULT_PREPARATION_TIME_STEP; a study or specimen that records
# no rule was made with options.UNRECORDED_TIME_STEP, and is continued with it.
TIME_STEP_CHOICES = options_module.TIME_STEP_RULES
DEFAULT_TIME_STEP = options_module.DEFAULT_TIME_STEP
DEFAULT_PREPARATION_TIME_STEP = "smallest-inertia"
UNRECORDED_TIME_STEP = options_module.UNRECORDED_TIME_STEP


def add_time_step_option(parser, study=False):
    if not study:
        parser.add_argument("--time-step", choices=TIME_STEP_CHOICES, default=DEFAULT_PREPARATION_TIME_STEP,
                            help="time step rule of the preparation (docs/time-step.md): smallest-inertia, a safety "
                                 "factor 0.5 of the body's smallest sqrt(inertia / stiffness), or per-axis, 0.8 of the "
                                 "bound of each body's stiffest mode, a longer step; the preparation's rates are per "
                                 "unit time, so per-axis takes fewer steps, and makes another packing (default: %s)"
                                 % DEFAULT_PREPARATION_TIME_STEP)
        return
    parser.add_argument("--time-step", choices=TIME_STEP_CHOICES, default=None,
                        help="time step rule of the states and the probes (docs/time-step.md): per-axis, 0.8 of the "
                             "bound of each body's stiffest mode, or smallest-inertia, 0.5 of the body's smallest "
                             "sqrt(inertia / stiffness), a shorter step. The path rate and the servos' gains and step "
                             "counts are per step of smallest-inertia, so either rule loads at the same rate in time. "
                             "When not given: the rule of the study --out holds (%s for one that records none), else "
                             "%s" % (UNRECORDED_TIME_STEP, DEFAULT_TIME_STEP))


def resolve_time_step(o):
    """--time-step of prepare_specimen.py: the rule every engine chain of this run takes (dem.time_step_rule)."""
    from . import dem
    dem.time_step_rule = o.time_step
    return o.time_step


def _continue_held(o, option, held, default, says):
    """Sets the unset --OPTION of a study run: the value the study --out holds (a rerun continues
    it instead of being refused for a value the user never chose, as --threads), else the default.
    Says so when the held value is not the default, since the user did not ask for it."""
    value = default if held is None else held
    setattr(o, option, value)
    if held is not None and held != default:
        print("%s: --%s not given: %s, so this run does too" % (o.out, option.replace("_", "-"), says % held),
              flush=True)
    return value


def resolve_study_time_step(o):
    """--time-step of a study (o.time_step, the states' rule) and the probes' rule (o.probe_time_step).

    Not given: the rules of the study --out holds, each read from its fingerprint (state.time_step,
    probe.time_step); a study that records none was made with UNRECORDED_TIME_STEP, and goes on
    with it; no study: DEFAULT_TIME_STEP for both. Said in one line when that is not the default.
    Given: both rules, and a study made with another is refused by its fingerprint (study_dir.check);
    but given as the states' rule of a study whose probes took another (a study made before the
    probes took the study's rule), the probes go on with theirs, said in one line."""
    from . import study_dir
    held = None if getattr(o, "force_new", False) else study_dir.time_step_rules_of(o.out)
    if o.time_step is None:
        states, probes = held or (None, None)
        _continue_held(o, "time_step", states, DEFAULT_TIME_STEP, "its study reached its states with the %s rule")
        o.probe_time_step = probes or DEFAULT_TIME_STEP
        if probes is not None and probes != o.time_step:
            print("%s: its study probed its states with the %s time step rule, so this run does too"
                  % (o.out, probes), flush=True)
        return o.time_step
    o.probe_time_step = o.time_step
    if held is not None and held[0] == o.time_step and held[1] != o.time_step:
        o.probe_time_step = held[1]
        print("%s: its study probed its states with the %s time step rule, so this run does too"
              % (o.out, held[1]), flush=True)
    return o.time_step


def resolve_path_rate(o):
    """--path-rate when not given: the rate of the study --out holds, else the default."""
    from . import options, study_dir
    if o.path_rate is not None:
        return o.path_rate
    default = options.ServoOptions.path_rate  # one home: the servo's options
    held = None if getattr(o, "force_new", False) else study_dir.path_rate_of(o.out)
    return _continue_held(o, "path_rate", held, default, "its study reached its states at %g Pa per step")


def description(doc):
    """A script's --help description: the first paragraph of its docstring, whole (not its first
    line, which may stop mid-sentence), its formulas without the dollars the manual typesets them
    from (a terminal shows the TeX between them as it stands)."""
    first = doc.strip().split("\n\n")[0]
    text = " ".join(line.strip() for line in first.splitlines())
    return re.sub(r"(?<!\\)\$([^$`]+)(?<!\\)\$", r"\1", text)


# ---------------------------------------------------------------- option types (argparse type=)

def finite(text):
    """A float that is a number: nan and inf are refused when the options are read."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("%r is not a number" % text) from None
    if not math.isfinite(x):
        raise argparse.ArgumentTypeError("%r is not a finite number" % text)
    return x


def positive(text):
    x = finite(text)
    if not x > 0:
        raise argparse.ArgumentTypeError("%r is not > 0" % text)
    return x


def positive_or_inf(text):
    """A number > 0, or inf (e.g. a rate with no limit); nan is refused."""
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError("%r is not a number" % text) from None
    if not x > 0:  # nan and -inf fail too
        raise argparse.ArgumentTypeError("%r is not > 0 (or inf)" % text)
    return x


def poisson_ratio(text):
    """A particle's Poisson's ratio: a number in (-1, 0.5), the range of an isotropic elastic solid."""
    x = finite(text)
    if not -1 < x < 0.5:
        raise argparse.ArgumentTypeError("%r is not in (-1, 0.5)" % text)
    return x


def non_negative(text):
    x = finite(text)
    if not x >= 0:
        raise argparse.ArgumentTypeError("%r is not >= 0" % text)
    return x


ASSEMBLIES = ("sphere", "clump1", "clump2")  # a specimen's particles (docs/specimens.md)


def assembly(text):
    """--assembly of every script: sphere, clump1 or clump2; 'spheres', the paper's word, is taken
    for sphere by every script alike."""
    name = {"spheres": "sphere"}.get(text, text)
    if name not in ASSEMBLIES:
        raise argparse.ArgumentTypeError("unknown assembly %r (available: %s)" % (text, ", ".join(ASSEMBLIES)))
    return name


def count(text):
    """An integer >= 0 (seeds, thread counts)."""
    return at_least(0)(text)


def at_least(least, why=""):
    """An argparse type: an integer >= least, refused with that least (count() said '>= 0' for a
    particle count whose least is 1 or 100, and the next check then named the real one)."""
    def parse(text):
        try:
            k = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError("%r is not an integer" % text) from None
        if k < least:
            raise argparse.ArgumentTypeError("%r is not >= %d%s" % (text, least, " (%s)" % why if why else ""))
        return k
    parse.__name__ = "integer"  # what argparse calls the type in its messages
    return parse


def output_problem(path, directory=True, option="--out"):
    """Why `path` cannot be written, or None: a directory (or a file) that exists or can be
    created, in a place where this user can create files. Checked by creating and removing a
    file, so read-only mounts and permissions count as they really are (root included)."""
    import tempfile
    if not path:  # '' is no place (abspath would make it the working directory)
        return "%s must name a %s" % (option, "directory" if directory else "file")
    full = os.path.abspath(path)
    if os.path.isdir(full) != directory and os.path.exists(full):
        return "%s %s is a %s, not a %s" % (option, path, "directory" if directory is False else "file",
                                            "directory" if directory else "file")
    where = full if directory else os.path.dirname(full)
    while not os.path.exists(where):
        parent = os.path.dirname(where)
        if parent == where:
            break
        where = parent
    if not os.path.isdir(where):
        return "%s %s: %s is a file, not a directory" % (option, path, where)
    try:
        with tempfile.TemporaryFile(dir=where, prefix=".tmp-writable-"):
            pass
    except OSError as exc:
        return "%s %s: cannot create files in %s (%s)" % (option, path, where, exc.strerror)
    return None


# ---------------------------------------------------------------- tables and parsing

def script_args():
    """The script's own arguments, under python3 or yade-double (which keeps them in sys.argv)."""
    return sys.argv[1:]


def in_yade():
    return "yade" in sys.modules


_YES = ("yes", "true", "on", "1")
_NO = ("no", "false", "off", "0", "")


def _flag(value, where):
    """A table value for an on/off option: False, 0 and 'no' are off (bool('no') would be on)."""
    if isinstance(value, str) and value.strip().lower() in _YES + _NO:
        return value.strip().lower() in _YES
    if isinstance(value, (bool, int)) and value in (0, 1):
        return bool(value)
    if value is None:
        return False
    raise InputError("%s: %r is not on or off (use True/False, 1/0 or 'yes'/'no')" % (where, value))


def _text(value):
    if isinstance(value, (tuple, list)):  # an unquoted 1,5 evaluates to a tuple
        return ",".join(str(v) for v in value)
    return str(value)


def table_argv(parser, values, where):
    """Command-line tokens for {parameter: value} of a table line (prepended to the real ones,
    so that explicit options win)."""
    by_name = {}
    for a in parser._actions:
        for s in a.option_strings:
            if s.startswith("--"):
                by_name[s[2:]] = a
                by_name[s[2:].replace("-", "_")] = a
    argv = []
    for name, value in values.items():
        a = by_name.get(name)
        if a is None or name in ("help", "table", "line"):
            raise InputError("%s: column %r is not an option of this script (see --help)" % (where, name))
        opt = a.option_strings[-1]
        if isinstance(a, (argparse._StoreTrueAction, argparse._StoreFalseAction)):
            on = _flag(value, "%s column %s" % (where, name))
            if on == isinstance(a, argparse._StoreTrueAction):
                argv.append(opt)
        elif isinstance(a, argparse._AppendAction):
            for v in (value if isinstance(value, (tuple, list)) else [value]):
                argv.append("%s=%s" % (opt, _text(v)))
        elif value is not None:
            argv.append("%s=%s" % (opt, _text(value)))
    return argv


def _table_source(known):
    """(path, line) of the parameter table, or None: --table/--line first, then YADE_BATCH."""
    if known.table is not None:
        if not known.table.strip():  # not read as no table, which would say "--line needs --table"
            raise InputError("--table is empty: give the parameter table's path")
        if known.line is None:
            raise InputError("--table needs --line (the line number as a text editor shows it, as yade-batch counts)")
        return known.table, known.line
    if known.line is not None:
        raise InputError("--line needs --table")
    batch = os.environ.get("YADE_BATCH", "")
    if batch:  # yade-batch sets it empty for a job without a table
        path, _, line = batch.rpartition(":")
        try:
            return path, int(line)
        except ValueError:
            raise InputError("YADE_BATCH=%r is not TABLE:LINE" % batch) from None
    return None


def parse(parser, argv=None):
    """Parse options, filling them from a table line first; errors exit with one line."""
    parser.add_argument("--table", help="parameter table in yade-batch's format (trueaniso/param_table.py); "
                                        "yade-batch passes it in YADE_BATCH instead")
    parser.add_argument("--line", type=int, help="line of --table, numbered as a text editor shows it (as yade-batch does)")
    argv = script_args() if argv is None else list(argv)
    pre = Parser(add_help=False)  # its refusals are one line too (argparse's own printed usage first)
    pre.add_argument("--table", help="the table")
    pre.add_argument("--line", type=int, help="its line")
    try:
        known, _ = pre.parse_known_args(argv)
        source = _table_source(known)
        if source:
            path, line = source
            where = "parameter table %s line %d" % (path, line)
            if in_yade():
                defaults = {a.dest: a.default for a in parser._actions if a.dest not in ("help", "table", "line")}
                values = param_table.read_line_in_yade(path, line, defaults)
            else:
                values = param_table.read_line(path, line)
            argv = table_argv(parser, values, where) + argv
    except InputError as exc:
        fail(str(exc))
    return parser.parse_args(argv)


class Terminated(BaseException):
    """SIGTERM as an exception, like KeyboardInterrupt for SIGINT (not an Exception, so that no
    `except Exception` in the library swallows it)."""


_pending = None  # the last SIGINT or SIGTERM the handlers below raised (raise_pending)


def _interrupt(number, frame):
    """SIGINT as KeyboardInterrupt, SIGTERM as Terminated, remembered: Python runs a handler at the
    next instruction, which may be inside a finalizer (an archive's or a file's __del__); there the
    exception is printed as 'Exception ignored' and the work goes on (a Ctrl-C ignored, the run
    finishing with status 0); raise_pending() raises it again."""
    global _pending
    _pending = number
    raise Terminated() if number == signal.SIGTERM else KeyboardInterrupt()


def raise_pending():
    """Between chunks of work (progress.Progress calls it): a signal whose exception a finalizer
    swallowed is raised here. The script ends at the first one raised (guarded), so a remembered
    one is never raised twice in a run."""
    if _pending is not None:
        raise Terminated() if _pending == signal.SIGTERM else KeyboardInterrupt()


def release_start_guard():
    """Give SIGINT and SIGTERM back to Python's own handling in a script that was loaded, not run:
    mpi4py.futures' workers load run_states.py to find its functions, and kept the start-up guard
    of its first lines, so a worker ended by mpiexec (SIGTERM) printed 'interrupted while starting;
    nothing was done' beside the master's line that the job resumes. Only the main thread may set
    handlers; elsewhere there is nothing to give back."""
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


_saved_work = None  # set by a resumable script once it knows where its work goes (saves_work_in)
_work_complete = None  # ... and how to see that all of it is written (saves_work_in's complete)
_resumes = None  # ... and what its rerun does with that work (saves_work_in's resumes)
_done = False  # set by work_done()

# What the same command does with the work an interrupted run saved, by the kind of work. A
# preparation continues from its last checkpoint, mid-stage. A study continues from what it
# finished: a state or probe cut short leaves nothing, and is redone from the checkpoint of the
# last state before it on its path, or from the specimen (study.run_states, docs/runs.md).
RESUMES_PREPARATION = "resumes the preparation from its last checkpoint"
RESUMES_STUDY = ("resumes from the finished states and probes; one cut short starts again from the last state "
                 "finished before it on its path, or from the specimen")


def saves_work_in(check, *, resumes, complete=None):
    """Tell guarded() how to see whether an interrupted run has anything to resume from: check()
    is True when a checkpoint or a finished row of this command's work is on disk. Without it, an
    interruption before the first checkpoint promised a resume, and the rerun started over.
    complete(), when given, is True once all of the command's work is written: a Ctrl-C then (in
    the few milliseconds between the last line and the end of main) ends the run as finished.
    resumes: what the rerun then does (RESUMES_PREPARATION, RESUMES_STUDY), or a function that
    says it at the time (a study that prepares its specimen first is one, then the other)."""
    global _saved_work, _work_complete, _resumes
    _saved_work = check
    _work_complete = complete
    _resumes = resumes


def work_done():
    """The script's work is all written; what remains is its last lines and the exit. A Ctrl-C
    from here on ends it as finished (status 0), not as interrupted (status 130 and 'the same
    command resumes' for a run whose every row was written)."""
    global _done
    _done = True
    _finished()


def _complete_already():
    if _done:
        return True
    try:
        return bool(_work_complete and _work_complete())
    except Exception:  # cannot tell: interrupted, as before
        return False


def _resume_words():
    try:
        return _resumes() if callable(_resumes) else _resumes
    except Exception:  # cannot tell which: the words that hold for both
        return "resumes from the last checkpoint of its preparation or the last state it finished"


def _interrupted_line(what="interrupted"):
    if _saved_work is None:  # stopped before the script knew its output: nothing was saved
        return what + " before the first checkpoint; the same command starts over"
    try:
        saved = _saved_work()
    except Exception:  # cannot look (unreadable, undecodable): the promise that holds whenever one was written
        return what + "; the same command " + _resume_words() + ", if any was written (else it starts over)"
    return what + ("; the same command " + _resume_words() if saved
                   else " before the first checkpoint; the same command starts over")


def _exits_after_script():
    """True when the process ends with the script: python3, or yade-double -x (yade-batch's way);
    a yade-double session left open for the user (no -x) goes on after it."""
    if not in_yade():
        return True
    try:
        from yade import runtime
        return bool(runtime.opts.exitAfter)
    except (ImportError, AttributeError):  # another YADE: keep Ctrl-C working
        return False


def _finished():
    """The work is done and written; only the exit remains: python3's (about 0.03 s) or
    yade-double's (about 0.4 s, IPython's exit handlers). A Ctrl-C there would end the run without
    a word, killed by the signal (status 130 for a run that had finished), or with a traceback from
    IPython's exit handler. From here on SIGINT and
    SIGTERM are ignored, which the interpreter's exit keeps (it resets only handlers of its own):
    the run ends with status 0, as it finished. Not in a yade-double session that stays open, where
    Ctrl-C is the user's again."""
    global _pending
    if threading.current_thread() is not threading.main_thread():
        return
    if _exits_after_script():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
    else:  # the session's Ctrl-C is Python's own again, and no signal of this run is left to raise
        signal.signal(signal.SIGINT, signal.default_int_handler)
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        _pending = None


def guarded(main, resumable=False):
    """Run main(); refusals and ValueError become one line and exit 2. A resumable script (its
    work continues from checkpoints: studies, preparations) says so when interrupted, by Ctrl-C or
    by SIGTERM: what a scheduler sends at the time limit, `kill` by default, and what mpiexec sends
    its ranks when it is interrupted itself (without this, such a run ended with no word). It
    promises a resume only when something was saved (saves_work_in)."""
    # The scripts exit at once on Ctrl-C while they start (their first lines); from here on it
    # raises KeyboardInterrupt again, as under yade-double, so that the line below says what to do.
    global _pending, _guarding
    _pending = None  # a script run again in the same yade-double session starts with none
    _guarding = True
    _after_line.clear()
    signal.signal(signal.SIGINT, _interrupt)
    signal.signal(signal.SIGTERM, _interrupt)
    try:
        main()
        _finished()
    except (Refusal, ValueError) as exc:
        # ValueError: validation inside the library (bad specimen contents, bad arguments to an
        # engine); a traceback would hide the one line the user needs.
        fail(str(exc))
    except (KeyboardInterrupt, Terminated) as exc:
        if _complete_already():  # the signal came after the last result was written: finished
            _finished()
            try:
                sys.stdout.flush()
            except OSError:
                pass
            os._exit(0)
        status = 128 + (signal.SIGTERM if isinstance(exc, Terminated) else signal.SIGINT)
        fail(_interrupted_line() if resumable else "interrupted", status)
    except MemoryError:
        # The estimates refuse a run of a size the machine cannot hold before it starts; this is
        # a run that met less free memory than that (other jobs), or an estimate that fell short.
        fail("out of memory: the run needs more than this machine could give it now (the results already "
             "written are kept); give a smaller size, or run it when more memory is free", 1)
    except BrokenPipeError:
        # The reader of the output went away (`| head`, a closed terminal): a Unix tool ends
        # quietly on SIGPIPE, not with a traceback. Output to nowhere from here on, then the
        # line that says what was kept (on stderr, if it is still open).
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        what = "output closed (broken pipe)"
        fail(_interrupted_line(what) if resumable else what, 128 + signal.SIGPIPE)
    except OSError as exc:  # a full disk, a file system turned read-only, a permission taken away
        fail(io_error_line(exc, resumable), 1)


def tool(main):
    """Run an analysis tool's main() (python3 -m trueaniso.analysis.X), which returns its exit
    status (None: 0) and prints its own refusals, under guarded: Ctrl-C, SIGTERM, a closed pipe or
    an error of the library are one line and their status, as in every script, never a traceback."""
    def run():
        status = main()
        if status:
            try:
                sys.stdout.flush()
            except OSError:
                pass
            os._exit(status)
        work_done()
    guarded(run)


def io_error_line(exc, resumable=False):
    """The one line of an I/O error mid-run: the file, the reason, that what was written stays
    (results are written atomically or appended row by row) and how to go on."""
    import errno
    where = "%s: %s" % (exc.filename, exc.strerror) if exc.filename else (exc.strerror or str(exc))
    fix = {errno.ENOSPC: "free space there", errno.EDQUOT: "free space there (disk quota)",
           errno.EROFS: "make that file system writable", errno.EACCES: "make it writable for this user",
           errno.EPERM: "make it writable for this user"}.get(exc.errno, "fix that")
    if resumable:
        return "%s; the results already written are kept; %s and run the same command again: %s" % (
            where, fix, "it " + _resume_words() if _saved() else "it starts over")
    return "%s; files already written are kept; %s and run the same command again" % (where, fix)


def _saved():
    try:
        return bool(_saved_work and _saved_work())
    except Exception:
        return False
