"""What the fully deformable cell costs: steps per second of the sheared force loop and
detection against the orthorhombic fast path on the same packing, and the steps to reach a state
with six-component control against three (from docs/data/cell-states-*.csv, bench_cell_states.py).

    /usr/bin/python3 bench/bench_cell_cost.py --specimen specimens/spheres-4000-s1.npz --doc docs/studies/benchmarks.md

The sheared scene is the specimen as prepared (its consolidation sheared the cell by ~1e-5, so
hSize has off-diagonal terms and every step takes the sheared path); the orthorhombic scene is the
same packing with those terms set to zero (the diagonal fast path). Both run the same fixed time
step, damping 0.2, rotations free, with the velocity gradient zero, on the engine thread count
given (1 by default), timed in turns (best, median and slowest of --repeats). With --doc the table between
<!-- cell-cost:begin --> and <!-- cell-cost:end --> of that file is replaced.
"""
import csv
import glob
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

DATA = os.path.join(os.path.dirname(HERE), "docs", "data")


def timings(o):
    import numpy as np
    from trueaniso import dem, engines, specimen_file
    engines.set_threads(o.threads)
    sheared, _ = specimen_file.load(o.specimen)
    if sheared.orthorhombic:
        raise cli.InputError("specimen %s has a diagonal cell: nothing takes the sheared path" % o.specimen)
    ortho = sheared.copy()
    ortho.cell = np.diag(np.diag(sheared.cell))
    ortho.velocity_gradient = np.zeros((3, 3))
    sheared.velocity_gradient = np.zeros((3, 3))
    assert ortho.orthorhombic and not sheared.orthorhombic
    dt = 0.5 * engines.TimeStepper.stiffness_bound(sheared)
    chains = {}
    for name, s in (("sheared", sheared), ("orthorhombic", ortho)):
        s.dt = dt
        c = dem.Chain(s, damping=0.2)
        c.timestep.dead = True
        c.run(200)  # first detection and allocation outside the timing
        chains[name] = c
    rate = {k: [] for k in chains}
    for rep in range(o.repeats):
        for name in (("sheared", "orthorhombic") if rep % 2 == 0 else ("orthorhombic", "sheared")):
            t = time.perf_counter()
            chains[name].run(o.steps)
            rate[name].append(o.steps / (time.perf_counter() - t))
            print("%-12s %.0f steps/s" % (name, rate[name][-1]), flush=True)
    return sheared.num_bodies, dt, rate, off_diagonal(sheared)


def off_diagonal(s):
    import numpy as np
    h = np.asarray(s.cell)
    return float(np.abs(h - np.diag(np.diag(h))).max() / np.diag(h).mean())


def steps_table():
    """Median and largest steps per state, six against three controlled components, per N."""
    rows = {}
    for path in glob.glob(os.path.join(DATA, "cell-states-*.csv")):
        with open(path) as f:
            r = list(csv.DictReader(f))
        if r:
            rows[(int(r[0]["n"]), r[0]["control"])] = r
    lines = ["| N | control | median steps per state | largest | total steps (40 states) | largest off-diagonal left (Pa) |",
             "|---|---|---|---|---|---|"]
    for (n, control), r in sorted(rows.items()):
        steps = [int(x["steps"]) for x in r]
        lines.append("| %d | %s | %d | %d | %d | %.0f |" % (n, control, statistics.median(steps), max(steps), sum(steps),
                                                           max(float(x["tau_max"]) for x in r)))
    return lines if len(lines) > 2 else []


def main(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz) prepared with the full cell")
    p.add_argument("--steps", type=cli.count, default=3000, help="timed steps per run")
    p.add_argument("--repeats", type=cli.count, default=3, help="timed runs of each scene (the best is kept)")
    p.add_argument("--threads", type=cli.count, default=1, help="engine threads")
    p.add_argument("--doc", help="markdown file whose cell-cost block is replaced")
    o = cli.parse(p, argv)
    if not os.path.isfile(o.specimen):
        raise cli.InputError("specimen file not found: %s" % o.specimen)
    if o.steps < 1 or o.repeats < 1 or o.threads < 1:
        raise cli.InputError("--steps, --repeats and --threads must be >= 1")
    if o.doc and not os.path.isfile(o.doc):
        raise cli.InputError("--doc %s: no such file" % o.doc)
    n, dt, rate, shear = timings(o)
    lines = ["Machine: %s; %d engine thread(s); %s. Specimen %s: %d spheres, cell shear %.1e (largest off-diagonal "
             "of hSize over its diagonal), time step %.3g s, damping 0.2, %d runs of %d steps each, interleaved. "
             "The machine is shared: the spread of the runs says how far a difference can be read."
             % (_bench.machine(), o.threads, time.strftime("%Y-%m-%d"), os.path.basename(o.specimen), n, shear, dt,
                o.repeats, o.steps), "",
             "| cell | best steps/s | median | slowest | best M particle-steps/s | best relative to orthorhombic |",
             "|---|---|---|---|---|---|"]
    best = {k: max(v) for k, v in rate.items()}
    for name in ("orthorhombic", "sheared"):
        lines.append("| %s | %.0f | %.0f | %.0f | %.2f | %.3f |"
                     % (name, best[name], statistics.median(rate[name]), min(rate[name]), best[name] * n / 1e6,
                        best[name] / best["orthorhombic"]))
    steps = steps_table()
    if steps:
        lines += ["", "Steps to reach a state (bench_cell_states.py, the isotropic state and the 39 of Table C1, "
                      "1 thread): six controlled components (shear stresses to zero) against three (shear strains "
                      "held, the orthorhombic servo).", ""] + steps
    lines += ["", "Reproduce: `/usr/bin/python3 bench/bench_cell_cost.py --specimen %s --doc docs/studies/benchmarks.md`"
              % os.path.relpath(o.specimen)]
    _bench.publish(o.doc, "cell-cost", lines)


if __name__ == "__main__":
    cli.guarded(main)
