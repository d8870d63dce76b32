"""What each stepper change bought, measured on our own stepper alone.

    /usr/bin/python3 bench/bench_stepper_changes.py --specimen S.npz [--small T.npz] [--doc docs/studies/benchmarks.md]

1. Body order. The specimen is tiled K x K x K times (a periodic packing tiled is a packing: 4000
   spheres give 32,000 at K = 2, 108,000 at K = 3) and stepped with its bodies in a random order,
   sorted by rows of a grid of one-diameter cells (what specimen placement gives) and along the
   Morton curve (Scene.order_in_space), one engine thread. Figure: particle-steps per CPU second of the timed
   steps (CPU time, not wall time: the figure the machine's other jobs disturb least).
2. Parallel threshold. The small specimen (--small) stepped on two threads with every loop in a
   team (engines.set_parallel_minimum(0)) and with the default threshold;
   wall time per step, which is what a team's waits cost.
Each variant runs in its own process; repeats interleave the variants and the median is reported.
With --doc the tables between <!-- stepper-changes:begin --> and <!-- stepper-changes:end -->
of that file are replaced.
"""
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402


def worker(o):
    import numpy as np
    from trueaniso import dem, engines, specimen_file
    s, _ = specimen_file.load(o.specimen)
    if o.tile > 1:
        s = _bench.tiled(s, o.tile)
    if o.variant == "random":
        s.reorder_bodies(np.random.default_rng(1).permutation(s.num_bodies))
    elif o.variant == "rows":
        s.reorder_bodies(_bench.grid_rows(s))
    elif o.variant == "morton":
        s.order_in_space()
    elif o.variant == "team-always":
        engines.set_parallel_minimum(0)
    dem.refresh(s)
    s.dt = 2.9e-8  # the 4000-sphere specimen's own step (bench_stepper.py); tiling keeps the sizes
    c = dem.Chain(s, damping=0.2)
    c.timestep.dead = True
    c.run(50)
    w, t = time.perf_counter(), time.process_time()
    c.run(o.steps)
    cpu, wall = time.process_time() - t, time.perf_counter() - w
    print(json.dumps(dict(variant=o.variant, n=s.num_bodies, steps=o.steps, cpu=cpu, wall=wall,
                          threads=engines.threads(), minimum=engines.parallel_minimum())))


def run(o, specimen, variant, tile, steps, threads):
    cmd = [sys.executable, os.path.abspath(__file__), "--worker", "--specimen", specimen, "--variant", variant,
           "--tile", str(tile), "--steps", str(steps)]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    out = subprocess.run(cmd, env=env, capture_output=True, text=True, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="sphere specimen (.npz) to tile for the body-order table")
    p.add_argument("--small", help="small specimen (.npz; a few hundred spheres) for the threshold table")
    p.add_argument("--tiles", default="1,2,3", help="tilings K (K^3 copies), comma separated")
    p.add_argument("--repeats", type=int, default=3, help="runs of each variant, interleaved")
    p.add_argument("--particle-steps", type=float, default=2.4e7, help="particle-steps per timed run")
    p.add_argument("--doc", help="Markdown file whose stepper-changes block is replaced")
    p.add_argument("--worker", action="store_true", help="(internal) time one variant in this process")
    p.add_argument("--variant", default="morton", help="(internal) random, morton, team-always, default")
    p.add_argument("--tile", type=int, default=1, help="(internal)")
    p.add_argument("--steps", type=int, default=1000, help="(internal)")
    o = cli.parse(p)
    o.tiles = _bench.tile_counts(o.tiles)
    for path in [o.specimen] + ([o.small] if o.small else []):
        if not os.path.isfile(path):
            cli.fail("no specimen file %s (prepare it first, docs/studies/benchmarks.md)" % path)
    if o.repeats < 1 or min(o.tiles) < 1 or max(o.tiles) > 4:
        cli.fail("--repeats must be >= 1 and --tiles between 1 and 4 (4^3 x the specimen is already large)")
    return o


def main():
    o = options()
    if o.worker:
        return worker(o)
    lines = ["Machine: %s; %s. Each variant in its own process, %d interleaved runs, medians; time step 2.9e-8 s, "
             "damping 0.2." % (_bench.machine(), time.strftime("%Y-%m-%d"), o.repeats), "",
             "Body order, one engine thread (the specimen %s tiled):" % os.path.basename(o.specimen), "",
             "| spheres | random order (M particle-steps per CPU s) | grid rows (what placement gives) | Morton order | Morton / rows |",
             "|---|---|---|---|---|"]
    orders = ("random", "rows", "morton")
    for k in o.tiles:
        res = {v: [] for v in orders}
        for r in range(o.repeats):
            for v in orders[r % 3:] + orders[:r % 3]:  # the order rotates between repeats
                x = run(o, o.specimen, v, k, max(50, int(o.particle_steps / (4000 * k ** 3))), 1)
                res[v].append(x["n"] * x["steps"] / x["cpu"] / 1e6)
                print("  %s" % json.dumps(x), flush=True)
        m = {v: statistics.median(res[v]) for v in orders}
        lines.append("| %d | %.2f | %.2f | %.2f | %.2f |" % (x["n"], m["random"], m["rows"], m["morton"], m["morton"] / m["rows"]))
    if o.small:
        lines += ["", "Parallel threshold, two engine threads, %s:" % os.path.basename(o.small), "",
                  "| loops in a team | wall time per step (us) |", "|---|---|"]
        res = {"team-always": [], "default": []}
        minimum = None
        for r in range(o.repeats):
            for v in (("team-always", "default") if r % 2 == 0 else ("default", "team-always")):
                x = run(o, o.small, v, 1, 2000, 2)
                res[v].append(x["wall"] / x["steps"] * 1e6)
                if v == "default":
                    minimum = x["minimum"]
                print("  %s" % json.dumps(x), flush=True)
        lines.append("| every loop (parallel minimum 0, before) | %.0f |" % statistics.median(res["team-always"]))
        lines.append("| loops of >= %d items (default) | %.0f |" % (minimum, statistics.median(res["default"])))
    lines += ["", "Reproduce: `/usr/bin/python3 bench/bench_stepper_changes.py %s`"
              % " ".join(a if not os.path.isfile(a) else os.path.relpath(a) for a in sys.argv[1:])]
    _bench.publish(o.doc, "stepper-changes", lines, heading="## Stepper changes")


if __name__ == "__main__":
    cli.guarded(main)
