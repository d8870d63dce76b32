"""The whole study's clock: the default study (run_study.py) timed end to end on one engine thread
(or --threads), for built checkouts of the code (before and after a change), with where its time goes.

    /usr/bin/python3 bench/bench_study.py --tree BEFORE --label before --specimen S.npz
    /usr/bin/python3 bench/bench_study.py --tree . --label after --specimen S.npz
    /usr/bin/python3 bench/bench_study.py --tree . --label after --prepare --assembly clump2 --n 4000 --seed 1
    /usr/bin/python3 bench/bench_study.py --tabulate --label after --doc docs/benchmarks.md
    /usr/bin/python3 bench/bench_study.py --tabulate --label before --label after \
        --doc docs/studies/benchmarks.md --block study-clock-change

A study run is `TREE/pyscripts/run_study.py --specimen S --ids IDS --threads T` (T is --threads, 1
unless given; the study's own default is every core; all 39 states of
Table C1 unless --ids names fewer; their probes on z, x and y; the static solves of the isotropic
state and of state 21; the figures and the report), a process of its own that imports that tree's
package and engines (TRUEANISO_BUILD=TREE/build; the level each tree's package chooses) into
--runs/LABEL/SPECIMEN. A preparation run (--prepare) is `TREE/pyscripts/prepare_specimen.py` of
the assembly's default recipe (or --recipe), whose specimen a study run can then take. Each run
records its wall time, its CPU time (the process's user and system seconds) and the one-minute
load average at its start and end in --runs/LABEL/NAME.json (with its profile beside it); a run of other --ids on the same specimen and label is a
part of the same study (run_study.py continues the study where it stopped), so that a study longer
than a quiet window is timed in parts whose times add up.

Where the time goes, from Python's own profiler (cProfile) in the timed process, each function's
own time (not what it calls) put in one of these parts:
  stepping     the engines' steps (dem.Chain.run, the C++ loop: contact detection, forces,
               integration, the servo's or the probe's cell measures, separate or fused; and
               dem.refresh, a contact detection);
  measurement  the state measures the study records, outside the steps (trueaniso.fabric, the
               stress and coordination a state's row and the specimen summary read);
  statics      the exact static solves (trueaniso.statics, the sparse factorisation in C++);
  I/O          files: reading (with their checks) and writing specimens, checkpoints, .json and .csv;
  analysis     the zeta fit, the figures and the report (trueaniso.zeta, trueaniso.analysis, matplotlib);
  Python       everything else: the package's own Python, numpy, imports, the checks.
The engines are Boost.Python functions, which the profiler does not see as calls of their own: their
time is the own time of the Python function that calls them, which is why those callers name the
parts. The profiler adds a cost to each Python call, so to the Python part, not to the engines'.

--tabulate (alone, or after the runs) writes one row per label, assembly and specimen: steps of the
states and probes, wall and CPU seconds, and, with more than one label, the first label's time over
each later label's (the speed-up; --label chooses the labels and their order, the first the
reference; all, by name, when none is given); then the seconds of the states, the probes and the
static solves by the study's own timers (probes.csv, the statics records) and of each part by the
profile. Labels that did not run the same states of the same specimen are not compared. Under the
table, the commands that made its runs, as a reader runs them in a checkout: a tree other than
this one is named by its label in capitals, said to be a built checkout of its commit, and the
--runs folders and specimens by their paths in the checkout. With --doc the table between
<!-- NAME:begin --> and <!-- NAME:end --> (--block) is replaced: docs/benchmarks.md holds the
current code's (study-clock), docs/studies/benchmarks.md the codes compared (study-clock-change).
"""
import csv
import json
import os
import pstats
import resource
import shlex
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso importable)
from trueaniso import cli  # noqa: E402

REPO = os.path.dirname(HERE)
ALL_IDS = list(range(1, 40))
HEADING = "## The whole study's clock"  # the section of both benchmarks pages (docs/, docs/studies/)
PARTS = ("stepping", "measurement", "statics", "io", "analysis", "python")
PART_NAMES = dict(stepping="stepping", measurement="measurement", statics="statics", io="I/O", analysis="analysis",
                  python="Python")

# The timed process: the tree's script under the profiler, as `python3 SCRIPT ARGS` would run it
# (run_study.py puts its own pyscripts/ first on the path). The profile is written also when the
# script exits with a status (a refusal), so the parent can say which.
WORKER = r"""
import cProfile, runpy, sys
script, prof = sys.argv[1], sys.argv[2]
sys.argv = [script] + sys.argv[3:]
profile = cProfile.Profile()
profile.enable()
try:
    runpy.run_path(script, run_name="__main__")
finally:
    profile.disable()
    profile.dump_stats(prof)
"""


def part_of(path, function):
    """The part of the study (PARTS) that a function's own time belongs to, from the file it is
    defined in (`~` for built-ins, whose `function` is their description) and its name."""
    p = path.replace("\\", "/")
    if p.endswith("/trueaniso/dem.py") and function in ("run", "refresh"):
        return "stepping"
    if p.endswith("/trueaniso/statics.py"):
        return "statics"
    if p.endswith("/trueaniso/fabric.py") or (p.endswith("/trueaniso/specimen.py") and function == "state"):
        return "measurement"
    if any(m in p for m in ("/matplotlib/", "/PIL/", "/trueaniso/analysis/", "/trueaniso/zeta.py")) or (
            path == "~" and "Imaging" in function):
        return "analysis"
    if any(p.endswith("/trueaniso/%s.py" % m) for m in ("atomic", "specimen_file", "results_csv", "prep_checkpoint")) \
            or any(m in p for m in ("/json/", "/zipfile", "/numpy/lib/npyio.py", "/numpy/lib/format.py", "/csv.py",
                                    "/shutil.py", "/tempfile.py", "/gzip.py", "/_compression.py")):
        return "io"
    if path == "~" and any(w in function for w in ("_io.", "io.open", "posix.", "zlib.", "'read'", "'write'",
                                                   "'flush'", "'close'", "_csv.", "builtins.open")):
        return "io"
    return "python"


def split(profile_path):
    """Seconds of each part (PARTS) in a profile written by WORKER: the sum of its functions' own times."""
    out = dict.fromkeys(PARTS, 0.0)
    for (path, _line, function), (_cc, _nc, own, _cum, _callers) in pstats.Stats(profile_path).stats.items():
        out[part_of(path, function)] += own
    return out


def parse_ids(text):
    """--ids: Table C1 states by number, ranges A-B and single numbers separated by commas."""
    try:
        ids = _bench.state_ids(text)
    except ValueError:
        cli.fail("--ids takes state numbers and ranges separated by commas (1-39, 1,5,21), not %r" % text)
    bad = [i for i in ids if i not in ALL_IDS]
    if bad or not ids or len(set(ids)) != len(ids):
        cli.fail("--ids: states of Table C1 (1-39), each once, not %r" % text)
    return ids


def options(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--tree", action="append", default=None,
                   help="a built checkout to time (default: this one); give it again for another, each with --label")
    p.add_argument("--label", action="append", default=None,
                   help="the name of each --tree in the table; with --tabulate, the codes tabulated, in order (the "
                        "first is the reference of the speed-up; default: every label in --runs)")
    p.add_argument("--specimen", help="specimen file (.npz) the study runs on")
    p.add_argument("--ids", default="1-39", help="Table C1 states of this run: numbers and ranges")
    p.add_argument("--time-step", choices=("smallest-inertia", "per-axis"),
                   help="run_study.py --time-step for the states and probes (default: the tree's own default)")
    p.add_argument("--threads", type=cli.count, default=1,
                   help="engine threads of the timed run (run_study.py or prepare_specimen.py --threads); a label's "
                        "runs all take the same")
    p.add_argument("--prepare", action="store_true", help="time the preparation of a specimen instead of a study")
    p.add_argument("--assembly", type=cli.assembly, default="sphere", help="--prepare: sphere, clump1 or clump2")
    p.add_argument("--n", type=cli.at_least(100, "a study specimen"), default=4000, help="--prepare: particles")
    p.add_argument("--seed", type=cli.count, default=1, help="--prepare: seed of the packing")
    p.add_argument("--recipe", help="--prepare: a named recipe (prepare_specimen.py --recipe) instead of the default")
    p.add_argument("--runs", action="append", default=None,
                   help="where the runs' studies, specimens and records are kept (default: results/bench-study); with "
                        "--tabulate it may be given again, each folder a round of the same runs")
    p.add_argument("--tabulate", action="store_true", help="write the table of the runs recorded in --runs")
    p.add_argument("--doc", help="Markdown file whose table is replaced (with --tabulate)")
    p.add_argument("--block", default="study-clock", help="name of the table's markers in --doc")
    p.add_argument("--note", help="with --tabulate: how the runs were kept apart from other work, for the machine line "
                                  "(e.g. 'other work paused during each run')")
    o = cli.parse(p, argv)
    o.rounds = [os.path.abspath(r) for r in (o.runs or [os.path.join(REPO, "results", "bench-study")])]
    o.runs = o.rounds[0]
    given_trees = o.tree is not None
    o.trees = [os.path.abspath(t) for t in (o.tree or [REPO])]
    o.labels = o.label or [os.path.basename(t) for t in o.trees]
    # With --tabulate alone, --label gives the order of the codes (the first the reference).
    if len(o.labels) != len(o.trees) and (given_trees or o.prepare or o.specimen is not None):
        cli.fail("--label: one for each --tree")
    if len(set(o.labels)) != len(o.labels) or any(not lb or "/" in lb or lb.startswith(".") for lb in o.labels):
        cli.fail("--label: a name for each --tree, each once, without '/'")
    o.ids = parse_ids(o.ids)
    if o.prepare and o.specimen:
        cli.fail("--prepare makes a specimen; --specimen studies one: give one of them")
    if o.prepare and o.time_step:
        cli.fail("--time-step is the study's rule for states and probes: without --prepare")
    if not o.prepare and (o.recipe or o.assembly != "sphere"):
        cli.fail("--assembly, --n, --seed and --recipe describe a preparation: with --prepare")
    o.runs_asked = o.prepare or o.specimen is not None
    if not o.runs_asked and not o.tabulate:
        cli.fail("nothing to do: give --specimen (a study), --prepare (a preparation) or --tabulate")
    if o.tabulate and given_trees and not o.runs_asked:
        cli.fail("--tabulate reads the runs in --runs; --tree times one: give --specimen or --prepare with it")
    if o.runs_asked and len(o.rounds) > 1:
        cli.fail("--runs: one folder for a run (more only with --tabulate alone, each a round)")
    if o.doc and not o.tabulate:
        cli.fail("--doc writes the table: with --tabulate")
    if o.runs_asked:
        for t in o.trees:
            if not os.path.exists(os.path.join(t, "pyscripts", "run_study.py")):
                cli.fail("--tree %s: not a trueaniso checkout (no pyscripts/run_study.py)" % t)
            if not os.path.isdir(os.path.join(t, "build", "python")):
                cli.fail("--tree %s: not built (no build/python in it: ./setup.sh builds it)" % t)
    if o.specimen:
        o.specimen = os.path.abspath(o.specimen)
        o.specimen_info = specimen_info(o.specimen)
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def specimen_info(path):
    """Assembly, particle count and checksum of a specimen file; one line of error otherwise."""
    from trueaniso import specimen_file
    try:
        arrays, meta = specimen_file.read(path)
    except specimen_file.SpecimenFileError as exc:
        cli.fail(str(exc))
    params = meta.get("parameters") or {}
    return dict(assembly=params.get("assembly", "sphere"), n=len(arrays["positions"]), sha256=file_sha256(path),
                level=(meta.get("versions") or {}).get("build", "x86-64"),
                recipe=params.get("recipe") or "default", prepared_wall_time=params.get("wall_time"))


def file_sha256(path):
    import hashlib
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def git_commit(tree):
    """The tree's commit, "-dirty" when what a study runs (pyscripts/, engines/) differs from it."""
    head = subprocess.run(["git", "-C", tree, "rev-parse", "--short=7", "HEAD"], capture_output=True, text=True)
    dirty = subprocess.run(["git", "-C", tree, "status", "--porcelain", "--", "pyscripts", "engines"],
                           capture_output=True, text=True)
    return (head.stdout.strip() or "?") + ("-dirty" if dirty.stdout.strip() else "")


def timed(tree, script, args, prof, log, threads=1):
    """Runs TREE/pyscripts/SCRIPT ARGS under the profiler on `threads` engine threads; returns its
    wall and CPU seconds, the load average before it and the engines' level it loaded."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), TRUEANISO_BUILD=os.path.join(tree, "build"))
    env.pop("TRUEANISO_LEVEL", None)  # the level the tree's package chooses: its default
    cmd = ["/usr/bin/python3", "-c", WORKER, os.path.join(tree, "pyscripts", script), prof] + list(args)
    load = os.getloadavg()[0]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t = time.perf_counter()
    with open(log, "w") as out:
        proc = subprocess.run(cmd, stdout=out, stderr=subprocess.STDOUT, env=env, cwd=tree)
    wall = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        with open(log) as f:
            tail = f.read()[-2000:]
        cli.fail("%s in %s failed (status %d; its output in %s):\n%s" % (script, tree, proc.returncode, log, tail), 1)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # The one-minute load average at the end: about 1 when the run had the machine to itself (the
    # one at the start still carries what a quiet window has just paused).
    return dict(wall=wall, cpu=cpu, load_before=load, load_after=os.getloadavg()[0])


def build_level(tree):
    try:
        with open(os.path.join(tree, "build", "python", "_trueaniso.arch")) as f:
            return f.read().strip()
    except OSError:
        return "?"


def study_times(out, ids, since):
    """From the study in `out`: the steps and seconds of the states and probes `ids` (probes.csv's
    own timers), the seconds of the static solves written since `since` (their records' own; a
    solve a part before wrote is read, not solved again), and the level the study ran at."""
    with open(os.path.join(out, "probes.csv")) as f:
        rows = [r for r in csv.DictReader(f) if r["state"] in {str(i) for i in ids}]
    states = {}
    for r in rows:
        states[r["state"]] = (int(float(r["state_steps"])), float(r["state_wall_time"]))
    statics_s = 0.0
    for name in os.listdir(out):
        if name.startswith("statics_") and name.endswith(".json") and os.path.getmtime(os.path.join(out, name)) >= since:
            with open(os.path.join(out, name)) as f:
                statics_s += float(json.load(f).get("time") or 0.0)
    with open(os.path.join(out, "metadata.json")) as f:
        meta = json.load(f)
    versions = meta["runs"][-1].get("versions", {})
    return dict(states=len(states), state_steps=sum(s for s, _ in states.values()),
                state_seconds=sum(t for _, t in states.values()), probes=len(rows),
                probe_steps=sum(int(float(r["probe_steps"])) for r in rows),
                probe_seconds=sum(float(r["probe_wall_time"]) for r in rows), statics_seconds_recorded=statics_s,
                level=versions.get("build", "x86-64"), state_time_step=meta["fingerprint"]["state"].get(
                    "time_step", "smallest-inertia"))


def untimed_states(out, ids):
    """The states of `ids` whose rows the study in `out` already holds."""
    try:
        with open(os.path.join(out, "probes.csv")) as f:
            have = {r["state"] for r in csv.DictReader(f)}
    except OSError:
        return set()
    return {i for i in ids if str(i) in have}


def record_path(runs, label, name):
    return os.path.join(runs, label, name + ".json")


def load_record(path):
    if not os.path.exists(path):
        return None
    with open(path) as f:
        return json.load(f)


def save_record(path, record):
    from trueaniso import atomic
    os.makedirs(os.path.dirname(path), exist_ok=True)
    atomic.write_json(path, record)


def run_study(o, tree, label):
    info = o.specimen_info
    name = os.path.splitext(os.path.basename(o.specimen))[0]
    out = os.path.join(o.runs, label, name)
    path = record_path(o.runs, label, name)
    record = load_record(path) or dict(kind="study", label=label, tree=tree, specimen=o.specimen, **info, parts=[],
                                       time_step_asked=o.time_step, threads=o.threads)
    if record["sha256"] != info["sha256"]:
        cli.fail("%s records a study of another specimen file than %s (another checksum): another --runs, or "
                 "remove it" % (path, o.specimen))
    if record.get("time_step_asked") != o.time_step:
        cli.fail("%s records a study run with --time-step %s, this run asks %s: another --label" % (
            path, record.get("time_step_asked") or "(the default)", o.time_step or "the default"))
    same_threads(record, path, o.threads)
    done = {i for part in record["parts"] for i in part["ids"]}
    todo = [i for i in o.ids if i not in done]
    if not todo:
        print("%s: states %s of %s already timed (%s)" % (label, ",".join(map(str, o.ids)), name, path))
        return record
    untimed = sorted(untimed_states(out, todo))
    if untimed:  # a run interrupted after some states: the study would skip them, and the clock undercount
        cli.fail("%s already has rows of states %s that no timed run of %s recorded (a run interrupted?): remove %s, "
                 "or give another --runs" % (out, said_ids(untimed), path, out))
    os.makedirs(out, exist_ok=True)
    prof = os.path.join(o.runs, label, "%s-%d.prof" % (name, len(record["parts"]) + 1))
    log = os.path.join(o.runs, label, "%s-%d.log" % (name, len(record["parts"]) + 1))
    args = ["--specimen", o.specimen, "--ids", ",".join(map(str, todo)), "--threads", str(o.threads),
            "--progress-every", "600", "--out", out] + (["--time-step", o.time_step] if o.time_step else [])
    print("%s: run_study.py %s (%s)" % (label, shlex.join(args), tree), flush=True)
    since = time.time()
    clock = timed(tree, "run_study.py", args, prof, log, o.threads)
    part = dict(ids=todo, started=time.strftime("%Y-%m-%dT%H:%M:%S%z"), commit=git_commit(tree),
                built_level=build_level(tree), **clock, split=split(prof), profile=prof, **study_times(out, todo, since))
    record["parts"].append(part)
    save_record(path, record)
    print("%s: %.1f s wall, %.1f s CPU, %d state steps, %d probe steps" % (
        label, part["wall"], part["cpu"], part["state_steps"], part["probe_steps"]), flush=True)
    return record


def same_threads(record, path, threads):
    """A label's runs all take one thread count: a run asking another is refused before it starts."""
    if record.get("threads", 1) != threads:
        cli.fail("%s records a %s on %d engine thread(s), this run asks %d: another --label" % (
            path, "preparation" if record["kind"] == "prepare" else "study", record.get("threads", 1), threads))


def run_preparation(o, tree, label):
    name = "%s-%d-s%d%s" % (o.assembly, o.n, o.seed, "-" + o.recipe if o.recipe else "")
    path = record_path(o.runs, label, "prepare-" + name)
    done = load_record(path)
    if done:
        same_threads(done, path, o.threads)
        print("%s: the preparation of %s already timed (%s)" % (label, name, path))
        return done
    os.makedirs(os.path.join(o.runs, label, "specimens"), exist_ok=True)
    spec = os.path.join(o.runs, label, "specimens", name + ".npz")
    args = ["--assembly", o.assembly, "--n", str(o.n), "--seed", str(o.seed), "--threads", str(o.threads),
            "--progress-every", "600", "--out", spec] + (["--recipe", o.recipe] if o.recipe else [])
    prof = os.path.join(o.runs, label, "prepare-%s.prof" % name)
    log = os.path.join(o.runs, label, "prepare-%s.log" % name)
    print("%s: prepare_specimen.py %s (%s)" % (label, shlex.join(args), tree), flush=True)
    clock = timed(tree, "prepare_specimen.py", args, prof, log, o.threads)
    info = specimen_info(spec)
    record = dict(kind="prepare", label=label, tree=tree, specimen=spec, **info, recipe_asked=o.recipe or "default",
                  seed=o.seed, threads=o.threads, started=time.strftime("%Y-%m-%dT%H:%M:%S%z"), commit=git_commit(tree),
                  built_level=build_level(tree), **clock, split=split(prof), profile=prof)
    save_record(path, record)
    print("%s: prepared %s in %.1f s wall, %.1f s CPU" % (label, spec, record["wall"], record["cpu"]), flush=True)
    return record


def records(runs, round_=0):
    """The records in the folder `runs`, each marked with the round it is (its place among --runs)."""
    out = []
    if not os.path.isdir(runs):
        return out
    for label in sorted(os.listdir(runs)):
        folder = os.path.join(runs, label)
        if not os.path.isdir(folder):
            continue
        for name in sorted(os.listdir(folder)):
            if name.endswith(".json"):
                r = load_record(os.path.join(folder, name))
                if r:
                    out.append(dict(r, round=round_, runs=runs))
    return out


def totals(record):
    """A study record's parts added up: wall, CPU, steps, seconds by part, the states covered."""
    parts = record["parts"]
    t = dict(ids=sorted(i for p in parts for i in p["ids"]), wall=sum(p["wall"] for p in parts),
             cpu=sum(p["cpu"] for p in parts), runs=len(parts), round=record["round"],
             commit=parts[-1]["commit"], level=parts[-1]["level"], time_step=parts[-1]["state_time_step"],
             threads=record.get("threads", 1))
    for key in ("state_steps", "probe_steps", "state_seconds", "probe_seconds", "statics_seconds_recorded"):
        t[key] = sum(p[key] for p in parts)
    t["split"] = {k: sum(resplit(p)[k] for p in parts) for k in PARTS}
    t["loads"] = [p["load_after"] for p in parts if "load_after" in p]
    return t


def said_values(values, digits=0):
    """The median of `values`, with their range when there are more than one: '250 (212-318)'."""
    import statistics
    f = "%%.%df" % digits
    text = f % statistics.median(values)
    return text if len(values) == 1 else "%s (%s-%s)" % (text, f % min(values), f % max(values))


def resplit(run):
    """A run's parts, from its profile when it is still there (so that the table follows part_of
    as it is now), else as recorded."""
    prof = run.get("profile")
    return split(prof) if prof and os.path.exists(prof) else run["split"]


def table(o, order):
    """The Markdown tables of the recorded runs of the labels in `order` (the first is the reference
    of the speed-up; every label when empty), each --runs folder a round; returns (text, notes, load
    averages, whether codes are compared)."""
    recs = [r for k, runs in enumerate(o.rounds) for r in records(runs, k)]
    studies = [r for r in recs if r["kind"] == "study"]
    preps = [r for r in recs if r["kind"] == "prepare"]
    if not studies and not preps:
        cli.fail("no runs recorded in %s: time some first (--specimen or --prepare)" % ", ".join(o.rounds))
    if order:
        missing = [lb for lb in order if not any(r["label"] == lb for r in recs)]
        if missing:
            cli.fail("--label %s: no runs of that label in %s" % (", ".join(missing), ", ".join(o.rounds)))
        recs = [r for r in recs if r["label"] in order]
        studies = [r for r in recs if r["kind"] == "study"]
        preps = [r for r in recs if r["kind"] == "prepare"]
    labels = list(order) or sorted({r["label"] for r in recs})
    rank = {lb: k for k, lb in enumerate(labels)}
    # One code alone (the current code's table): no speed-up columns, and no label to tell codes apart.
    compared = len(labels) > 1

    def code(label, details):
        return "%s (%s)" % (label, details) if compared else details

    def who(assembly, label):
        return "%s %s" % (assembly, label) if compared else assembly
    clock = ["| assembly | particles | code | states | steps: states | steps: probes | rounds | wall (s) | CPU (s) |%s"
             % (" wall: first / this | CPU: first / this |" if compared else ""),
             "|---|---|---|---|---|---|---|---|---|%s" % ("---|---|" if compared else "")]
    where = ["| assembly |%s states (s) | probes (s) | static solves (s) | %s |" % (
        " code |" if compared else "", " | ".join(PART_NAMES[k] for k in PARTS)),
        "|---|%s---|---|---|%s" % ("---|" if compared else "", "---|" * len(PARTS))]
    groups = {}
    for r in studies:
        groups.setdefault((r["assembly"], r["n"], r["sha256"]), {}).setdefault(r["label"], []).append(totals(r))
    notes = []
    order_of = {"sphere": 0, "clump1": 1, "clump2": 2}
    for key in sorted(groups, key=lambda k: (order_of.get(k[0], 9), k[1], k[2])):
        assembly, n = key[0], key[1]
        by_label = groups[key]
        ref_label = min(by_label, key=lambda lb: rank[lb])
        ref = {t["round"]: t for t in by_label[ref_label]}
        for label in sorted(by_label, key=lambda lb: rank[lb]):
            ts = by_label[label]
            t = ts[0]
            if any((u["state_steps"], u["probe_steps"]) != (t["state_steps"], t["probe_steps"]) for u in ts):
                notes.append("%s: its rounds took different steps (%s)" % (
                    who(assembly, label), ", ".join("%d + %d" % (u["state_steps"], u["probe_steps"]) for u in ts)))
            paired = [(ref[u["round"]], u) for u in ts if u["round"] in ref and ref[u["round"]]["ids"] == u["ids"]]
            ratios = " %s | %s |" % (said_values([a["wall"] / u["wall"] for a, u in paired], 2) if paired else "-",
                                     said_values([a["cpu"] / u["cpu"] for a, u in paired], 2) if paired else "-")
            clock.append("| %s | %d | %s | %s | %d | %d | %d | %s | %s |%s" % (
                assembly, n, code(label, "%s, %s, %s%s" % (t["commit"], t["level"], t["time_step"], said_threads(t))),
                said_ids(t["ids"]),
                t["state_steps"], t["probe_steps"], len(ts), said_values([u["wall"] for u in ts]),
                said_values([u["cpu"] for u in ts]), ratios if compared else ""))
            med = lambda key: said_values([u[key] for u in ts])  # noqa: E731
            where.append("| %s |%s %s | %s | %s | %s |" % (
                assembly, " %s |" % label if compared else "", med("state_seconds"), med("probe_seconds"),
                med("statics_seconds_recorded"), " | ".join(said_values([u["split"][k] for u in ts]) for k in PARTS)))
            for u in ts:
                if u["runs"] > 1:
                    notes.append("%s%s: timed in %d runs (states %s), their times added" % (
                        who(assembly, label), " (round %d)" % (u["round"] + 1) if len(o.rounds) > 1 else "", u["runs"],
                        "; ".join(said_ids(p["ids"]) for r in studies if r["label"] == label and r["round"] == u["round"]
                                  and (r["assembly"], r["n"], r["sha256"]) == key for p in r["parts"])))
            if not paired and label != ref_label:
                notes.append("%s %s ran states %s, %s no round of the same: not compared" % (
                    assembly, label, said_ids(t["ids"]), ref_label))
            elif len(paired) < len(ts) and label != ref_label:
                notes.append("%s %s: %d of its %d rounds without a run of %s of the same states, not in its ratio" % (
                    assembly, label, len(ts) - len(paired), len(ts), ref_label))
    text = ""
    if studies:
        text = "\n".join(clock) + "\n\nWhere the time goes, in seconds: the study's own timers (probes.csv, the statics " \
            "records), then the profile's parts:\n\n" + "\n".join(where)
    if preps:
        rows = ["| assembly | particles | code | recipe | wall (s) | CPU (s) | %s |" % " | ".join(
            PART_NAMES[k] for k in PARTS), "|---|---|---|---|---|---|%s" % ("---|" * len(PARTS))]
        for r in sorted(preps, key=lambda r: (order_of.get(r["assembly"], 9), rank[r["label"]], r["round"])):
            part = resplit(r)
            rows.append("| %s | %d | %s | %s | %.0f | %.0f | %s |" % (
                r["assembly"], r["n"], code(r["label"], "%s, %s%s" % (r["commit"], r.get("level", r["built_level"]),
                                                                     said_threads(r))),
                r["recipe_asked"], r["wall"], r["cpu"], " | ".join("%.0f" % part[k] for k in PARTS)))
        text += ("\n\n" if text else "") + "Preparation (prepare_specimen.py), in seconds:\n\n" + "\n".join(rows)
    loads = [x for r in studies for x in totals(r)["loads"]] + [r["load_after"] for r in preps if "load_after" in r]
    return text, notes, loads, compared, {r.get("threads", 1) for r in recs}


def said_threads(record):
    """', 2 threads' for a run on more than one engine thread; '' for one (the machine line says it)."""
    n = record.get("threads", 1)
    return ", %d threads" % n if n != 1 else ""


def said_ids(ids):
    ids = sorted(ids)
    if ids == list(range(ids[0], ids[-1] + 1)) and len(ids) > 2:
        return "%d-%d" % (ids[0], ids[-1])
    return ",".join(map(str, ids))


def inside(path, folder):
    path, folder = os.path.abspath(path), os.path.abspath(folder)
    return path == folder or path.startswith(folder + os.sep)


class Shown:
    """How the commands under a table name the runs' places, so that a reader can run them in a
    checkout of their own: a tree this checkout is `.` (the default, left out), any other the name
    of its label in capitals (BEFORE), said to be a built checkout of its commit; a --runs folder
    outside this checkout results/bench-study (the first round, the default) or
    results/bench-study-K (round K); a specimen file in a --runs folder is named in its round's,
    one in this checkout by its path from the root, one elsewhere as specimens/NAME."""

    def __init__(self, rounds):
        self.rounds = [os.path.abspath(r) for r in rounds]
        self.trees = {}  # placeholder: the commits of the runs that named it
        self.specimens = {}  # a specimen from outside this checkout: what its record says it is

    def runs(self, k):
        folder = self.rounds[k]
        if inside(folder, REPO):
            return os.path.relpath(folder, REPO)
        return os.path.join("results", "bench-study") + ("-%d" % (k + 1) if k else "")

    def runs_option(self, k):
        shown = self.runs(k)
        return "" if shown == os.path.join("results", "bench-study") else " --runs " + shlex.quote(shown)

    def tree(self, record, commit):
        if os.path.abspath(record["tree"]) == REPO:
            return ""
        name = record["label"].upper()
        self.trees.setdefault(name, set()).add(commit.replace("-dirty", ""))
        return " --tree " + shlex.quote(name)

    def specimen(self, record):
        path = record["specimen"]
        for k in range(len(self.rounds)):
            if inside(path, self.rounds[k]):
                return os.path.join(self.runs(k), os.path.relpath(path, self.rounds[k]))
        if inside(path, REPO):
            return os.path.relpath(path, REPO)
        shown = os.path.join("specimens", os.path.basename(path))
        self.specimens[shown] = "a %s specimen of the %s recipe, %d particles, prepared at %s, sha256 %s..." % (
            record["assembly"], record.get("recipe", "default"), record["n"], record.get("level", "x86-64"),
            record["sha256"][:12])
        return shown

    def doc(self, path):
        return os.path.relpath(path, REPO) if inside(path, REPO) else path

    def said(self):
        """What the placeholder trees and the specimens named in specimens/ are, in words ('' when
        there are none): 'BEFORE is a built checkout of 9c084da (...)'."""
        said = []
        if self.trees:
            names = sorted(self.trees)
            first = names[0], sorted(self.trees[names[0]])[0]
            said.append("%s %s %s, made by `git worktree add --detach %s %s` and `./setup.sh _trueaniso` in it" % (
                " and ".join(names), "is a built checkout of" if len(names) == 1 else "are built checkouts of",
                " and ".join(" or ".join(sorted(self.trees[n])) for n in names), first[0], first[1]))
        said += ["%s is %s" % (name, what) for name, what in sorted(self.specimens.items())]
        return "; ".join(said)


def commands(o, labels):
    """The commands that made the recorded runs of `labels` (all when empty), a command that ran in
    more than one round (each --runs folder) once, with the rounds it ran in; then the table's.
    Returns (lines, the sentence that says what the placeholder trees are)."""
    shown = Shown(o.rounds)
    lines, rounds_of = [], {}
    for k, runs in enumerate(o.rounds):
        for r in sorted(records(runs, k), key=lambda r: (r["kind"] != "prepare", r["assembly"], r["label"])):
            if labels and r["label"] not in labels:
                continue
            if r["kind"] == "prepare":
                base = "/usr/bin/python3 bench/bench_study.py%s --label %s%s" % (
                    shown.tree(r, r["commit"]), r["label"], threads_option(r))
                found = ["%s --prepare --assembly %s --n %d --seed %d%s" % (
                    base, r["assembly"], r["n"], r["seed"], "" if r["recipe_asked"] == "default" else
                    " --recipe " + r["recipe_asked"])]
            else:
                rule = " --time-step " + r["time_step_asked"] if r.get("time_step_asked") else ""
                found = ["/usr/bin/python3 bench/bench_study.py%s --label %s%s --specimen %s --ids %s%s" % (
                    shown.tree(r, p["commit"]), r["label"], threads_option(r), shlex.quote(shown.specimen(r)),
                    said_ids(p["ids"]), rule) for p in r["parts"]]
            for command in found:
                if command not in rounds_of:
                    lines.append(command)
                rounds_of.setdefault(command, []).append(k)
    out = []
    for command in lines:
        ks = rounds_of[command]
        again = [shown.runs(k) for k in ks[1:]]
        out.append(command + shown.runs_option(ks[0]) + (
            "   # and again with --runs %s (a round each)" % ", ".join(again) if again else ""))
    # The rounds in their order: each named when there are more than one (the first is the default's).
    tab = "/usr/bin/python3 bench/bench_study.py --tabulate%s%s" % (
        "".join(" --label %s" % lb for lb in labels),
        "".join(" --runs " + shlex.quote(shown.runs(k)) if len(o.rounds) > 1 else shown.runs_option(k)
                for k in range(len(o.rounds))))
    if o.note:
        tab += " --note " + shlex.quote(o.note)
    if o.doc:
        tab += " --doc %s --block %s" % (shlex.quote(shown.doc(o.doc)), o.block)
    return out + [tab], shown.said()


def threads_option(record):
    n = record.get("threads", 1)
    return " --threads %d" % n if n != 1 else ""


def write_table(o):
    labels = o.labels if o.label else []
    body, notes, loads, compared, threads = table(o, labels)
    lines, trees = commands(o, labels)
    load = "one-minute load average %.1f-%.1f at the end of the runs" % (min(loads), max(loads)) if loads else ""
    text = ("Machine: %s%s; %s, %s; %s. "
            "Steps, wall and CPU time of the whole run (CPU: the process's user and system seconds), the median over "
            "its rounds (each --runs folder a round) and their range%s. The parts are each function's own time under "
            "Python's profiler (cProfile), whose sum is the run's wall time within the profiler's cost.%s\n\n%s\n\n"
            "Reproduce (one run a line, then the table%s):\n\n%s"
            % (_bench.machine(), ", " + o.note if o.note else "",
               "one engine thread" if threads == {1} else "engine threads as the code column says (one unless said)",
               load or "no load average recorded",
               time.strftime("%Y-%m-%d"),
               "; first / this: the first code's time over this one's in the same round, on the same specimen and "
               "states" if compared else "",
               "".join(" %s." % (n[0].upper() + n[1:]) for n in notes), body,
               "; " + trees if trees else "",
               "\n".join("    " + c for c in lines)))
    print(text)
    if o.doc:
        _bench.replace_block(o.doc, o.block, text, heading=HEADING)


def main(argv=None):
    o = options(argv)
    if o.runs_asked:
        for tree, label in zip(o.trees, o.labels):
            if o.prepare:
                run_preparation(o, tree, label)
            else:
                run_study(o, tree, label)
    if o.tabulate:
        write_table(o)


if __name__ == "__main__":
    cli.guarded(main)
