"""A results directory is one study.

``metadata.json`` holds the study's fingerprint: what every row and checkpoint in the directory
depends on (the specimen's checksum, the code version, the engine thread count, the effective
state and probe settings, and for run_study.py the specimen recipe) and the definitions of the
states (id -> b, sigma_z). A run into an existing directory compares them with its own before any
work; on a difference it refuses in one line that names the difference and the way out. Adding
states or probe axes to a study is its normal way to grow and is allowed; redefining a state is not.

All of this runs under the directory's lock (trueaniso/lock.py). Under the lock, the temporary
files (``.tmp-*``) that a killed run left behind are removed: no live writer can own them.
docs/runs.md states the contract.
"""
import contextlib
import json
import math
import os
import shutil
import time

from . import atomic, lock, resources, validate
from .refusal import Refusal

METADATA = "metadata.json"
SUPERSEDED = "superseded"
LAYOUT = 2  # of metadata.json; layout 1 (no fingerprint) cannot prove what its rows were made with
CSV_NAME = "probes.csv"  # one row per state and probe direction (trueaniso/study.py)


def checkpoint_path(out, sid):
    """The checkpoint of state `sid` in the study directory `out`: the scene held at that state."""
    return os.path.join(out, "states", "%s.npz" % sid)
WAY_OUT = "use a new --out, or --force-new to move the old study aside into %s/"


LABELS = {"assembly": "the assembly (assembly: sphere, clump1 or clump2)", "code": "the code version (code: a hash of engines/ and pyscripts/trueaniso/, and of the x86-64 level the engines were built for, TRUEANISO_ARCH)",
          "specimen": "the specimen (specimen: its checksum)", "threads": "the engine thread count (threads)",
          # The fields the scripts' options set, named by the option (--mu 0.3, not
          # "state.friction is 0.5 there, 0.3 in this run").
          "state.friction": "the loading friction (--mu; state.friction)",
          "state.path_rate": "the path rate (--path-rate; state.path_rate)",
          "state.time_step": "the time step rule of the states (--time-step; state.time_step)",
          "probe.time_step": "the time step rule of the probes (--time-step; probe.time_step)",
          "state.rolling_stiffness": "the rolling stiffness (--rolling-stiffness; state.rolling_stiffness)",
          "state.rolling_friction": "the rolling friction (--rolling-friction; state.rolling_friction)",
          "probe.damping": "the damping (--damping; probe.damping)",
          "state.damping": "the damping (--damping; state.damping)",
          "probe.gamma": "the probe strain (--gamma; probe.gamma)",
          "probe.rotations": "the probes' rotations (--rotations; probe.rotations)",
          "probe.detection": "the probes' contact detection (--skip-detection; probe.detection)",
          "probe.sides": "the probes' sides (--probe-sides; probe.sides)",
          "path": "the loading path (--path)"}


class StudyMismatch(Refusal):
    """The directory holds another study than the run asks for."""


def _way_out(out):
    return WAY_OUT % os.path.join(out, SUPERSEDED)


def clean_strays(out, log=print, subdirs=("", "states", "figures")):
    """Remove the temporary files of dead runs (the caller holds the lock)."""
    assert lock.is_held(out), "strays can only be cleaned under the results directory's lock"
    gone = []
    for sub in subdirs:
        d = os.path.join(out, sub)
        if not os.path.isdir(d):
            continue
        for name in os.listdir(d):
            if name.startswith(".tmp-"):
                os.unlink(os.path.join(d, name))
                gone.append(os.path.join(sub, name))
    if gone:
        log("%s: removed %d temporary file(s) of an interrupted run: %s" % (out, len(gone), ", ".join(gone)))
    return gone


def has_saved_work(out):
    """True when the study in `out` has something a rerun continues from: a row in probes.csv or
    a state's checkpoint (states/ID.npz)."""
    csv = os.path.join(out, CSV_NAME)
    if os.path.isfile(csv):
        with open(csv) as f:
            if sum(1 for line in f if line.strip()) > 1:  # the header and a row
                return True
    states = os.path.join(out, "states")
    return os.path.isdir(states) and any(n.endswith(".npz") and not n.startswith(".") for n in os.listdir(states))


def has_rows(out, state_ids, probes):
    """True when probes.csv in `out` holds a complete row of every state and probe asked for: the
    run's work is all written (cli.guarded then takes a late Ctrl-C as the exit's, not the work's)."""
    from . import results_csv
    try:
        rows = results_csv.read(os.path.join(out, CSV_NAME)).rows
    except Exception:  # unreadable: not known to be complete
        return False
    have = {(r.get("state"), r.get("probe")) for r in rows}
    return all((str(i), p) in have for i in state_ids for p in probes)


def supersede(out, log=print):
    """--force-new: move everything of the old study into out/superseded/<time>/ (nothing is
    deleted); the caller holds the lock."""
    assert lock.is_held(out)
    names = [n for n in os.listdir(out) if n not in (lock.LOCK_NAME, SUPERSEDED)]
    if not names:
        return None
    target = os.path.join(out, SUPERSEDED, time.strftime("%Y%m%d-%H%M%S"))
    k = 1
    while os.path.exists(target):
        k += 1
        target = os.path.join(out, SUPERSEDED, time.strftime("%Y%m%d-%H%M%S") + "-%d" % k)
    os.makedirs(target)
    for n in names:
        os.rename(os.path.join(out, n), os.path.join(target, n))
    log("%s: the earlier study moved to %s (--force-new)" % (out, target))
    return target


@contextlib.contextmanager
def undone_if_nothing_saved(out, new, log=print):
    """For the block that starts a study in `out`: when it ends in an error before a row or a
    checkpoint is saved and the study is `new` (no metadata.json before), the metadata.json and
    the empty states/ it wrote are removed, so that the directory holds no study that was never
    run (the next run there, with other settings, was refused as 'another study')."""
    try:
        yield
    except Exception:
        if new and not has_saved_work(out):
            for name in (METADATA, CSV_NAME):
                path = os.path.join(out, name)
                if os.path.isfile(path):
                    os.unlink(path)
            states = os.path.join(out, "states")
            if os.path.isdir(states) and not os.listdir(states):
                os.rmdir(states)
        raise


def read_metadata(out):
    path = os.path.join(out, METADATA)
    if not os.path.exists(path):
        return None
    try:
        with open(path) as f:
            meta = json.load(f)
    except (OSError, ValueError) as exc:
        raise StudyMismatch("%s is unreadable (%s): the study in %s cannot be checked; %s"
                            % (path, exc, out, _way_out(out))) from None
    if isinstance(meta, dict) and meta.get("layout") != LAYOUT:
        return meta  # an older layout: require_layout names it as such
    found = validate.problem(meta, "study")
    if found:
        raise StudyMismatch("%s: %s: %s; the study in %s cannot be checked; %s"
                            % (path, *found, out, _way_out(out)))
    return meta


def checkpoint_problem(exc, state):
    """The message for a study's checkpoint (states/ID.npz) that specimen_file cannot read: named
    as the checkpoint it is, with the way out (a removed one is reached again)."""
    text = str(exc)
    text = (text.replace("specimen file", "checkpoint of state %s," % state, 1) if "specimen file" in text
            else "checkpoint of state %s: %s" % (state, text))
    return "%s; remove it and rerun to compute it again" % text


def threads_of(out):
    """The engine thread count of the study `out` holds, or None (no study, or none readable:
    the checks that follow say what is wrong with it)."""
    try:
        t = read_metadata(out)["fingerprint"]["threads"]
    except (StudyMismatch, OSError, TypeError, KeyError):
        return None
    return t if isinstance(t, int) and t > 0 else None


def state_option_of(out, name):
    """A setting of the states (fingerprint state.<name>) of the study `out` holds, or None (no
    study, none readable, or one from before the setting existed)."""
    try:
        return read_metadata(out)["fingerprint"]["state"][name]
    except (StudyMismatch, OSError, TypeError, KeyError):
        return None


def time_step_rules_of(out):
    """(the states' rule, the probes' rule) of the study `out` holds, or None (no study, or none
    readable: the checks that follow say what is wrong with it). A study that records no rule
    (fingerprint state.time_step, probe.time_step) was made with options.UNRECORDED_TIME_STEP:
    its states before the rule was recorded, its probes before they took the study's rule."""
    from .options import TIME_STEP_RULES, UNRECORDED_TIME_STEP
    try:
        fp = read_metadata(out)["fingerprint"]
        state, probe = fp["state"], fp["probe"]
    except (StudyMismatch, OSError, TypeError, KeyError):
        return None
    if not (isinstance(state, dict) and isinstance(probe, dict)):
        return None
    rules = tuple(part.get("time_step", UNRECORDED_TIME_STEP) for part in (state, probe))
    return rules if all(r in TIME_STEP_RULES for r in rules) else None


def path_rate_of(out):
    """The servo's path rate (Pa per step) of the study `out` holds, or None (no study, none
    readable, or one from before the rate was an option: the checks that follow say what is wrong)."""
    try:
        return float(state_option_of(out, "path_rate"))  # "inf" is how metadata.json keeps an infinite rate (study._effective)
    except (TypeError, ValueError):
        return None


def _normal(x):
    """JSON's view of a value (tuples become lists, numpy scalars numbers): what metadata holds."""
    return json.loads(json.dumps(x, default=atomic._jsonable))


def states_key(fingerprint):
    """What a state's checkpoint depends on, as one hash: the study's fingerprint without its probe
    options (specimen, code, path, threads, every option of reaching a state). A checkpoint records
    it, and one of another study is refused on load: a checkpoint made at --mu 0.3 copied into a
    study at 0.5 must not start a later state without a word."""
    import hashlib
    reach = {k: v for k, v in _normal(fingerprint).items() if k != "probe"}
    return hashlib.sha256(json.dumps(reach, sort_keys=True).encode()).hexdigest()[:16]


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        name = prefix + str(k)
        if isinstance(v, dict):
            out.update(_flat(v, name + "."))
        else:
            out[name] = v
    return out


NON_FINITE = ("inf", "-inf", "nan")  # how metadata.json keeps a non-finite number (study._effective)


def _show(v):
    """A value as a refusal line says it: JSON's spelling, but a non-finite number as the user
    types it (inf, not JSON's Infinity), whether it is a float here or metadata's text there."""
    if v is _ABSENT:
        return "absent"
    if isinstance(v, float) and not math.isfinite(v):
        return repr(v)
    return v if v in NON_FINITE else json.dumps(v)


_ABSENT = object()


def differences(old, new, rel_tol=0.0):
    """[(field, value there, value here)] over the flattened dicts (a field one lacks is _ABSENT).
    The one comparison behind every refusal that names what differs: a study's fingerprint, a
    preparation checkpoint's recipe, an existing specimen's settings. Numbers within `rel_tol`
    are the same (a specimen file stores d50 as the size distribution computed it)."""
    a, b = _flat(old), _flat(new)
    return [(k, a.get(k, _ABSENT), b.get(k, _ABSENT)) for k in sorted(set(a) | set(b))
            if not _same(a.get(k, _ABSENT), b.get(k, _ABSENT), rel_tol)]


def said(diff):
    """The differences in words, one per field: "seed: 7 there, 8 here"."""
    return ["%s: %s there, %s here" % (k, _show(x), _show(y)) for k, x, y in diff]


def _same(x, y, rel_tol):
    numbers = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in (x, y))
    return math.isclose(x, y, rel_tol=rel_tol) if numbers and rel_tol else x == y


def states_table(states):
    """{id as text: {b, sigma_z}} of [(id, b, sigma_z)]."""
    return {str(i): dict(b=float(b), sigma_z=float(sz)) for i, b, sz in states}


def require_layout(out, meta):
    if meta.get("layout") != LAYOUT or "fingerprint" not in meta:
        raise StudyMismatch("%s was written by an older trueaniso without a study fingerprint: its rows cannot be "
                            "proved to match this run; %s" % (out, _way_out(out)))


def with_unrecorded_rules(fingerprint):
    """A study's fingerprint with the time step rules and probe sides it does not record filled in:
    what it was made with (options.UNRECORDED_TIME_STEP, UNRECORDED_PROBE_SIDES), so that the same
    setting continued is no difference."""
    from .options import UNRECORDED_PROBE_SIDES, UNRECORDED_TIME_STEP
    out = dict(fingerprint)
    for part in ("state", "probe"):
        if isinstance(out.get(part), dict) and "time_step" not in out[part]:
            out[part] = dict(out[part], time_step=UNRECORDED_TIME_STEP)
    if isinstance(out.get("probe"), dict) and "sides" not in out["probe"]:
        out["probe"] = dict(out["probe"], sides=UNRECORDED_PROBE_SIDES)
    return out


def check(out, fingerprint, states):
    """The existing metadata when the directory holds this study (or None when it holds none);
    raises StudyMismatch naming the first difference."""
    states_dir = os.path.join(out, "states")
    if os.path.lexists(states_dir) and not os.path.isdir(states_dir):
        raise StudyMismatch("%s is not a directory: a study keeps its state checkpoints there; move it away, or %s"
                            % (states_dir, _way_out(out)))
    meta = read_metadata(out)
    if meta is None:
        others = [n for n in os.listdir(out) if n in (CSV_NAME, "states")]
        if others:
            raise StudyMismatch("%s holds results (%s) but no %s: nothing proves which study they belong to; %s"
                                % (out, ", ".join(others), METADATA, _way_out(out)))
        return None
    require_layout(out, meta)
    diff = differences(with_unrecorded_rules(meta["fingerprint"]), _normal(fingerprint))
    if diff:
        field, there, here = diff[0]
        more = " (and %d more difference%s)" % (len(diff) - 1, "s" if len(diff) > 2 else "") if len(diff) > 1 else ""
        way = _way_out(out)
        if field.startswith("recipe.") and here is _ABSENT:
            # run_states.py on run_study.py's directory: "recipe.assembly is "sphere" there, absent
            # in this run" would name a field the user never set.
            raise StudyMismatch("%s holds a study made by run_study.py (its specimen recipe, %s, is there and "
                                "run_states.py gives none); continue it with run_study.py, or %s"
                                % (out, ", ".join(k for k, _, _ in diff if k.startswith("recipe.")), way))
        if field == "threads" and len(diff) == 1 and isinstance(there, int):
            # The same study on another thread count: the last bits of every sum would differ.
            way = "continue it with --threads %d (under yade-double: -j %d), or %s" % (there, there, way)
            if resources.openmp_threads_env() == str(here):  # --threads 0 took it from there
                more = " (OMP_NUM_THREADS=%s)" % os.environ["OMP_NUM_THREADS"] + more
        if field == "code":
            # A build for another x86-64 level is another code (provenance.code_version): say which,
            # since the sources may well be the same.
            from . import buildarch, engines
            built = (meta.get("versions") or {}).get("build", buildarch.BASELINE)
            if built != engines.build_arch():
                more = " (its engines were built for %s, this run's for %s)" % (built, engines.build_arch()) + more
                way = "continue it at %s: %s, or %s" % (
                    built, buildarch.how_to_run_at(built, os.path.dirname(engines.__file__)), way)
        raise StudyMismatch("%s holds another study: %s is %s there, %s in this run%s; %s"
                            % (out, LABELS.get(field, field), _show(there), _show(here), more, way))
    have = meta.get("states", {})
    for sid, d in states_table(states).items():
        if sid in have and have[sid] != d:
            # %.12g: %g prints 100050 for both 100050 and 100049.99
            raise StudyMismatch("%s holds another study: state %s is b = %.12g, sigma_z = %.12g Pa there, b = %.12g, "
                                "sigma_z = %.12g Pa in this run; %s" % (out, sid, have[sid]["b"], have[sid]["sigma_z"],
                                                                         d["b"], d["sigma_z"], _way_out(out)))
    return meta


def write_metadata(out, fingerprint, states, probes, record, previous=None):
    """metadata.json with the union of the states and probe axes done or asked so far, and this
    run appended to the list of runs (atomic; the caller holds the lock)."""
    previous = previous or {}
    table = dict(previous.get("states", {}))
    table.update(states_table(states))
    axes = list(previous.get("probes", []))  # a list of axis names ("zxy" before shear probes)
    axes += [a for a in probes if a not in axes]
    runs = list(previous.get("runs", [])) + [_normal(record)]
    meta = dict(layout=LAYOUT, about="a trueaniso study: every row and checkpoint here was made with this "
                                     "fingerprint (docs/runs.md)",
                fingerprint=_normal(fingerprint), states=table, probes=axes, runs=runs)
    for k in ("specimen", "versions", "parameters"):
        if k in record:
            meta[k] = _normal(record[k])
    atomic.write_json(os.path.join(out, METADATA), meta)
    return meta


def record_cost(out, meta, cost):
    """This run's cost (run_cost.Meter.record) into its entry, the last of the runs of `meta`, the
    metadata.json write_metadata wrote for it, written again (atomic; the caller holds the lock):
    not read back and validated again, since this run wrote it."""
    meta["runs"][-1]["cost"] = _normal(cost)
    atomic.write_json(os.path.join(out, METADATA), meta)


def remove(paths, log=print):
    """Remove derived files (a summary that a new run will write again)."""
    for p in paths:
        if os.path.isdir(p):
            shutil.rmtree(p)
        elif os.path.exists(p):
            os.unlink(p)
