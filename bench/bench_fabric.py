"""Benchmark of the fabric measures: the cost of recording them during a run, and the C++
computation against the same computation in Python over YADE's O.interactions.

    yade-double -n -x bench/bench_fabric.py --specimen specimens/spheres-4000.npz --out bench_fabric.json

OpenMP threads: set OMP_NUM_THREADS in the environment (default: all cores).
(prepare the specimen with pyscripts/prepare_specimen.py --n 4000 --seed 1). Results are printed
as a Markdown table and written as JSON; docs/studies/fabric-cost.md quotes them. Timings are minima over
repeats, runs with and without the recorder interleaved, so that a busy machine biases neither.
"""
import json
import os
import platform
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)
from trueaniso import atomic, cli, dem, engines, fabric, specimen_file, yade_bridge  # noqa: E402


def options(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz) of a consolidated packing")
    p.add_argument("--steps", type=int, default=3000, help="steps per timed run")
    p.add_argument("--every", type=int, default=100, help="recording interval (steps)")
    p.add_argument("--repeats", type=int, default=8, help="timed runs of each kind")
    p.add_argument("--calls", type=int, default=200, help="fabric() calls timed for the per-call cost")
    p.add_argument("--python-repeats", type=int, default=3, help="timed runs of the Python version")
    p.add_argument("--out", required=True, help="JSON output")
    o = cli.parse(p, argv)
    if o.steps < o.every or o.every < 1 or o.repeats < 1 or o.calls < 1 or o.python_repeats < 1:
        raise cli.InputError("need --steps >= --every >= 1 and positive repeat counts")
    return o


def timed(f, *a):
    t0 = time.perf_counter()
    f(*a)
    return time.perf_counter() - t0


def evaluated(scene):
    """Contacts of a force evaluation at the current positions, without moving anything."""
    sim = engines.Simulation(scene)
    sim.add(engines.ContactDetection())
    sim.add(engines.ContactForces())
    sim.run(1)
    return scene


def recording_cost(base, o):
    """Runs without recorder, with one recording every o.every steps, and with a recorder that
    never records (same engine list, the noise floor), in alternating order."""
    times = dict(plain=[], recorded=[], idle=[])
    kinds = list(times)
    for rep in range(o.repeats):
        for kind in (kinds if rep % 2 == 0 else kinds[::-1]):
            s = base.copy()
            every = dict(plain=None, recorded=o.every, idle=10 * (o.steps + o.every))[kind]
            chain = dem.Chain(s, controllers=[] if every is None else [fabric.recorder(every)])
            chain.run(o.every)  # warm-up: list built, buffers allocated
            times[kind].append(timed(chain.run, o.steps))
    s = evaluated(base.copy())
    per_call = min(timed(engines.fabric, s) for _ in range(o.calls))
    plain = min(times["plain"])
    step = plain / o.steps
    return dict(step_time=step, plain=plain, recorded=min(times["recorded"]), idle=min(times["idle"]),
                measured_overhead=min(times["recorded"]) / plain - 1.0,
                noise_floor=min(times["idle"]) / plain - 1.0,
                spread=(sorted(times["plain"])[len(times["plain"]) // 2] / plain - 1.0),
                fabric_call=per_call, predicted_overhead=per_call / (o.every * step),
                contacts=int(engines.fabric(s)["Nc"]), all_times=times)


def python_speedup(base, o):
    from yade import O
    yade_bridge.yade_scene_from(base, O)  # the same packing in O, interactions created by YADE
    t_python = min(timed(fabric.fabric_from_interactions, O) for _ in range(o.python_repeats))
    ref = fabric.fabric_from_interactions(O)
    imported = []
    for _ in range(o.python_repeats):
        t0 = time.perf_counter()
        s, _ids = yade_bridge.scene_from_yade(O)
        ours = engines.fabric(evaluated(s))
        imported.append(time.perf_counter() - t0)
    t_cpp = min(timed(engines.fabric, s) for _ in range(o.calls))
    agree = max(float(abs(ours[k] - ref[k]).max() / abs(ref[k]).max()) for k in ("R", "H", "B", "M"))
    return dict(python=t_python, cpp=t_cpp, speedup=t_python / t_cpp, cpp_with_import=min(imported),
                speedup_with_import=t_python / min(imported), interactions=int(ref["Nc"]),
                max_relative_difference=agree)


def main(argv=None):
    o = options(argv)
    base, meta = specimen_file.load(o.specimen)
    threads = int(os.environ.get("OMP_NUM_THREADS", os.cpu_count() or 1))
    cost = recording_cost(base, o)
    speed = python_speedup(base, o)
    result = dict(specimen=o.specimen, n=base.num_bodies, steps=o.steps, every=o.every, repeats=o.repeats,
                  threads=threads, machine=platform.platform(), cpus=os.cpu_count(),
                  recording=cost, python_vs_cpp=speed)
    with atomic.atomic_open(o.out, "w") as f:
        json.dump(result, f, indent=1)
    print("| quantity | value |\n|---|---|")
    print("| particles / contacts | %d / %d |" % (base.num_bodies, cost["contacts"]))
    print("| step time (no recorder) | %.3f ms |" % (1e3 * cost["step_time"]))
    print("| fabric() call | %.3f ms |" % (1e3 * cost["fabric_call"]))
    print("| recording every %d steps, measured (min of %d runs) | %+.2f %% |"
          % (o.every, o.repeats, 100 * cost["measured_overhead"]))
    print("| recorder that never records (noise floor) | %+.2f %% |" % (100 * cost["noise_floor"]))
    print("| median / min of the plain runs | %+.2f %% |" % (100 * cost["spread"]))
    print("| recording every %d steps, call / (every x step) | %.2f %% |" % (o.every, 100 * cost["predicted_overhead"]))
    print("| Python over O.interactions (%d) | %.1f ms |" % (speed["interactions"], 1e3 * speed["python"]))
    print("| C++ fabric() | %.3f ms (x %.0f) |" % (1e3 * speed["cpp"], speed["speedup"]))
    print("| bridge import + 1 force step + fabric() | %.1f ms (x %.1f) |"
          % (1e3 * speed["cpp_with_import"], speed["speedup_with_import"]))
    print("| max relative difference C++ vs Python | %.1e |" % speed["max_relative_difference"])


if __name__ == "__main__":  # also under yade-double -x; an import runs nothing
    cli.guarded(main)
