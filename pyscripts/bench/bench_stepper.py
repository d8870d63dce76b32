"""Speed of the stepper against YADE's on the same consolidated packing (issue 2 benchmark).

    /usr/bin/python3 pyscripts/bench/bench_stepper.py --specimen S.npz [--doc docs/benchmarks.md]

Both codes run the same scene (spheres, periodic cell, contact history), the same fixed time step,
local damping 0.2, the simplified Hertz-Mindlin law (ours: engines; YADE 2023.02a:
Law2_ScGeom_MindlinPhys_Mindlin with InsertionSortCollider), on 1 and 2 OpenMP threads, each run
in its own process (ours under /usr/bin/python3, YADE under yade-double -j N). The figure is
particle-steps per second of the timed steps only (set-up excluded); repeats interleave the two
codes and the median is reported. With --doc the table between the markers
<!-- stepper:begin --> and <!-- stepper:end --> of that file is replaced.
"""
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
sys.path[:0] = [os.path.dirname(HERE), os.path.dirname(os.path.dirname(HERE))]  # trueaniso, analysis
from trueaniso import cli  # noqa: E402


def worker_ours(o):
    from trueaniso import dem, engines, specimen_file
    s, _ = specimen_file.load(o.specimen)
    s.dt = o.dt
    c = dem.Chain(s, damping=0.2)
    c.timestep.dead = True
    c.run(100)
    t = time.perf_counter()
    c.run(o.steps)
    dt = time.perf_counter() - t
    return dict(code="trueaniso", steps=o.steps, seconds=dt, n=s.num_bodies,
                rebuilds=c.detection.rebuilds, pressure=float(engines.stress(s).trace() / 3))


def worker_yade(o):
    from yade import O, utils
    from trueaniso import specimen_file, yade_bridge
    s, _ = specimen_file.load(o.specimen)
    s.dt = o.dt
    yade_bridge.yade_scene_from(s, O, damping=0.2)
    O.dt = o.dt
    O.run(100, True)
    t = time.perf_counter()
    O.run(o.steps, True)
    dt = time.perf_counter() - t
    return dict(code="yade", steps=o.steps, seconds=dt, n=len(O.bodies),
                pressure=float(-utils.getStress().trace() / 3))


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz) to step")
    p.add_argument("--worker", choices=("ours", "yade"), help="(internal) time one stepper in this process")
    p.add_argument("--dt", type=float, default=0.0, help="time step (s); 0: half the stiffness bound")
    p.add_argument("--steps", type=int, default=0, help="timed steps (0: 20000 ours, 2000 YADE)")
    p.add_argument("--threads", default="1,2", help="thread counts to time, comma separated")
    p.add_argument("--repeats", type=int, default=3, help="timed runs per setting (the best is kept)")
    p.add_argument("--doc", help="Markdown file whose stepper table is replaced")
    return cli.parse(p)


def run_worker(code, threads, o, dt):
    me = os.path.abspath(os.path.join(HERE, "bench_stepper.py"))
    steps = o.steps or (20000 if code == "ours" else 2000)
    args = ["--specimen", o.specimen, "--worker", code, "--dt", repr(dt), "--steps", str(steps)]
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    cmd = (["/usr/bin/python3", me] if code == "ours" else ["yade-double", "-j", str(threads), "-n", "-x", me]) + args
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=3600)
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if out.returncode != 0 or not line:
        cli.fail("benchmark worker failed: %s\n%s" % (" ".join(cmd), out.stderr[-2000:]), 1)
    return json.loads(line[-1][6:])


def machine():
    model = "unknown CPU"
    try:
        for ln in open("/proc/cpuinfo"):
            if ln.startswith("model name"):
                model = ln.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return "%s, %d cores, %s" % (model, os.cpu_count(), platform.platform())


def main():
    o = options()
    if o.worker:
        r = worker_ours(o) if o.worker == "ours" else worker_yade(o)
        print("BENCH " + json.dumps(r), flush=True)
        return
    from trueaniso import engines, specimen_file
    s, meta = specimen_file.load(o.specimen)
    dt = o.dt or 0.5 * engines.TimeStepper.stiffness_bound(s)
    threads = [int(t) for t in o.threads.split(",")]
    rows = []
    for th in threads:
        res = dict(ours=[], yade=[])
        for rep in range(o.repeats):
            for code in (("ours", "yade") if rep % 2 == 0 else ("yade", "ours")):
                r = run_worker(code, th, o, dt)
                res[code].append(r["n"] * r["steps"] / r["seconds"])
                print("threads %d %-5s %.3f M particle-steps/s" % (th, code, res[code][-1] / 1e6), flush=True)
        ours, yade = statistics.median(res["ours"]), statistics.median(res["yade"])
        rows.append((th, ours, yade))
    n = s.num_bodies
    lines = ["Machine: %s. Specimen: %d spheres at 100 kPa (e = %.3f, Zm = %.2f), time step %.3g s, "
             "damping 0.2, medians of %d interleaved runs, %s."
             % (machine(), n, meta["summary"]["void_ratio"], meta["summary"]["Zm"], dt, o.repeats,
                time.strftime("%Y-%m-%d")), "",
             "| threads | trueaniso (M particle-steps/s) | YADE Mindlin (M particle-steps/s) | ratio |",
             "|---|---|---|---|"]
    for th, ours, yade in rows:
        lines.append("| %d | %.2f | %.3f | %.1f |" % (th, ours / 1e6, yade / 1e6, ours / yade))
    lines += ["", "Reproduce: `/usr/bin/python3 pyscripts/bench/bench_stepper.py --specimen %s --doc docs/benchmarks.md`"
              % os.path.relpath(o.specimen)]
    table = "\n".join(lines)
    print(table)
    if o.doc:
        from trueaniso import atomic
        text = open(o.doc).read() if os.path.exists(o.doc) else ""
        block = "<!-- stepper:begin -->\n" + table + "\n<!-- stepper:end -->"
        if "<!-- stepper:begin -->" in text:
            text = re.sub(r"<!-- stepper:begin -->.*?<!-- stepper:end -->", lambda m: block, text, flags=re.S)
        else:
            text += "\n" + block + "\n"
        with atomic.atomic_open(o.doc) as f:
            f.write(text)


if __name__ == "__main__":  # also under yade-double -x; an import runs nothing
    cli.guarded(main)
