"""Benchmark of the static stiffness solve (not a test): wall time against N, rotations free and
blocked, and the moduli against the kinematic (affine) estimate; writes both tables into
docs/studies/statics.md between their markers.

    /usr/bin/python3 bench/bench_statics.py /tmp/statics/s1000.npz /tmp/statics/s4000.npz \\
        /tmp/statics/s16000.npz --doc docs/studies/statics.md

Specimens from: pyscripts/prepare_specimen.py --n N --seed 1 --out /tmp/statics/sN.npz
"""
import os
import resource
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
import numpy as np  # noqa: E402

from trueaniso import cli, engines, specimen_file, statics  # noqa: E402


def options(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("specimens", nargs="+", help="specimen files (.npz)")
    p.add_argument("--doc", default=None, help="markdown file whose benchmark/results blocks are replaced")
    p.add_argument("--repeat", type=int, default=1, help="solves per case; the fastest is reported")
    return cli.parse(p, argv)


def solve(scene, rotations, repeat):
    best = None
    for _ in range(repeat):
        load = os.getloadavg()[0]
        c0 = resource.getrusage(resource.RUSAGE_SELF).ru_utime
        t0 = time.time()
        r = statics.static_stiffness(scene, rotations=rotations)
        r["wall"] = time.time() - t0
        r["cpu"] = resource.getrusage(resource.RUSAGE_SELF).ru_utime - c0
        r["load"] = load
        if best is None or r["wall"] < best["wall"]:
            best = r
    return best


def main(o):
    bench = ["Machine: %s. Command: `%s`. Wall time of `static_stiffness` (held state, assembly and "
             "zero modes, METIS analysis, numeric factorisation, solves) and its CPU time (all threads); "
             "`load` is the 1-minute load average when the solve started (other jobs share the 2 cores)."
             % (_bench.machine(), " ".join(["/usr/bin/python3"] + sys.argv)), "",
             "| N | rotations | DOFs | contacts | nnz(L) | GFlop | analysis s | factor s | solve s | **total s** "
             "| CPU s | load | residual |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    res = ["| N | Zm | rattlers | E_kin (MPa) | E_free / E_kin | E_blocked / E_kin | E_free (MPa) | mean nu_free "
           "| zeta (x, y, z) "
           "| zeta_h, zeta_v | zeta_rotation (x, y, z) |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for path in o.specimens:
        scene, _ = specimen_file.load(path)
        n = scene.num_bodies
        r = {rot: solve(scene, rot, o.repeat) for rot in (True, False)}
        for rot in (False, True):
            x, t = r[rot], r[rot]["time"]
            bench.append("| %d | %s | %d | %d | %.3g M | %.0f | %.2f | %.2f | %.2f | **%.2f** | %.2f | %.1f | %.1e |" % (
                n, "free" if rot else "blocked", x["dofs"], x["contacts"], x["factor_nonzeros"] / 1e6,
                x["factor_flops"] / 1e9, t["analysis"], t["factorization"], t["solve"], x["wall"], x["cpu"],
                x["load"], x["residual"]))
            print(bench[-1], flush=True)
        z = statics.rotation_factor(scene, free=r[True], blocked=r[False])
        E_aff = z["E_kinematic"]  # Eq. (32) = Eq. (37) with zeta = 1, through Eq. (40)
        nu = r[True]["nu"]
        res.append("| %d | %.3f | %d | %s | %s | %s | %s | %.3f | %s | %.3f, %.3f | %s |" % (
            n, engines.coordination(scene)["Zm"], len(r[True]["rattlers"]),
            ", ".join("%.1f" % v for v in E_aff / 1e6),
            ", ".join("%.3f" % v for v in r[True]["E"] / E_aff), ", ".join("%.3f" % v for v in r[False]["E"] / E_aff),
            ", ".join("%.1f" % v for v in r[True]["E"] / 1e6), np.nanmean(nu),
            ", ".join("%.3f" % v for v in z["zeta"]), z["zeta_h"], z["zeta_v"],
            ", ".join("%.3f" % v for v in z["zeta_rotation"])))
        print(res[-1], flush=True)
    if o.doc:
        _bench.replace_block(o.doc, "benchmark", "\n".join(bench))
        _bench.replace_block(o.doc, "results", "\n".join(res))


if __name__ == "__main__":
    cli.guarded(lambda: main(options()))
