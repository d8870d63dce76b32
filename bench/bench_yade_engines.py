"""Cost per step of our engines in YADE's loop against YADE's own, on the same packing.

 trueaniso: InteractionLoop with our law (Law2_ScGeom_SimplifiedMindlinPhys_Mindlin) and our
            TrueTriaxialServo (the YADE plugin, engines/yade), loading towards state 21 of Table C1;
 YADE:      InteractionLoop with YADE's Law2_ScGeom_MindlinPhys_Mindlin and its PeriTriaxController
            (stressMask 7, its default globUpdate 5) towards the same stresses.
Both: the specimen imported through yade_bridge.yade_scene_from, InsertionSortCollider,
NewtonIntegrator(damping 0.4), the same time step, yade-double -j THREADS, each run in its own
process; the two alternate within each round and their order rotates. The ratio is ours / YADE's
seconds per step in the same round; the goal is <= 1.10.

    /usr/bin/python3 bench/bench_yade_engines.py --specimen S.npz [--steps 2000] [--repeats 5]
        [--threads 1] [--doc docs/yade-benchmarks.md]

Needs the plugin: ./setup.sh with the YADE source (build/yade-prefix).
"""
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
REPO = os.path.dirname(HERE)
sys.path[:0] = [os.path.join(REPO, "pyscripts")]
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402
from trueaniso import cli  # noqa: E402

PREFIX = os.path.join(REPO, "build", "yade-prefix")
STATE = (0.5, 140e3, 100e3)  # state 21: b, sigma_z, p
BLOCK = "yade-engines"


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="sphere specimen file (.npz) to step")
    p.add_argument("--steps", type=int, default=2000, help="timed steps per run (after 100 untimed)")
    p.add_argument("--repeats", type=int, default=5, help="rounds; the medians and ranges over them are reported")
    p.add_argument("--threads", type=int, default=1, help="yade-double -j THREADS for both loops")
    p.add_argument("--doc", default=None, help="Markdown file whose yade-engines table is replaced (docs/yade-benchmarks.md)")
    p.add_argument("--worker", choices=("trueaniso", "yade"), help="(internal) time one loop in this process")
    o = cli.parse(p)
    if o.steps < 1 or o.repeats < 1 or o.threads < 1:
        cli.fail("--steps, --repeats and --threads must be >= 1")
    if not o.worker and o.doc:
        _bench.writable_doc(o.doc)
    return o


def worker(o):
    import numpy as np
    from yade import O
    from trueaniso import dem, engines, specimen_file, yade_bridge
    s, _ = specimen_file.load(o.specimen)
    law = "trueaniso" if o.worker == "trueaniso" else "yade"
    yade_bridge.yade_scene_from(s, O, damping=0.4, law=law)
    d50 = 2.0 * float(np.median(s.radii))
    rate = dem.strain_rate_for_inertial_number(1e-3, d50, s.density, STATE[2])
    b, sz, p = STATE
    if law == "trueaniso":
        from yade.wrapper import TrueTriaxialServo
        ctrl = TrueTriaxialServo(b=b, sigmaZ=sz, meanStress=p, pathRate=2.0, maxStrainRate=rate)
    else:
        from yade.wrapper import PeriTriaxController
        sx, sy, _ = engines.true_triaxial_stresses(b, sz, p)  # Eq. (9), the servo's goal
        ctrl = PeriTriaxController(goal=(-sx, -sy, -sz), stressMask=7, maxStrainRate=(rate, rate, rate),
                                   maxUnbalanced=1e-4, dynCell=False)
    O.engines = O.engines[:-1] + [ctrl] + O.engines[-1:]
    O.run(100, True)
    t = time.perf_counter()
    O.run(o.steps, True)
    seconds = time.perf_counter() - t
    print("BENCH " + json.dumps(dict(code=o.worker, steps=o.steps, seconds=seconds, n=len(O.bodies),
                                     contacts=sum(1 for i in O.interactions if i.isReal))), flush=True)


def run(code, o):
    env = dict(os.environ, YADE_PREFIX=PREFIX, OMP_NUM_THREADS=str(o.threads))
    cmd = ["yade-double", "-j", str(o.threads), "-n", "-x", os.path.abspath(__file__), "--worker", code,
           "--specimen", o.specimen, "--steps", str(o.steps)]
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=7200)
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if out.returncode != 0 or not line:
        sys.exit("error: benchmark worker failed: %s\n%s" % (" ".join(cmd), out.stderr[-2000:]))
    return json.loads(line[-1][6:])


def main():
    o = options()
    if o.worker:
        worker(o)
        return
    if not os.path.exists(os.path.join(PREFIX, "lib", "x86_64-linux-gnu", "yade-double", "libtrueanisoYade.so")):
        sys.exit("error: the YADE plugin is not installed in %s (./setup.sh with TRUEANISO_YADE_SOURCE)" % PREFIX)
    n = _bench.sphere_specimen(o.specimen)
    codes = ["trueaniso", "yade"]
    per_step = {c: [] for c in codes}
    ratios = []
    contacts = None
    load_before = os.getloadavg()[0]
    for rep in range(o.repeats):
        order = codes if rep % 2 == 0 else codes[::-1]
        got = {}
        for c in order:
            r = got[c] = run(c, o)
            per_step[c].append(r["seconds"] / r["steps"])
            contacts = r["contacts"]
            print("round %d %-9s %.3f ms/step" % (rep + 1, c, 1e3 * per_step[c][-1]), flush=True)
        ratios.append(per_step["trueaniso"][-1] / per_step["yade"][-1])
    lines = ["Machine: %s, shared with other jobs (load average %.1f before, %.1f after). Specimen: %s, %d spheres, "
             "%d contacts; %d timed steps after 100, yade-double -j %d, %d rounds, the loops alternating within each, %s."
             % (_bench.machine(), load_before, os.getloadavg()[0], os.path.basename(o.specimen), n, contacts, o.steps,
                o.threads, o.repeats, time.strftime("%Y-%m-%d")), "",
             "| loop | ms per step (median) | range |", "|---|---|---|"]
    for c, name in (("trueaniso", "our law + TrueTriaxialServo"), ("yade", "YADE Mindlin + PeriTriaxController")):
        v = per_step[c]
        lines.append("| %s | %.3f | %.3f-%.3f |" % (name, 1e3 * statistics.median(v), 1e3 * min(v), 1e3 * max(v)))
    lines.append("| ratio ours / YADE (same round) | %.3f | %.3f-%.3f |"
                 % (statistics.median(ratios), min(ratios), max(ratios)))
    lines += ["", "Reproduce: `/usr/bin/python3 bench/bench_yade_engines.py %s`"
              % " ".join(os.path.relpath(a) if os.path.isfile(a) else a for a in sys.argv[1:])]
    _bench.publish(o.doc, BLOCK, lines)


if __name__ == "__main__":  # also under yade-double -x
    main()
