"""Speed against error of the ways to get E_i and nu_ij at a held state (issue 5).

    /usr/bin/python3 pyscripts/bench_speed_error.py --specimens A.npz B.npz ... \
        --doc docs/speed-vs-error.md --plot docs/speed-vs-error.png

Reference: the exact static stiffness (engines/statics, rotations free), whose normal block
gives what a probe on z measures. Compared, each timed as wall time of the probe alone:
 - our dynamic probe (StressProbe) over settings of damping, ramp/gain/settling (the
   equilibrium tolerance), stress increment (gamma) and contact detection on or off;
 - the same probe averaged over +dsigma and -dsigma (cancels the secant error);
 - YADE's way (PeriTriaxController, Mindlin law, friction 1e23, relax then +dsigma_z) over its
   stress tolerance, run in yade-double with the same damping;
 - the static solve itself.
Error: |E_z / E_z(static) - 1| and max_j |nu_zj - nu_zj(static)|.
"""
import json
import os
import re
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
sys.path.insert(0, HERE)
from trueaniso import cli  # noqa: E402

OURS = [  # label, damping, ramp, gain, settle, relative tolerance, unbalanced, gamma, detection
    ("fast", 0.7, 50, 0.2, 20, 5e-3, 1e-4, 1e-6, True),
    ("default", 0.4, 300, 0.03, 100, 2e-3, 1e-5, 1e-6, True),
    ("default, no detection", 0.4, 300, 0.03, 100, 2e-3, 1e-5, 1e-6, False),
    ("damping 0.2", 0.2, 300, 0.03, 100, 2e-3, 1e-5, 1e-6, True),
    ("gamma 1e-7", 0.4, 300, 0.03, 100, 2e-3, 1e-5, 1e-7, True),
    ("tight", 0.4, 2000, 0.01, 200, 1e-4, 1e-7, 1e-6, True),
]
YADE = [  # label, relStressTol, maxUnbalanced
    ("YADE tol 1e-4", 1e-4, 1e-4),
    ("YADE tol 1e-5", 1e-5, 1e-5),
    ("YADE tol 3e-6", 3e-6, 1e-6),
]


def yade_worker(o):
    import numpy as np
    from yade import O, PeriTriaxController, utils
    from trueaniso import engines, specimen_file, yade_adapter, yade_bridge
    out = []
    for label, rel, unb in YADE:
        s, _ = specimen_file.load(o.specimen)
        hold = np.diag(engines.stress(s)).copy()
        yade_bridge.yade_scene_from(s, O, damping=0.4)
        yade_adapter.set_friction(O, 1e23)
        ref = np.array([O.cell.hSize[k][k] for k in range(3)])
        t0 = time.perf_counter()
        tr = PeriTriaxController(goal=tuple(-hold), stressMask=7, relStressTol=rel, absStressTol=1e3, globUpdate=1,
                                 maxUnbalanced=unb, maxStrainRate=(10, 10, 10), doneHook="O.pause()")
        O.engines = O.engines[:-1] + [tr] + O.engines[-1:]
        O.run(300000, True)
        s0 = -np.diag(np.array(utils.getStress()))
        e0 = -np.log(np.array([O.cell.hSize[k][k] for k in range(3)]) / ref)
        tr.goal = tuple(-(hold + np.array([0, 0, o.increment])))
        start = O.iter
        O.run(300000, True)
        ds = -np.diag(np.array(utils.getStress())) - s0
        de = -np.log(np.array([O.cell.hSize[k][k] for k in range(3)]) / ref) - e0
        out.append(dict(label=label, E=ds[2] / de[2], nu=[-de[0] / de[2], -de[1] / de[2]],
                        steps=int(O.iter), probe_steps=int(O.iter - start), time=time.perf_counter() - t0))
    print("BENCH " + json.dumps(out), flush=True)


def options():
    p = cli.Parser(description=__doc__.splitlines()[0])
    p.add_argument("--specimens", nargs="+")
    p.add_argument("--specimen")
    p.add_argument("--increment", type=float, default=0.0)
    p.add_argument("--yade-worker", action="store_true")
    p.add_argument("--no-yade", action="store_true")
    p.add_argument("--doc")
    p.add_argument("--plot")
    return cli.parse(p)


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
        E0, nu0 = st["E"][2], [st["nu"][2, 0], st["nu"][2, 1]]
        results.append(dict(n=n, method="static", label="static (CHOLMOD)", E=E0, nu=nu0, time=t_static,
                            err_E=0.0, err_nu=0.0, steps=0))
        print("N=%d static E_z = %.2f MPa (%.2f s)" % (n, E0 / 1e6, t_static), flush=True)
        inc = None
        for label, damping, ramp, gain, settle, tol, unb, gamma, det in OURS:
            kw = dict(damping=damping, ramp_steps=ramp, gain=gain, settle_steps=settle, relative_tolerance=tol,
                      unbalanced=unb, gamma=gamma, skip_detection=not det)
            up = triaxial.probe(s, hold, "z", **kw)
            if label == "default":
                inc = up["d_stress"][2]
            rows = [("ours " + label, up["E"], [up["nu_zx"], up["nu_zy"]], up["wall_time"], up["steps"])]
            if label in ("default", "tight"):
                dn = triaxial.probe(s, hold, "z", sign=-1, **kw)
                rows.append(("ours %s, +/- mean" % label, 0.5 * (up["E"] + dn["E"]),
                             [0.5 * (up["nu_zx"] + dn["nu_zx"]), 0.5 * (up["nu_zy"] + dn["nu_zy"])],
                             up["wall_time"] + dn["wall_time"], up["steps"] + dn["steps"]))
            for lab, E, nu, t, steps in rows:
                r = dict(n=n, method="ours", label=lab, E=E, nu=nu, time=t, steps=steps,
                         err_E=abs(E / E0 - 1), err_nu=max(abs(a - b) for a, b in zip(nu, nu0)))
                results.append(r)
                print("N=%d %-32s err E %.2e  err nu %.2e  %6d steps %.2f s" % (n, lab, r["err_E"], r["err_nu"], steps, t),
                      flush=True)
        if not o.no_yade:
            me = os.path.abspath(os.path.join(HERE, "bench_speed_error.py"))
            cmd = ["yade-double", "-j", "1", "-n", "-x", me, "--yade-worker", "--specimen", path,
                   "--increment", repr(inc)]
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=7200)
            lines = [ln for ln in p.stdout.splitlines() if ln.startswith("BENCH ")]
            if not lines:
                cli.fail("YADE worker failed:\n" + p.stderr[-2000:], 1)
            for y in json.loads(lines[-1][6:]):
                r = dict(n=n, method="yade", label=y["label"], E=y["E"], nu=y["nu"], time=y["time"], steps=y["steps"],
                         err_E=abs(y["E"] / E0 - 1), err_nu=max(abs(a - b) for a, b in zip(y["nu"], nu0)))
                results.append(r)
                print("N=%d %-32s err E %.2e  err nu %.2e  %6d steps %.2f s" % (n, y["label"], r["err_E"], r["err_nu"],
                                                                                y["steps"], y["time"]), flush=True)
    return results


def write(o, results):
    from bench_stepper import machine
    lines = ["Machine: %s; OpenMP threads: ours %s, YADE 1; %s." % (machine(), os.environ.get("OMP_NUM_THREADS", "all"),
                                                                  time.strftime("%Y-%m-%d")), "",
             "| N | method | E_z (MPa) | error E_z | error nu_zj | steps | wall time (s) |", "|---|---|---|---|---|---|---|"]
    for r in results:
        lines.append("| %d | %s | %.2f | %.1e | %.1e | %d | %.2f |" % (r["n"], r["label"], r["E"] / 1e6, r["err_E"],
                                                                       r["err_nu"], r["steps"], r["time"]))
    lines += ["", "Reproduce: `/usr/bin/python3 pyscripts/bench_speed_error.py --specimens %s --doc %s --plot %s`"
              % (" ".join(os.path.relpath(p) for p in o.specimens), o.doc, o.plot)]
    table = "\n".join(lines)
    print(table)
    from trueaniso import atomic
    if o.doc:
        text = open(o.doc).read() if os.path.exists(o.doc) else ""
        block = "<!-- speed:begin -->\n" + table + "\n<!-- speed:end -->"
        text = re.sub(r"<!-- speed:begin -->.*?<!-- speed:end -->", lambda m: block, text, flags=re.S) \
            if "<!-- speed:begin -->" in text else text + "\n" + block + "\n"
        with atomic.atomic_open(o.doc) as f:
            f.write(text)
    if o.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(7, 5))
        marks = dict(static="*", ours="o", yade="s")
        sizes = sorted({r["n"] for r in results})
        colors = dict(zip(sizes, ["tab:blue", "tab:orange", "tab:green", "tab:red"]))
        for r in results:
            ax.scatter(r["time"], max(r["err_E"], 1e-7), marker=marks[r["method"]], color=colors[r["n"]],
                       s=80 if r["method"] == "static" else 30)
        for nn in sizes:
            ax.scatter([], [], color=colors[nn], label="N = %d" % nn)
        for m, k in marks.items():
            ax.scatter([], [], marker=k, color="gray", label=m)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("wall time of one z probe (s)")
        ax.set_ylabel("|E_z / E_z(static) - 1| (floored at 1e-7)")
        ax.set_title("Speed against error, random sphere specimens at 100 kPa")
        ax.legend(fontsize=8)
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


if __name__ == "__main__" or cli.in_yade():
    cli.guarded(main)
