"""One stepper change measured: the same packing stepped by two builds of trueaniso, before and after.

    /usr/bin/python3 bench/bench_builds.py --before TREE --after TREE --specimen S.npz [--tiles 1,2] [--doc docs/studies/benchmarks.md]

TREE is a checkout of trueaniso, built (./setup.sh), e.g. `git worktree add ../before HEAD~1`.
Each run is a process of its own that imports that tree's engines and steps the specimen (tiled
K x K x K times and numbered in grid rows, as a prepared specimen of that size is) with
ContactDetection, ContactForces and NewtonIntegrator on one engine thread (--threads N: N), as
bench_stepper.py does; before and after alternate, the first of the pair alternating too.
Figure: particle-steps per CPU second of the timed steps (CPU time, the figure other jobs on the
machine disturb least); with --threads above 1, per second of wall time, since a team's CPU time
counts the threads' waits at its barriers, which is what a change for threads removes. The two builds must step the packing to the same bits (a checksum of the
positions and contact forces after the timed steps is compared): a change that alters results is not a speed-up
of the same computation, and the benchmark refuses to time it as one.
With --state ID the two builds run a whole Table C1 state with its three probes instead
(run_states.py --ids ID --threads 1: the servo, its measures every step, the probes), timed in CPU
seconds and refused when their probe tables differ (wall-time columns aside).
With --doc the table between <!-- NAME:begin --> and <!-- NAME:end --> (--block) is replaced.
"""
import os
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

# Run in a fresh interpreter with the tree's pyscripts first on the path: it uses only what both
# builds have (specimen_file.load, dem.Chain, Scene.contact_arrays), so it can time an older tree.
WORKER = r"""
import hashlib, json, sys, time
tree, specimen, tile, steps = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
sys.path[:0] = [tree + "/pyscripts", tree + "/bench"]
import numpy as np
from trueaniso import dem, specimen_file
s, _ = specimen_file.load(specimen)
if tile > 1:
    import _bench
    s = _bench.tiled(s, tile)
    s.reorder_bodies(_bench.grid_rows(s))  # as a prepared specimen of that size (bench_stepper.py)
    dem.refresh(s)
s.dt = 2.9e-8
c = dem.Chain(s, damping=0.2)
c.timestep.dead = True
c.run(50)
t, w = time.process_time(), time.perf_counter()
c.run(steps)
cpu, wall = time.process_time() - t, time.perf_counter() - w
d = s.contact_arrays()
h = hashlib.sha256()
for a in (s.positions, d["normal_force"], d["shear_force"], d["overlap"]):
    h.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
print("BENCH " + json.dumps(dict(n=s.num_bodies, steps=steps, cpu=cpu, wall=wall, checksum=h.hexdigest()[:16])))
"""


def child_env(threads=1):
    """`threads` engine threads (one unless --threads), and the tree's own compiled module:
    TRUEANISO_BUILD would give both trees the same one."""
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    env.pop("TRUEANISO_BUILD", None)
    return env


def run(tree, specimen, tile, steps, threads=1):
    out = subprocess.run(["/usr/bin/python3", "-c", WORKER, tree, specimen, str(tile), str(steps)],
                         capture_output=True, text=True, env=child_env(threads))
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if out.returncode != 0 or not line:
        cli.fail("stepping with %s failed:\n%s" % (tree, out.stderr[-2000:]), 1)
    import json
    return json.loads(line[-1][6:])


def run_state(tree, specimen, state):
    """CPU seconds of run_states.py --ids STATE of this tree (the state and its three probes) and a
    checksum of its probe table without the wall-time columns."""
    import csv
    import hashlib
    import resource
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        out = subprocess.run(["/usr/bin/python3", os.path.join(tree, "pyscripts", "run_states.py"), "--specimen", specimen,
                              "--ids", str(state), "--threads", "1", "--out", os.path.join(tmp, "s")],
                             capture_output=True, text=True, env=child_env())
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        if out.returncode != 0:
            cli.fail("state %s with %s failed:\n%s" % (state, tree, out.stderr[-2000:]), 1)
        with open(os.path.join(tmp, "s", "probes.csv")) as f:
            rows = list(csv.DictReader(f))
    h = hashlib.sha256()
    for r in rows:
        h.update(repr(sorted((k, v) for k, v in r.items() if not k.endswith("wall_time"))).encode())
    steps = int(float(rows[0]["state_steps"])) + sum(int(float(r["probe_steps"])) for r in rows)
    cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    return dict(cpu=cpu, steps=steps, checksum=h.hexdigest()[:16])


def alternating(o, names, measure, differ):
    """measure(tree) o.repeats times for each build, before and after alternating which goes first;
    the two runs of a pair must give the same checksum (else: 'the two builds DIFFER')."""
    # Keyed by side, not by tree: a tree timed against itself (an A/A check of the noise) keeps its
    # two sides' runs apart, where one list would print a ratio of 1.000.
    runs = {"before": [], "after": []}
    tree = {"before": o.before, "after": o.after}
    for r in range(o.repeats):
        for side in (("before", "after") if r % 2 == 0 else ("after", "before")):
            runs[side].append(measure(tree[side]))
            print("  %s %s %s" % (side, names[side], runs[side][-1]), flush=True)
        a, b = runs["before"][-1]["checksum"], runs["after"][-1]["checksum"]
        if a != b:
            cli.fail("the two builds %s (checksums %s and %s): not the same computation" % (differ, a, b), 1)
    return runs


def paired(before, after, fmt):
    """Table cells: the medians of before and after, the median of the paired ratios after/before
    and their range."""
    ratios = [a / b for a, b in zip(after, before)]
    return (fmt + " | " + fmt + " | %.3f | %.3f - %.3f") % (
        statistics.median(before), statistics.median(after), statistics.median(ratios), min(ratios), max(ratios))


def stepper_table(o, names):
    """The bare stepper on the specimen tiled K x K x K, particle-steps per CPU second (per wall
    second on a team of threads)."""
    team = o.threads > 1
    lines = ["Machine: %s; %s. %s: %s (before) against %s (after), %s, %d interleaved runs "
             "of each, medians; time step 2.9e-8 s, damping 0.2; both builds step to the same bits."
             % (_bench.machine(), time.strftime("%Y-%m-%d"), o.change, names["before"], names["after"],
                "%d engine threads, wall time" % o.threads if team else "one engine thread", o.repeats), "",
             "| spheres | before (M particle-steps per %s s) | after | after / before | paired ratios (min - max) |"
             % ("wall" if team else "CPU"),
             "|---|---|---|---|---|"]
    for k in o.tiles:
        steps = max(50, int(round(o.particle_steps / (o.spheres * k ** 3))))  # the asked particle-steps
        runs = alternating(o, names, lambda tree: run(tree, o.specimen, k, steps, o.threads),
                           "step the packing to different results")
        rate = {t: [x["n"] * x["steps"] / x["wall" if team else "cpu"] / 1e6 for x in xs] for t, xs in runs.items()}
        lines.append("| %d | %s |" % (runs["after"][-1]["n"], paired(rate["before"], rate["after"], "%.2f")))
    return lines


def state_table(o, names):
    """--state: the whole state (servo, measures, probes) as run_states.py runs it, CPU seconds."""
    lines = ["Machine: %s; %s. %s: %s (before) against %s (after): run_states.py --ids %s --threads 1 on %s, "
             "%d alternating runs of each, medians; both builds give the same probe table (wall times aside)."
             % (_bench.machine(), time.strftime("%Y-%m-%d"), o.change, names["before"], names["after"], o.state,
                os.path.basename(o.specimen), o.repeats), "",
             "| state | steps (state and probes) | before (CPU s) | after (CPU s) | after / before | paired ratios (min - max) |",
             "|---|---|---|---|---|---|"]
    runs = alternating(o, names, lambda tree: run_state(tree, o.specimen, o.state),
                       "give different probe tables for state %s" % o.state)
    cpu = {t: [x["cpu"] for x in xs] for t, xs in runs.items()}
    lines.append("| %s | %d | %s |" % (o.state, runs["after"][-1]["steps"], paired(cpu["before"], cpu["after"], "%.1f")))
    return lines


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--before", required=True, help="checkout of trueaniso before the change (built)")
    p.add_argument("--after", required=True, help="checkout of trueaniso with the change (built)")
    p.add_argument("--specimen", required=True, help="sphere specimen (.npz)")
    p.add_argument("--tiles", default="1", help="tilings K (K^3 copies of the specimen), comma separated")
    p.add_argument("--repeats", type=int, default=5, help="runs of each build, interleaved")
    p.add_argument("--particle-steps", type=float, default=1.2e7,
                   help="particle-steps per timed run (steps: this over the spheres of the tiled specimen, at least 50)")
    p.add_argument("--state", help="time a whole Table C1 state with its probes (run_states.py --ids STATE) "
                                   "instead of the bare stepper; CPU seconds")
    p.add_argument("--threads", type=int, default=1,
                   help="engine threads of the bare stepper (above 1: timed in wall seconds)")
    p.add_argument("--change", default="the change", help="what the change is, for the table")
    p.add_argument("--doc", help="Markdown file whose block is replaced")
    p.add_argument("--block", default="stepper-builds", help="marker name of the block in --doc")
    o = cli.parse(p)
    o.tiles = _bench.tile_counts(o.tiles)
    if o.repeats < 1 or min(o.tiles) < 1 or max(o.tiles) > 4:
        cli.fail("--repeats must be >= 1 and --tiles between 1 and 4")
    from trueaniso import resources
    if not 1 <= o.threads <= resources.max_threads() or (o.threads > 1 and o.state):
        cli.fail("--threads must be 1 to %d, and 1 with --state (run_states.py --threads 1)" % resources.max_threads())
    import math
    if not (math.isfinite(o.particle_steps) and o.particle_steps > 0):
        cli.fail("--particle-steps must be a number > 0, not %r" % o.particle_steps)
    if not os.path.isfile(o.specimen):
        cli.fail("no specimen file %s (prepare it first, docs/studies/benchmarks.md)" % o.specimen)
    o.spheres = _bench.sphere_specimen(o.specimen)
    if o.state is not None:
        from trueaniso import triaxial
        if o.state not in {str(i) for i, _, _ in triaxial.table_c1_states()}:
            cli.fail("--state: a state of Table C1 (1-39), not %r" % o.state)
    if o.doc:
        _bench.writable_doc(o.doc)
    for tree in (o.before, o.after):
        if not os.path.isfile(os.path.join(tree, "pyscripts", "trueaniso", "dem.py")):
            cli.fail("%s is not a trueaniso checkout (no pyscripts/trueaniso/dem.py)" % tree)
        if not os.path.isdir(os.path.join(tree, "build", "python")):
            cli.fail("%s is not built: run its ./setup.sh first (no build/python)" % tree)
    o.before, o.after = os.path.abspath(o.before), os.path.abspath(o.after)
    return o


def revision(tree):
    out = subprocess.run(["git", "-C", tree, "describe", "--always", "--dirty"], capture_output=True, text=True)
    return out.stdout.strip() or os.path.basename(tree)


def main():
    o = options()
    names = {"before": revision(o.before), "after": revision(o.after)}
    lines = state_table(o, names) if o.state else stepper_table(o, names)
    lines += ["", "Reproduce: `/usr/bin/python3 bench/bench_builds.py %s`"
              % " ".join(shlex.quote(a if not os.path.exists(a) else os.path.relpath(a)) for a in sys.argv[1:])]
    _bench.publish(o.doc, o.block, lines, heading="## Stepper changes")


if __name__ == "__main__":
    cli.guarded(main)
