"""Inherent anisotropy of clump specimens at their isotropic state, beside the paper's numbers:
void ratio, Zm, the fabric R and H (Eqs. 15-16) and the clumps' long-axis fabric, and
E_x, E_y, E_z with particle rotations restrained and free, from the exact static solve
(docs/statics.md) and from the dynamic stress probes (Eq. 10, gamma = 1e-6, the study's settings).

    /usr/bin/python3 bench/anisotropy_clumps.py --specimen specimens/clump1-4000-s1.npz \
        --specimen specimens/clump2-4000-s1.npz [--doc docs/studies/specimens.md] [--json out.json]

With --doc the table between <!-- anisotropy:begin --> and <!-- anisotropy:end --> is replaced.
"""
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
import numpy as np  # noqa: E402

from trueaniso import cli  # noqa: E402

# Table B1 (rotations restrained) and section 2.1 of the paper.
PAPER = {"clump1": dict(e=0.445, E=(306.0, 306.0, 581.5), R="R_zz < R_xx ~ R_yy", H="H_zz > H_xx ~ H_yy"),
         "clump2": dict(e=0.636, E=(405.1, 405.1, 346.2), R="R_zz > R_xx", H="H_zz < H_xx")}


def measure(path, probes=True):
    from trueaniso import clump_shapes, fabric, specimen, specimen_file, statics, triaxial
    s, meta = specimen_file.load(path)
    st = specimen.state(s)
    f = fabric.fabric(s)
    R, H = np.diag(np.asarray(f["R"])), np.diag(np.asarray(f["H"]))
    out = dict(path=path, assembly=meta.get("parameters", {}).get("assembly", "?"), n=s.num_bodies,
               e=st["void_ratio"], Zm=st["Zm"], R=R.tolist(), H_over_trace=(H / H.sum()).tolist(),
               long_axis=np.diag(clump_shapes.long_axis_fabric(s)).tolist(),
               prep_time=meta.get("parameters", {}).get("wall_time"), threads=meta.get("parameters", {}).get("threads"))
    hold = triaxial.stress_as_held(s)  # the specimen as it is, its shear stresses included
    solved = {}
    for rot in ("restrained", "free"):
        t = time.time()
        r = solved[rot] = statics.static_stiffness(s, rotations=(rot == "free"))
        out["static_" + rot] = [float(x) for x in r["E"]]
        out["static_time_" + rot] = time.time() - t
        if probes:
            E = []
            for axis in range(3):
                p = triaxial.probe(s, hold, axis, restrain_rotations=(rot == "restrained"))
                E.append(p["E"])
                print("  %s probe %s: E = %.1f MPa (%d steps, %.0f s)" % (rot, "xyz"[axis], p["E"] / 1e6, p["steps"],
                                                                     p["wall_time"]), flush=True)
            out["probe_" + rot] = E
    # The magnitude zeta (docs/statics.md): NaN where no zeta in its range reproduces E_free.
    z = statics.rotation_factor(s, free=solved["free"], blocked=solved["restrained"])
    out.update(zeta_h=float(z["zeta_h"]), zeta_v=float(z["zeta_v"]), rattlers=len(solved["free"]["rattlers"]),
               E_kinematic=[float(x) for x in z["E_kinematic"]])
    return out


def table(rows):
    lines = ["| assembly | source | e | Zm | <u_z^2> | R_xx, R_yy, R_zz | H_ii / tr H | rotations | E_x, E_y, E_z (MPa) "
             "| E_z/E_x | E_z/E_y |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        p = PAPER.get(r["assembly"])
        if p:
            lines.append("| %s | paper (Table B1) | %.3f | | | %s | %s | restrained | %.1f, %.1f, %.1f | %.3f | %.3f |" % (
                r["assembly"], p["e"], p["R"], p["H"], *p["E"], p["E"][2] / p["E"][0], p["E"][2] / p["E"][1]))
        for rot in ("restrained", "free"):
            for src in ("probe", "static"):
                key = "%s_%s" % (src, rot)
                if key not in r:
                    continue
                E = np.array(r[key]) / 1e6
                lines.append("| %s | ours, %d clumps, %s | %.3f | %.2f | %.2f | %s | %s | %s | %.1f, %.1f, %.1f | %.3f | %.3f |" % (
                    r["assembly"], r["n"], "dynamic probe" if src == "probe" else "static solve", r["e"], r["Zm"],
                    r["long_axis"][2],
                    ", ".join("%.3f" % x for x in r["R"]), ", ".join("%.3f" % x for x in r["H_over_trace"]), rot,
                    *E, E[2] / E[0], E[2] / E[1]))
    return "\n".join(lines)


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", action="append", required=True, help="clump specimen file (repeatable)")
    p.add_argument("--no-probes", action="store_true", help="static solves only")
    p.add_argument("--doc", help="Markdown file whose anisotropy table is replaced")
    p.add_argument("--json", help="write every measured number here")
    o = cli.parse(p)
    rows = []
    for path in o.specimen:
        print("measuring %s" % path, flush=True)
        rows.append(measure(path, probes=not o.no_probes))
    text = table(rows)
    print(text)
    if o.json:
        from trueaniso import atomic
        atomic.write_json(o.json, rows)
    if o.doc:
        cmd = "/usr/bin/python3 bench/anisotropy_clumps.py %s --doc %s" % (
            " ".join("--specimen %s" % os.path.relpath(s) for s in o.specimen), os.path.relpath(o.doc))
        _bench.replace_block(o.doc, "anisotropy", "%s\n\nReproduce: `%s` (%s)." % (text, cmd, time.strftime("%Y-%m-%d")))


if __name__ == "__main__" or cli.in_yade():
    cli.guarded(main)
