"""Speed of the stepper against YADE's and LAMMPS's on the same consolidated packing.

    /usr/bin/python3 bench/bench_stepper.py --specimen S.npz [--doc docs/benchmarks.md]

Every code runs the same scene (spheres, periodic cell) at the same fixed time step with the
simplified Hertz-Mindlin law: ours (engines, local damping 0.2); YADE 2023.02a
(Law2_ScGeom_MindlinPhys_Mindlin with InsertionSortCollider, local damping 0.2, yade-double -j N);
LAMMPS (Debian's `lmp`) with `pair_style granular` (hertz/material + mindlin, the same law) and
with `gran/hertz/history` (the same normal force and initial shear stiffness, a simpler shear
update), no damping, fix nve/sphere, on N MPI ranks (the Debian build has no OpenMP package), from
data files written by lammps_peer.py. LAMMPS's pair pressure at step 0 is checked against ours
before its time counts: the same packing and law, or the run stops. Each run is its own process;
the figure is particle-steps per second of the timed steps only (set-up excluded); repeats
interleave the codes and the thread counts (both orders rotate) and the median is reported. A
ratio is the median, over the rounds, of ours against the other code in the same round (each
round runs every code on every thread count once, minutes apart at most), with its range: this
machine's speed drifts by more than a change of code over an hour, and a ratio of the medians
would mix runs an hour apart. The speed-up over the first thread count is paired the same way. With --doc the table
between the markers <!-- stepper:begin --> and <!-- stepper:end --> of that file is replaced.

Code `ours+servo` is our stepper with a study's TrueTriaxialServo in the chain (state 21's path,
never settling; _bench.loading_servo): the step of the study's loop, which reads the stress, the
affine stiffness and the unbalanced force every step and deforms the cell (its shear terms too).
Its row is paired with the other codes in the same rounds, as ours is.

--also-build DIR times ours a second time, from the build tree DIR (TRUEANISO_BUILD), in the same
rounds: a build of the same engine sources for another x86-64 level (cmake -DTRUEANISO_ARCH=x86-64-v3,
CMakeLists.txt), one row of its own. Its engine hash must equal this tree's, and its pressure after
the timed steps must equal the default build's within 1e-8 relative (fused multiply-adds change
the last bits, and 8000 steps of 4000 spheres grow them to about 1e-10), or the benchmark stops.
"""
import os
import statistics
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402


def load(o):
    """The specimen, tiled --tile times along each axis (_bench.tiled) if asked. A cell with shear
    terms (the six-component servo leaves ~1e-6 of the edge) is squared by the same function, for
    every code alike: lammps_peer writes an orthorhombic box."""
    from trueaniso import dem, specimen_file
    s, _ = specimen_file.load(o.specimen)
    if o.tile == 1:
        return _bench.orthorhombic(s)
    s = _bench.tiled(s, o.tile)
    # In the order a prepared specimen of that size has (grid rows, _bench.grid_rows): the Morton
    # curve steps ours 6-10 % slower than rows (docs/studies/benchmarks.md, "Stepper changes").
    s.reorder_bodies(_bench.grid_rows(s))
    dem.refresh(s)
    return s


def worker_ours(o, servo=False):
    from trueaniso import engines
    s = load(o)
    c, dt = _bench.time_ours(s, o.dt, o.steps, servo=servo)
    return dict(code="trueaniso" + " servo" * servo, steps=o.steps, seconds=dt, n=s.num_bodies,
                rebuilds=c.detection.rebuilds, pressure=float(engines.stress(s).trace() / 3),
                build=engines.build_arch(), source_hash=engines.source_hash())


def worker_yade(o):
    from yade import O, utils
    from trueaniso import yade_bridge
    s = load(o)
    s.dt = o.dt
    yade_bridge.yade_scene_from(s, O, damping=0.2)
    O.dt = o.dt
    O.run(100, True)
    t = time.perf_counter()
    O.run(o.steps, True)
    dt = time.perf_counter() - t
    return dict(code="yade", steps=o.steps, seconds=dt, n=len(O.bodies),
                pressure=float(-utils.getStress().trace() / 3))


def worker_lammps(style, threads, o, dt, steps):
    import lammps_peer
    from trueaniso import engines
    s = load(o)
    with tempfile.TemporaryDirectory(prefix="lammps-") as d:
        lammps_peer.write_inputs(s, d, style, dt, steps)
        r = lammps_peer.run(d, procs=threads)
    ours = float(engines.stress(s).trace() / 3)
    if not abs(r["pressure"] - ours) <= 1e-6 * abs(ours):  # the same packing and normal law
        cli.fail("LAMMPS %s: pair pressure %.9g Pa at step 0, ours %.9g Pa: not the same scene" % (style, r["pressure"], ours), 1)
    return dict(code="lammps " + style, steps=r["steps"], seconds=r["seconds"], n=r["atoms"], pressure=r["pressure"])


CODES = ("ours", "ours+servo", "yade", "lammps granular", "lammps gran/hertz/history")
SERVO = "ours+servo"  # our stepper with a study's TrueTriaxialServo in the chain (_bench.loading_servo)


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz) to step")
    p.add_argument("--worker", choices=("ours", SERVO, "yade"), help="(internal) time one stepper in this process")
    p.add_argument("--dt", type=float, default=0.0, help="time step (s); 0: half the stiffness bound")
    p.add_argument("--steps", type=int, default=0, help="timed steps of ours and LAMMPS (0: 20000)")
    p.add_argument("--codes", default="ours,yade,lammps granular,lammps gran/hertz/history",
                   help="codes to time, comma separated, from: " + ", ".join(CODES))
    p.add_argument("--threads", default="1,2", help="thread counts to time, comma separated")
    p.add_argument("--repeats", type=int, default=3, help="timed runs per setting (their median is reported)")
    p.add_argument("--tile", type=int, default=1, help="step the specimen tiled K x K x K times (K^3 x its spheres)")
    p.add_argument("--yade-steps", type=int, default=0, help="timed steps of YADE (0: 2000), slower by an order")
    p.add_argument("--doc", help="Markdown file whose stepper table is replaced")
    p.add_argument("--machine-note", default="",
                   help="said after the machine in the table's first line (e.g. that other work was paused)")
    p.add_argument("--block", default="stepper", help="name of the table's markers in --doc (one block per specimen)")
    p.add_argument("--also-build", metavar="DIR",
                   help="also time ours from this build tree, e.g. one configured with -DTRUEANISO_ARCH=x86-64-v3")
    o = cli.parse(p)
    if o.also_build is not None:
        o.also_build = os.path.abspath(o.also_build)
        if not any(f.startswith("_trueaniso") and f.endswith(".so")
                   for f in (os.listdir(os.path.join(o.also_build, "python"))
                             if os.path.isdir(os.path.join(o.also_build, "python")) else ())):
            cli.fail("--also-build: %s has no python/_trueaniso module; a build tree is what cmake -B names"
                     % o.also_build)
    if not 1 <= o.tile <= 4:
        cli.fail("--tile must be 1 to 4, not %d" % o.tile)
    if not all(ch.isalnum() or ch == "-" for ch in o.block) or not o.block:
        cli.fail("--block: a marker name of letters, digits and '-', not %r" % o.block)
    o.codes = [c.strip() for c in o.codes.split(",") if c.strip()]
    for c in o.codes:
        if c not in CODES:
            cli.fail("--codes: %r is not one of %s" % (c, ", ".join(CODES)))
    if len(set(o.codes)) < len(o.codes):  # as --threads: a round times each code once
        cli.fail("--codes: name each code once, not %r" % ",".join(o.codes))
    if "ours" not in o.codes:
        cli.fail("--codes must include ours (every ratio is against it)")
    # Before any work: --dt -1 would be printed as the table's time step, --threads 99 timed,
    # --repeats 0 fail after the runs, --dt nan and --steps -1 inside the engine.
    import math
    from trueaniso import resources
    if not (math.isfinite(o.dt) and o.dt >= 0):
        cli.fail("--dt must be a time step > 0 in s, or 0 for half the stiffness bound; not %r" % o.dt)
    if o.steps < 0 or o.yade_steps < 0 or o.repeats < 1:
        cli.fail("--steps and --yade-steps must be >= 0 (0: their defaults) and --repeats >= 1")
    # resources.check_threads' bound, said in this script's terms: its message offers 0 (all cores),
    # which a benchmark refuses (it times the counts it names).
    try:
        o.thread_counts = [int(t) for t in o.threads.split(",")]
        if not all(1 <= t <= resources.max_threads() for t in o.thread_counts):
            raise ValueError
    except ValueError:
        cli.fail("--threads: thread counts 1 to %d, comma separated, not %r" % (resources.max_threads(), o.threads))
    if len(set(o.thread_counts)) < len(o.thread_counts):  # a round times each count once
        cli.fail("--threads: name each thread count once, not %r" % o.threads)
    if not o.worker:
        _bench.sphere_specimen(o.specimen)
        if o.doc:
            _bench.writable_doc(o.doc)
    return o


ALSO = "ours (--also-build)"


def run_worker(code, threads, o, dt):
    me = os.path.abspath(os.path.join(HERE, "bench_stepper.py"))
    steps = (o.yade_steps or 2000) if code == "yade" else (o.steps or 20000)
    if code.startswith("lammps"):
        return worker_lammps(code.split(" ", 1)[1], threads, o, dt, steps)
    args = ["--specimen", o.specimen, "--tile", str(o.tile), "--dt", repr(dt), "--steps", str(steps)]
    if code == ALSO:
        return _bench.run_worker(me, "ours", threads, args, timeout=3600, build=o.also_build)
    if code == SERVO:
        return _bench.run_worker(me, SERVO, threads, args, timeout=3600)
    return _bench.run_worker(me, code, threads, args, timeout=3600)


def disagreement(first, also):
    """Why the --also-build run is not the default build's computation, or None: the same engine
    sources, and the same pressure after the same steps within 1e-8 relative (module doc)."""
    if also["source_hash"] != first["source_hash"]:
        return ("--also-build: its module was built from other engine sources than this tree's; build the same "
                "sources for another level (cmake -S . -B DIR -DTRUEANISO_ARCH=x86-64-v3)")
    if not abs(also["pressure"] - first["pressure"]) <= 1e-8 * abs(first["pressure"]):
        return ("--also-build: pressure %.12g Pa after the timed steps, the default build's %.12g: not the same "
                "computation" % (also["pressure"], first["pressure"]))
    return None


def speedups(these, first):
    """Ours on this row's thread count over ours on the first thread count, round by round: the
    median and range as a table cell ("1" on the first count's own rows)."""
    if these is first:
        return "1"
    r = [a / b for a, b in zip(these, first)]
    return "%.2f (%.2f-%.2f)" % (statistics.median(r), min(r), max(r))


def main():
    o = options()
    if o.worker:
        _bench.reply(worker_yade(o) if o.worker == "yade" else worker_ours(o, servo=o.worker == SERVO))
        return
    from trueaniso import engines, specimen_file
    _, meta = specimen_file.load(o.specimen)
    s = load(o)
    dt = o.dt or 0.5 * engines.TimeStepper.stiffness_bound(s)
    limit = engines.TimeStepper.critical_pair_step(s)
    if dt >= limit:  # before any run, not in a worker after the others have been timed
        cli.fail("--dt %g s: unstable on this packing (the two-body limit of its stiffest contact is %.3g s)"
                 % (dt, limit))
    threads = o.thread_counts
    codes = o.codes + ([ALSO] if o.also_build else [])
    ours = ["ours"] + ([ALSO] if o.also_build else []) + ([SERVO] if SERVO in o.codes else [])
    others = [c for c in o.codes if c not in ours]
    level = {}
    # Rounds outside, thread counts inside: every thread count of a round runs within minutes of the
    # others, so the speed-up over one thread is a ratio within a round too. Timed as separate
    # loops over thread counts, the 2-thread runs would come tens of minutes after the 1-thread
    # ones and the speed-up take the machine's drift with it (1.57 at 16,000 spheres; paired
    # within rounds, 1.66 and 1.87 in two runs hours apart, single rounds 1.37-2.29).
    res = {(th, c): [] for th in threads for c in codes}
    for rep in range(o.repeats):
        j = rep % len(threads)
        for th in threads[j:] + threads[:j]:  # the order of the thread counts rotates too
            k = rep % len(codes)
            runs = {}
            for code in codes[k:] + codes[:k]:  # the order rotates, so no code always runs first
                r = runs[code] = run_worker(code, th, o, dt)
                res[th, code].append(r["n"] * r["steps"] / r["seconds"])
                level.setdefault(code, r.get("build"))
                print("round %d threads %d %-26s %.3f M particle-steps/s" % (rep + 1, th, code, res[th, code][-1] / 1e6),
                      flush=True)
            why = disagreement(runs["ours"], runs[ALSO]) if o.also_build else None
            if why:
                cli.fail(why, 1)
    rows = []
    for th in threads:
        for mine in ours:
            ratios = {c: [a / b for a, b in zip(res[th, mine], res[th, c])] for c in others}
            rows.append((th, mine, level[mine], statistics.median(res[th, mine]), {c: statistics.median(res[th, c]) for c in others},
                         ratios, speedups(res[th, mine], res[threads[0], mine])))
    n = s.num_bodies
    names = {"ours": "trueaniso", "yade": "YADE Mindlin", "lammps granular": "LAMMPS granular (mindlin)",
             "lammps gran/hertz/history": "LAMMPS gran/hertz/history"}
    plural = "s" * (threads[0] > 1)
    lines = ["Machine: %s. Specimen: %d spheres%s at 100 kPa (e = %.3f, Zm = %.2f), time step %.3g s, "
             "medians of %d interleaved runs, %s. Threads: OpenMP threads (ours, YADE) or MPI ranks (LAMMPS). "
             "Figures in M particle-steps/s (medians); ratios: ours / theirs in the same round, median and range "
             "over the rounds; x %d thread%s: ours / ours on %d thread%s in the same round, median and range. "
             "Build: the x86-64 level of the engines ours ran (the package loads the fastest the processor "
             "runs; TRUEANISO_LEVEL chooses another)."
             % (_bench.machine() + (", " + o.machine_note if o.machine_note else ""), n, (" (%s tiled %d x %d x %d)" % (os.path.basename(o.specimen), o.tile, o.tile, o.tile)
                                      if o.tile > 1 else ""), meta["summary"]["void_ratio"], meta["summary"]["Zm"], dt, o.repeats,
                time.strftime("%Y-%m-%d"), threads[0], plural, threads[0], plural), "",
             "| threads | step | build | %s |" % " | ".join(["trueaniso", "x %d thread%s" % (threads[0], plural)]
                                                            + ["%s | ratio" % names[c] for c in others]),
             "|" + "---|" * (5 + 2 * len(others))]
    for th, code, build, mine, med, ratios, up in rows:
        cells = ["with the servo" if code == SERVO else "bare", build, "%.2f" % (mine / 1e6), up] + [
            "%.3f | %.2f (%.2f-%.2f)" % (med[c] / 1e6, statistics.median(ratios[c]), min(ratios[c]), max(ratios[c]))
            for c in others]
        lines.append("| %d | %s |" % (th, " | ".join(cells)))

    lines += ["", "Reproduce: `/usr/bin/python3 bench/bench_stepper.py %s`"
              % " ".join(os.path.relpath(a) if os.path.isfile(a) else ("'%s'" % a if " " in a else a) for a in sys.argv[1:])]
    _bench.publish(o.doc, o.block, lines)


if __name__ == "__main__":  # also under yade-double -x; an import runs nothing
    cli.guarded(main)
