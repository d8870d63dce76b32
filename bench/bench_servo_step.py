"""The cost of a study's step, with the true-triaxial servo in the chain, against a bare step.

    /usr/bin/python3 bench/bench_servo_step.py --specimen S.npz [--tile K] [--tree DIR ...] [--doc docs/studies/benchmarks.md]

A bare step is contact detection, contact forces and the integrator at a fixed time step; a servo
step adds a TrueTriaxialServo loading the cell along state 21's path (b = 0.5, sigma_z 140 kPa,
0.5 Pa a step, never settling), which reads the stress, the affine stiffness and the unbalanced
force every step (control/CellMeasurement.hpp). Each run is a process of its own that imports a
source tree's package and engines (--tree, each built: ./setup.sh; the default is this tree), loads
the specimen, tiles it K x K x K times if asked (spheres and clumps; numbered in grid rows, as a
prepared specimen of that size is) and steps it. Rounds interleave every tree, mode and thread
count; the figure is particle-steps per second of the timed steps (per CPU second on one thread,
the figure other jobs on a shared machine disturb least; per second of wall time on more), and the servo's
cost is the ratio of the servo step's time to the bare step's in the same round (median and range
over the rounds).

With --callgrind the steps are counted in instructions instead (valgrind's callgrind, one thread):
each mode is run for two step counts and the difference, divided by the steps between them, is
the cost of one step without the set-up. Instruction counts are the same run after run, so a
shared machine does not disturb them; they are not times (a cache miss costs no instruction).
With --doc the table between <!-- NAME:begin --> and <!-- NAME:end --> (--block) is replaced.
"""
import os
import re
import shlex
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

# Run in a fresh interpreter with the tree's pyscripts first on the path: it uses only what every
# tree has (specimen_file.load, dem.Chain, the servo's settings), so it can time an older tree.
WORKER = r"""
import json, sys, time
tree, specimen, tile, steps, mode, here = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4]), sys.argv[5], sys.argv[6]
sys.path[:0] = [tree + "/pyscripts", tree + "/bench", tree + "/pyscripts/bench"]  # bench/ (older trees: pyscripts/bench)
sys.path.append(here)  # this script, for its tiler
import numpy as np
from trueaniso import dem, engines, specimen_file
s, _ = specimen_file.load(specimen)
if tile > 1:
    import _bench, bench_servo_step
    s = bench_servo_step.tiled(s, tile)
    s.reorder_bodies(_bench.grid_rows(s))
dem.refresh(s)
s.dt = 0.5 * engines.TimeStepper.stiffness_bound(s)
controllers = []
if mode == "servo":
    servo = engines.TrueTriaxialServo()
    servo.set_goal(0.5, 140e3, 100e3)
    servo.path_rate = 0.5
    servo.settle_steps = servo.hold_steps = servo.stall_steps = servo.max_steps = 10 ** 9
    controllers = [servo]
c = dem.Chain(s, damping=0.2, controllers=controllers)
c.timestep.dead = True
if controllers:
    servo.start(s)
c.run(20)
t, cpu = time.perf_counter(), time.process_time()
c.run(steps)
wall, cpu = time.perf_counter() - t, time.process_time() - cpu
if controllers:
    assert servo.status == "loading", servo.status
print("BENCH " + json.dumps(dict(n=s.num_bodies, steps=steps, wall=wall, cpu=cpu, level=engines.build_arch())))
"""

MODES = ("bare", "servo")


tiled = _bench.tiled  # spheres or clumps; the workers call it by this module's name


def run(tree, specimen, tile, steps, mode, threads, callgrind=False, level=None):
    """One worker: its answer (wall time), or with callgrind the instructions it executed. level:
    TRUEANISO_LEVEL for the worker (None: the level its package chooses)."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads), TRUEANISO_BUILD=os.path.join(tree, "build"))
    env.pop("TRUEANISO_LEVEL", None)
    if level:
        env["TRUEANISO_LEVEL"] = level
    cmd = ["/usr/bin/python3", "-c", WORKER, tree, specimen, str(tile), str(steps), mode, HERE]
    if callgrind:
        cmd = ["valgrind", "--tool=callgrind", "--callgrind-out-file=/dev/null"] + cmd
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=7200)
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if out.returncode != 0 or not line:
        cli.fail("benchmark worker failed (%s, %s):\n%s" % (tree, mode, out.stderr[-2000:]), 1)
    import json
    answer = json.loads(line[-1][6:])
    if callgrind:
        found = re.findall(r"Collected : (\d+)", out.stderr)
        if not found:
            cli.fail("callgrind printed no instruction count:\n%s" % out.stderr[-2000:], 1)
        answer["instructions"] = int(found[-1])
    return answer


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", action="append", required=True, help="specimen file (.npz); may be given again")
    p.add_argument("--tile", default="1", help="tiling counts K, comma separated (K^3 times the particles)")
    p.add_argument("--tree", action="append", default=None,
                   help="a built source tree to time (default: this one); give it again for another")
    p.add_argument("--label", action="append", default=None, help="the name of each --tree in the table")
    p.add_argument("--level", action="append", default=None,
                   help="TRUEANISO_LEVEL of each --tree's runs ('-': the level its package chooses); a tree may be "
                        "given twice with two levels")
    p.add_argument("--threads", default="1", help="thread counts, comma separated")
    p.add_argument("--steps", type=int, default=2000, help="timed steps a run")
    p.add_argument("--repeats", type=int, default=5, help="rounds")
    p.add_argument("--callgrind", action="store_true", help="count instructions (callgrind) instead of timing")
    p.add_argument("--doc", help="Markdown file whose table is replaced")
    p.add_argument("--block", default="servo-step", help="name of the table's markers in --doc")
    o = cli.parse(p)
    o.trees = [os.path.abspath(t) for t in (o.tree or [os.path.dirname(_bench._PYSCRIPTS)])]
    o.labels = o.label or [os.path.basename(t) for t in o.trees]
    if len(o.labels) != len(o.trees):
        cli.fail("--label: one for each --tree")
    o.levels = [None if lv in ("-", "") else lv for lv in (o.level or ["-"] * len(o.trees))]
    if len(o.levels) != len(o.trees):
        cli.fail("--level: one for each --tree")
    o.runs = list(zip(o.trees, o.labels, o.levels))
    for t in o.trees:
        if not os.path.isdir(os.path.join(t, "build", "python")):
            cli.fail("--tree %s: no build/python in it (./setup.sh builds it)" % t)
    o.tiles = _bench.tile_counts(o.tile)
    try:
        o.thread_counts = [int(x) for x in o.threads.split(",")]
    except ValueError:
        cli.fail("--threads: whole numbers separated by commas, not %r" % o.threads)
    if o.steps < 10 or o.repeats < 1:
        cli.fail("--steps must be >= 10 and --repeats >= 1")
    if o.callgrind and o.thread_counts != [1]:
        cli.fail("--callgrind counts one thread's instructions: --threads 1")
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def specimen_line(path, tile):
    from trueaniso import specimen_file
    arrays, meta = specimen_file.read(path)
    assembly = (meta.get("parameters") or {}).get("assembly", "sphere")
    n = len(arrays["positions"]) * tile ** 3
    return assembly, n


def timed(o):
    rows = []
    o.loaded = {}
    settings = [(sp, k, th) for sp in o.specimen for k in o.tiles for th in o.thread_counts]
    results = {}
    for r in range(o.repeats):
        for sp, k, th in settings:
            runs = [(tree, mode) for tree in o.runs for mode in MODES]
            if r % 2:
                runs.reverse()
            for tree, mode in runs:
                a = run(tree[0], sp, k, o.steps, mode, th, level=tree[2])
                o.loaded[tree] = a["level"]
                # One thread: CPU time, which other jobs on the machine disturb least; a team's
                # CPU time counts its waits at barriers, so two threads are timed on the wall.
                seconds = a["cpu"] if th == 1 else a["wall"]
                results.setdefault((sp, k, th, tree, mode), []).append(a["n"] * a["steps"] / seconds / 1e6)
                print("round %d: %s x%d, %d thread(s), %s %s: %.3f M particle-steps/s"
                      % (r + 1, os.path.basename(sp), k, th, tree[1], mode,
                         results[(sp, k, th, tree, mode)][-1]), flush=True)
    for sp, k, th in settings:
        assembly, n = specimen_line(sp, k)
        for tree in o.runs:
            bare, servo = results[(sp, k, th, tree, "bare")], results[(sp, k, th, tree, "servo")]
            ratio = [b / s for b, s in zip(bare, servo)]  # time of a servo step over a bare one
            rows.append("| %s | %d | %d | %s (%s) | %.2f | %.2f | %.2f (%.2f-%.2f) |"
                        % (assembly, n, th, tree[1], o.loaded[tree], statistics.median(bare), statistics.median(servo),
                           statistics.median(ratio), min(ratio), max(ratio)))
    head = ("| assembly | particles | threads | code | bare step (M particle-steps/s) | servo step | servo step / bare step "
            "(median, range) |\n|---|---|---|---|---|---|---|")
    return head + "\n" + "\n".join(rows), ("medians of %d interleaved rounds of %d steps, per CPU second on one thread and "
                                          "per wall second on more" % (o.repeats, o.steps))


def counted(o):
    rows = []
    short = max(10, o.steps // 4)
    for sp in o.specimen:
        for k in o.tiles:
            assembly, n = specimen_line(sp, k)
            for tree, label, level in o.runs:
                per = {}
                for mode in MODES:
                    a = run(tree, sp, k, short, mode, 1, callgrind=True, level=level)
                    b = run(tree, sp, k, o.steps, mode, 1, callgrind=True, level=level)
                    per[mode] = (b["instructions"] - a["instructions"]) / (o.steps - short)
                    print("%s x%d, %s (%s) %s: %.4g instructions a step" % (os.path.basename(sp), k, label, b["level"],
                                                                            mode, per[mode]), flush=True)
                rows.append("| %s | %d | %s (%s) | %.4g | %.4g | %.3f |" % (
                    assembly, n, label, b["level"], per["bare"], per["servo"], per["servo"] / per["bare"]))
    head = ("| assembly | particles | code | bare step (instructions) | servo step | servo step / bare step |\n"
            "|---|---|---|---|---|---|")
    return head + "\n" + "\n".join(rows), "instructions a step (callgrind), the difference of runs of %d and %d steps" % (
        short, o.steps)


def main():
    o = options()
    table, how = counted(o) if o.callgrind else timed(o)
    load = os.getloadavg()
    _bench.publish(o.doc, o.block, "Machine: %s; load average %.1f at the end; %s, one process at a time, %s.\n\n%s\n\n"
                   "Reproduce: `/usr/bin/python3 bench/bench_servo_step.py %s`"
                   % (_bench.machine(), load[1], how, time.strftime("%Y-%m-%d"), table, shlex.join(sys.argv[1:])))


if __name__ == "__main__":
    main()
