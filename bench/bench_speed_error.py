"""Speed against error of the ways to get E_i and nu_ij at a held state.

    /usr/bin/python3 bench/bench_speed_error.py --specimens A.npz B.npz ... \
        --doc docs/studies/speed-vs-error.md --plot docs/figures/speed-vs-error.png

Reference: the exact static stiffness (engines/statics, rotations free), whose normal block
gives what probes on x, y and z measure. Compared, each timed as the wall time of the three
probes (x, y, z) together:
 - our dynamic probe (StressProbe) over settings of damping, ramp/gain/settling (the
   equilibrium tolerance), stress increment (gamma) and contact detection on or off;
 - the same probes averaged over +dsigma and -dsigma (cancels the secant error);
 - YADE's way (PeriTriaxController, Mindlin law, friction 1e23, relax then +dsigma_i) over its
   stress tolerance, damping, stress increment and collider on or off, in yade-double;
 - the static solve itself (all of C at once).
Error: max_i |E_i / E_i(static) - 1| and max_ij |nu_ij - nu_ij(static)| over the three probes.
"""
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

OURS = [  # label, damping, ramp, gain, settle, relative tolerance, unbalanced, gamma, detection
    ("fast", 0.7, 50, 0.2, 20, 5e-3, 1e-4, 1e-6, True),
    ("default", 0.4, 300, 0.03, 100, 2e-3, 1e-5, 1e-6, True),
    ("default, no detection", 0.4, 300, 0.03, 100, 2e-3, 1e-5, 1e-6, False),
    ("damping 0.2", 0.2, 300, 0.03, 100, 2e-3, 1e-5, 1e-6, True),
    ("gamma 1e-7", 0.4, 300, 0.03, 100, 2e-3, 1e-5, 1e-7, True),
    ("tight", 0.4, 2000, 0.01, 200, 1e-4, 1e-7, 1e-6, True),
]
YADE = [  # label, relStressTol, maxUnbalanced, damping, increment factor, collider
    ("YADE tol 1e-4", 1e-4, 1e-4, 0.4, 1.0, True),
    ("YADE tol 1e-5", 1e-5, 1e-5, 0.4, 1.0, True),
    ("YADE tol 3e-6", 3e-6, 1e-6, 0.4, 1.0, True),
    ("YADE tol 1e-5, damping 0.2", 1e-5, 1e-5, 0.2, 1.0, True),
    ("YADE tol 1e-5, increment / 2", 1e-5, 1e-5, 0.4, 0.5, True),
    ("YADE tol 1e-5, collider off", 1e-5, 1e-5, 0.4, 1.0, False),
]
AXES = "xyz"


def yade_probe(o, axis, rel, unb, damping, factor, collider, increments):
    """One probe the YADE way on `axis`, from a fresh import of the held state."""
    import numpy as np
    from yade import O, PeriTriaxController, utils
    from trueaniso import engines, specimen_file, yade_adapter, yade_bridge
    s, _ = specimen_file.load(o.specimen)
    hold = np.diag(engines.stress(s)).copy()
    yade_bridge.yade_scene_from(s, O, damping=damping)
    yade_adapter.set_friction(O, 1e23)
    if not collider:  # nothing slides, the network cannot change: YADE's collider can rest
        O.engines[1].dead = True
    ref = np.array([O.cell.hSize[k][k] for k in range(3)])
    t0 = time.perf_counter()
    tr = PeriTriaxController(goal=tuple(-hold), stressMask=7, relStressTol=rel, absStressTol=1e3, globUpdate=1,
                             maxUnbalanced=unb, maxStrainRate=(10, 10, 10), doneHook="O.pause()")
    O.engines = O.engines[:-1] + [tr] + O.engines[-1:]
    O.run(300000, True)
    s0 = -np.diag(np.array(utils.getStress()))
    e0 = -np.log(np.array([O.cell.hSize[k][k] for k in range(3)]) / ref)
    goal = hold.copy()
    goal[axis] += factor * increments[axis]
    tr.goal = tuple(-goal)
    O.run(300000, True)
    ds = -np.diag(np.array(utils.getStress())) - s0
    de = -np.log(np.array([O.cell.hSize[k][k] for k in range(3)]) / ref) - e0
    return dict(E=ds[axis] / de[axis], nu={j: -de[j] / de[axis] for j in range(3) if j != axis},
                steps=int(O.iter), time=time.perf_counter() - t0)


def yade_worker(o):
    increments = [float(v) for v in o.increments.split(",")]
    out = []
    for label, rel, unb, damping, factor, collider in YADE:
        probes = [yade_probe(o, a, rel, unb, damping, factor, collider, increments) for a in range(3)]
        out.append(dict(label=label, E=[p["E"] for p in probes],
                        nu=[[p["nu"].get(j, 0.0) for j in range(3)] for p in probes],
                        steps=sum(p["steps"] for p in probes), time=sum(p["time"] for p in probes)))
    print("BENCH " + json.dumps(out), flush=True)


def errors(E, nu, E0, nu0):
    """max_i |E_i/E_i0 - 1| and max_{i != j} |nu_ij - nu_ij0| (nu as 3x3, row = loaded axis)."""
    err_E = max(abs(E[i] / E0[i] - 1) for i in range(3))
    err_nu = max(abs(nu[i][j] - nu0[i][j]) for i in range(3) for j in range(3) if i != j)
    return err_E, err_nu


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimens", nargs="+", help="specimen files (.npz) to scan")
    p.add_argument("--specimen", help="(worker) the one specimen a YADE worker probes")
    p.add_argument("--increments", default="0,0,0", help="(worker) stress increments on x,y,z in Pa")
    p.add_argument("--yade-worker", action="store_true", help="(internal) run as the YADE worker")
    p.add_argument("--no-yade", action="store_true", help="leave out the YADE probes")
    p.add_argument("--doc", help="Markdown file whose speed-error table is replaced")
    p.add_argument("--plot", help="PNG file for the speed-against-error figure")
    return cli.parse(p)


def ours_probes(triaxial, s, hold, kw, sign=1):
    """x, y and z probes with one setting: E (3), nu (3x3), steps and time summed, increments."""
    E, nu, steps, t, inc = [], [], 0, 0.0, []
    for a in range(3):
        r = triaxial.probe(s, hold, a, sign=sign, **kw)
        E.append(r["E"])
        nu.append([r.get("nu_%s%s" % (AXES[a], AXES[j]), 0.0) for j in range(3)])
        steps += r["steps"]
        t += r["wall_time"]
        inc.append(abs(r["d_stress"][a]))
    return E, nu, steps, t, inc


def run(o):
    import numpy as np
    from trueaniso import engines, specimen_file, statics, triaxial
    results = []
    for path in o.specimens:
        s, meta = specimen_file.load(path)
        n = s.num_bodies
        hold = np.diag(engines.stress(s)).copy()
        t0 = time.perf_counter()
        st = statics.static_stiffness(s)
        t_static = time.perf_counter() - t0
        E0 = list(st["E"])
        nu0 = [[float(st["nu"][i, j]) for j in range(3)] for i in range(3)]
        results.append(dict(n=n, method="static", label="static (CHOLMOD)", E=E0, nu=nu0, time=t_static,
                            err_E=0.0, err_nu=0.0, steps=0))
        print("N=%d static E = %s MPa (%.2f s)" % (n, np.round(np.array(E0) / 1e6, 2), t_static), flush=True)
        inc = None
        for label, damping, ramp, gain, settle, tol, unb, gamma, det in OURS:
            kw = dict(damping=damping, ramp_steps=ramp, gain=gain, settle_steps=settle, relative_tolerance=tol,
                      unbalanced=unb, gamma=gamma, skip_detection=not det)
            E, nu, steps, t, incs = ours_probes(triaxial, s, hold, kw)
            if label == "default":
                inc = incs
            rows = [("ours " + label, E, nu, t, steps)]
            if label in ("default", "tight"):
                Ed, nud, stepsd, td, _ = ours_probes(triaxial, s, hold, kw, sign=-1)
                rows.append(("ours %s, +/- mean" % label, [0.5 * (a + b) for a, b in zip(E, Ed)],
                             [[0.5 * (a + b) for a, b in zip(r1, r2)] for r1, r2 in zip(nu, nud)],
                             t + td, steps + stepsd))
            for lab, E_, nu_, t_, steps_ in rows:
                err_E, err_nu = errors(E_, nu_, E0, nu0)
                results.append(dict(n=n, method="ours", label=lab, E=E_, nu=nu_, time=t_, steps=steps_,
                                    err_E=err_E, err_nu=err_nu))
                print("N=%d %-32s err E %.2e  err nu %.2e  %6d steps %.2f s" % (n, lab, err_E, err_nu, steps_, t_),
                      flush=True)
        if not o.no_yade:
            me = os.path.abspath(os.path.join(HERE, "bench_speed_error.py"))
            cmd = ["yade-double", "-j", "1", "-n", "-x", me, "--yade-worker", "--specimen", path,
                   "--increments", ",".join(repr(v) for v in inc)]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=7200)
            lines = [ln for ln in p.stdout.splitlines() if ln.startswith("BENCH ")]
            if not lines:
                cli.fail("YADE worker failed:\n" + p.stderr[-2000:], 1)
            for y in json.loads(lines[-1][6:]):
                err_E, err_nu = errors(y["E"], y["nu"], E0, nu0)
                results.append(dict(n=n, method="yade", label=y["label"], E=y["E"], nu=y["nu"], time=y["time"],
                                    steps=y["steps"], err_E=err_E, err_nu=err_nu))
                print("N=%d %-32s err E %.2e  err nu %.2e  %6d steps %.2f s" % (n, y["label"], err_E, err_nu,
                                                                                y["steps"], y["time"]), flush=True)
    return results


def write(o, results):
    lines = ["Machine: %s; OpenMP threads: ours %s, YADE 1; %s." % (_bench.machine(), os.environ.get("OMP_NUM_THREADS", "all"),
                                                                  time.strftime("%Y-%m-%d")), "",
             "| N | method | E_x, E_y, E_z (MPa) | max error E_i | max error nu_ij | steps (x+y+z) | wall time x+y+z (s) |",
             "|---|---|---|---|---|---|---|"]
    for r in results:
        lines.append("| %d | %s | %s | %.1e | %.1e | %d | %.2f |" % (
            r["n"], r["label"], ", ".join("%.2f" % (e / 1e6) for e in r["E"]), r["err_E"], r["err_nu"], r["steps"],
            r["time"]))
    lines += ["", "Reproduce: `/usr/bin/python3 bench/bench_speed_error.py --specimens %s --doc %s --plot %s`"
              % (" ".join(os.path.relpath(p) for p in o.specimens), o.doc, o.plot)]
    _bench.publish(o.doc, "speed", lines)
    if o.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, axes = plt.subplots(1, 2, figsize=(12, 5))
        marks = dict(static="*", ours="o", yade="s")
        sizes = sorted({r["n"] for r in results})
        colors = dict(zip(sizes, ["tab:blue", "tab:orange", "tab:green", "tab:red"]))
        for ax, key, name in ((axes[0], "err_E", "max_i |E_i / E_i(static) - 1|"),
                              (axes[1], "err_nu", "max_ij |nu_ij - nu_ij(static)|")):
            for r in results:
                ax.scatter(r["time"], max(r[key], 1e-7), marker=marks[r["method"]], color=colors[r["n"]],
                           s=80 if r["method"] == "static" else 30)
            for nn in sizes:
                ax.scatter([], [], color=colors[nn], label="N = %d" % nn)
            for m, k in marks.items():
                ax.scatter([], [], marker=k, color="gray", label=m)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xlabel("wall time of the x, y and z probes (s)")
            ax.set_ylabel(name + " (floored at 1e-7)")
            ax.legend(fontsize=8)
        fig.suptitle("Speed against error, random sphere specimens at 100 kPa")
        fig.tight_layout()
        tmp = o.plot + ".tmp.png"
        fig.savefig(tmp, dpi=120)
        os.replace(tmp, o.plot)


def main():
    o = options()
    if o.yade_worker:
        yade_worker(o)
        return
    if not o.specimens:
        raise cli.InputError("give --specimens")
    write(o, run(o))


if __name__ == "__main__":  # also under yade-double -x; an import runs nothing
    cli.guarded(main)
