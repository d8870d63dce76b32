"""Cost of clump assemblies: the stepper on clumps against YADE's clumps on the same packing, and
the preparation time of each assembly.

    /usr/bin/python3 bench/bench_clumps.py --specimen specimens/clump1-4000-s1.npz \
        --specimen specimens/clump2-4000-s1.npz [--doc docs/studies/benchmarks.md]

Both codes run the same clump scene (periodic cell, contact history), the same fixed time step,
local damping 0.2, rotations free, the simplified Hertz-Mindlin law between member spheres (ours:
engines; YADE 2023.02a: O.bodies.appendClumped, Law2_ScGeom_MindlinPhys_Mindlin with
InsertionSortCollider, its NewtonIntegrator's aspherical rotation), each run in its own process on
1 and 2 OpenMP threads, interleaved, median of the repeats. Particle-steps per second count clumps
(a clump is one particle); member-steps are in the JSON. Preparation times are read from each
specimen's metadata (wall time of prepare_specimen.py). With --doc the table between
<!-- clumps:begin --> and <!-- clumps:end --> of that file is replaced.
"""
import os
import statistics
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402


def worker_ours(o):
    from trueaniso import specimen_file
    s, _ = specimen_file.load(o.specimen[0])
    _, seconds = _bench.time_ours(s, o.dt, o.steps)
    return dict(code="trueaniso", steps=o.steps, seconds=seconds, n=s.num_bodies,
                members=s.num_members)


def worker_yade(o):
    from yade import O
    from trueaniso import specimen_file, yade_clumps
    s, _ = specimen_file.load(o.specimen[0])
    s.dt = o.dt
    ids, members, _ = yade_clumps.yade_clump_scene_from(s, O, damping=0.2)
    O.dt = o.dt
    O.run(100, True)
    t = time.perf_counter()
    O.run(o.steps, True)
    return dict(code="yade", steps=o.steps, seconds=time.perf_counter() - t, n=len(ids), members=len(members))


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", action="append", required=True, help="clump specimen (repeatable)")
    p.add_argument("--worker", choices=("ours", "yade"), help="internal: run one timed process of this code")
    p.add_argument("--dt", type=float, default=0.0, help="time step (s); 0: half the stiffness bound")
    p.add_argument("--steps", type=int, default=0, help="timed steps (0: 10000 ours, 1000 YADE)")
    p.add_argument("--threads", default="1,2", help="OpenMP thread counts to time, comma separated")
    p.add_argument("--repeats", type=int, default=3, help="interleaved repeats per thread count (median)")
    p.add_argument("--shared", action="store_true", help="note in the table that the machine was shared")
    p.add_argument("--doc", help="Markdown file whose clumps table is replaced")
    return cli.parse(p)


def run_worker(code, threads, o, specimen, dt):
    me = os.path.abspath(os.path.join(HERE, "bench_clumps.py"))
    steps = o.steps or (10000 if code == "ours" else 1000)
    args = ["--specimen", specimen, "--dt", repr(dt), "--steps", str(steps)]
    return _bench.run_worker(me, code, threads, args, timeout=7200)


def main():
    o = options()
    if o.worker:
        _bench.reply(worker_ours(o) if o.worker == "ours" else worker_yade(o))
        return
    from trueaniso import engines, specimen_file
    threads = [int(t) for t in o.threads.split(",")]
    lines = ["Machine: %s%s. Medians of %d interleaved runs, damping 0.2, rotations free, time step half the "
             "stiffness bound, %s." % (_bench.machine(), " (shared with other jobs while measured: rerun on a quiet "
                                       "machine for final figures)" if o.shared else "", o.repeats,
                                       time.strftime("%Y-%m-%d")), "",
             "| specimen | clumps (members) | e | preparation | threads | trueaniso (M particle-steps/s) "
             "| YADE clumps (M particle-steps/s) | ratio |", "|---|---|---|---|---|---|---|---|"]
    for path in o.specimen:
        s, meta = specimen_file.load(path)
        if not s.has_clumps:
            raise cli.InputError("%s has no clumps" % path)
        dt = o.dt or 0.5 * engines.TimeStepper.stiffness_bound(s)
        par = meta.get("parameters", {})
        prep = "%.0f s (%d threads)" % (par.get("wall_time", float("nan")), par.get("threads", 0))
        for th in threads:
            res = dict(ours=[], yade=[])
            for rep in range(o.repeats):
                for code in (("ours", "yade") if rep % 2 == 0 else ("yade", "ours")):
                    r = run_worker(code, th, o, path, dt)
                    res[code].append(r["n"] * r["steps"] / r["seconds"])
                    print("%s threads %d %-5s %.3f M particle-steps/s" % (path, th, code, res[code][-1] / 1e6), flush=True)
            ours, yade = statistics.median(res["ours"]), statistics.median(res["yade"])
            lines.append("| %s (%s) | %d (%d) | %.3f | %s | %d | %.3f | %.4f | %.1f |" % (
                os.path.basename(path), par.get("assembly", "?"), s.num_bodies, s.num_members,
                engines.void_ratio(s), prep, th, ours / 1e6, yade / 1e6, ours / yade))
    lines += ["", "Reproduce: `OMP_NUM_THREADS=1 /usr/bin/python3 bench/bench_clumps.py %s --threads %s "
              "--repeats %d%s --doc docs/studies/benchmarks.md`"
              % (" ".join("--specimen %s" % os.path.relpath(p) for p in o.specimen), o.threads, o.repeats,
                 " --shared" if o.shared else "")]
    _bench.publish(o.doc, "clumps", lines, heading="## Clump assemblies")


if __name__ == "__main__" or cli.in_yade():
    cli.guarded(main)
