"""CPU time of a chain's steps on a specimen: the stepper as a study or a preparation runs it, with its
time stepper (--time-step), no controller.

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/chain_steps.py --specimen S.npz --steps 300 --time-step per-axis
    TRUEANISO_BUILD=BEFORE/build OMP_NUM_THREADS=1 /usr/bin/python3 bench/chain_steps.py ...   # another build

It steps --warmup steps untimed, then --steps timed, and prints one JSON line: the specimen, the
time step rule, the engines' level, the steps and the CPU milliseconds a step. Unlike
bench_stepper.py, which fixes the time step, the time stepper runs (every tenth step) and so does
what it triggers: the integrator's stability check when the step changes (clumps under
smallest-inertia). Under
`valgrind --tool=callgrind --collect-atstart=no --toggle-collect='trueaniso::Simulation::run*'` it
counts the instructions of the warm-up and the timed steps (docs/studies/benchmarks.md, "Stepper
changes").
"""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402,F401  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz), spheres or clumps")
    p.add_argument("--steps", type=cli.at_least(1), default=300, help="steps timed")
    p.add_argument("--warmup", type=cli.at_least(0), default=10, help="steps before the timed ones")
    p.add_argument("--time-step", choices=cli.TIME_STEP_CHOICES, default=cli.DEFAULT_TIME_STEP,
                   help="the time stepper's rule (docs/time-step.md)")
    o = cli.parse(p)
    if not os.path.isfile(o.specimen):
        cli.fail("--specimen %s: no such file" % o.specimen)
    return o


def main():
    o = options()
    from trueaniso import dem, engines, specimen_file
    scene, _ = specimen_file.load(o.specimen)
    dem.refresh(scene)
    chain = dem.Chain(scene, damping=0.2, rule=o.time_step)
    chain.run(o.warmup)
    t = time.process_time()
    chain.run(o.steps)
    cpu = time.process_time() - t
    print(json.dumps(dict(specimen=os.path.basename(o.specimen), time_step=o.time_step, build=engines.build_arch(),
                          bodies=scene.num_bodies, steps=o.steps, cpu_ms_a_step=round(1000 * cpu / o.steps, 4))))


if __name__ == "__main__":
    main()
