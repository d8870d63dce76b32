"""The default study, run by ./main.sh:

    yade-double -n -x pyscripts/run_study.py [--n 1000] [--seed 1] [--ids 1,5,9,13,17,21,25,35,39]
                                             [--out results/default]

1. a sphere specimen consolidated isotropically to 100 kPa (docs/specimens.md);
2. a selection of the paper's Table C1 states, each reached by the b-controlled servo and probed
   on z, x and y (docs/triaxial.md), with the micro-structure of each state (docs/fabric.md);
3. the exact static stiffness at the isotropic state and the rotation factor zeta it implies
   (docs/statics.md);
4. figures (E_i against sigma_i, K and G against Zm) and a summary.
Every stage writes its results atomically and is skipped when its output is already there, so an
interrupted study resumes where it stopped.
"""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
sys.path[:0] = [HERE, os.path.dirname(HERE)]  # the trueaniso package and the analysis package
from analysis import figures  # noqa: E402
from trueaniso import atomic, clump_specimen, cli, specimen, specimen_file, study  # noqa: E402

DEFAULT_IDS = "1,5,9,13,17,21,25,35,39"


def options():
    p = cli.Parser(description="trueaniso default study")
    p.add_argument("--assembly", default="sphere", help="sphere (default), clump1 or clump2 (docs/specimens.md)")
    p.add_argument("--n", type=int, default=1000, help="particles in the specimen")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--ids", default=DEFAULT_IDS, help="Table C1 states to run")
    p.add_argument("--out", default="results/default", help="results directory")
    return cli.parse(p)


def main():
    o = options()
    if o.n < 100:
        raise cli.InputError("--n must be >= 100 for a study specimen")
    o.assembly = {"spheres": "sphere"}.get(o.assembly, o.assembly)
    if o.assembly not in ("sphere", "clump1", "clump2"):
        raise cli.InputError("unknown assembly %r (available: sphere, clump1, clump2)" % o.assembly)
    if o.assembly != "sphere":
        try:
            clump_specimen.check_count(o.assembly, o.n)
        except ValueError as exc:
            raise cli.InputError(str(exc)) from None
    try:
        ids = [int(v) for v in o.ids.split(",") if v.strip()]
        states = study.table_states(ids)
    except ValueError as exc:
        raise cli.InputError("--ids: %s" % exc) from None
    os.makedirs(o.out, exist_ok=True)
    t0 = time.time()
    path = os.path.join(o.out, "specimen.npz")
    if os.path.exists(path):
        try:
            scene, meta = specimen_file.load(path)
            print("specimen: kept %s" % path)
            kept = meta.get("parameters", {}).get("assembly", "sphere")
            if kept != o.assembly:
                raise cli.InputError("%s holds a %s specimen, not %s: use another --out" % (path, kept, o.assembly))
        except specimen_file.SpecimenFileError as exc:
            raise cli.InputError("%s is not usable (%s); remove it to prepare it again" % (path, exc))
    else:
        print("specimen: preparing %d %s (seed %d) ..." % (o.n, o.assembly, o.seed), flush=True)
        if o.assembly == "sphere":
            scene, log = specimen.prepare_spheres(o.n, seed=o.seed)
        else:
            scene, log = clump_specimen.prepare_clumps(o.assembly, o.n, seed=o.seed)
        specimen_file.save(path, scene, seed=o.seed, parameters=log, summary=specimen.state(scene))
        print("specimen: saved %s (%.1f s)" % (path, time.time() - t0))
    st = specimen.state(scene)
    atomic.write_json(os.path.join(o.out, "specimen_state.json"), st)
    print("specimen: e = %.4f, Zm = %.3f, sigma = (%.2f, %.2f, %.2f) kPa, unbalanced = %.2e"
          % (st["void_ratio"], st["Zm"], st["sigma_x"] / 1e3, st["sigma_y"] / 1e3, st["sigma_z"] / 1e3,
             st["unbalanced"]), flush=True)

    rows = study.run_states(path, states, o.out, log=lambda m: print(m, flush=True))

    statics_path = os.path.join(o.out, "statics_isotropic.json")
    if not os.path.exists(statics_path):
        from trueaniso import statics
        free = statics.static_stiffness(scene, rotations=True)
        blocked = statics.static_stiffness(scene, rotations=False)
        zeta = statics.rotation_factor(scene, free=free, blocked=blocked)
        atomic.write_json(statics_path, dict(
            E_free=free["E"], E_blocked=blocked["E"], E_kinematic=zeta["E_kinematic"], nu_free=free["nu"],
            zeta_h=zeta["zeta_h"], zeta_v=zeta["zeta_v"], residual=free["residual"],
            rattlers=len(free["rattlers"]), time=free["time"]["total"] + blocked["time"]["total"]))
    sres = json.load(open(statics_path))
    print("statics (isotropic state): E_free = %s MPa, E_blocked = %s MPa, magnitude zeta_h = %.3f, zeta_v = %.3f"
          % ([round(e / 1e6, 1) for e in sres["E_free"]], [round(e / 1e6, 1) for e in sres["E_blocked"]],
             sres["zeta_h"], sres["zeta_v"]))

    contrast = contrast_zeta(o.out, rows)
    if contrast:
        print("zeta calibrated on the contrast a_i^2 (Eq. 25) over %d states, as the paper's Fig. 13: "
              "zeta_h = %.3f, zeta_v = %.3f (rms of a_i^2 %.4f; %.4f at the paper's 0.552, %.4f at 1); the "
              "magnitude zeta above answers another question (docs/statics.md 7.1)"
              % (contrast["n_states"], contrast["zeta_h"], contrast["zeta_v"], contrast["rms"],
                 contrast["rms_at_paper"], contrast["rms_at_1"]))

    fig_dir = os.path.join(o.out, "figures")
    os.makedirs(fig_dir, exist_ok=True)
    rows = study.read_rows(os.path.join(o.out, "probes.csv"))
    figures.modulus_vs_stress(rows, os.path.join(fig_dir, "E_vs_sigma.png"))
    fits = figures.scalar_moduli_vs_zm(rows, os.path.join(fig_dir, "K_G_vs_Zm.png"))
    atomic.write_json(os.path.join(o.out, "summary.json"), dict(
        specimen=st, states=len({r["state"] for r in rows}), probes=len(rows), statics=sres, K_G_fits=fits,
        zeta_contrast=contrast,
        wall_time=time.time() - t0))
    print("results: %s (probes.csv, figures/, summary.json) in %.0f s" % (o.out, time.time() - t0))
    if cli.in_yade():
        from trueaniso import yade_bridge
        yade_bridge.yade_scene_from(scene, import_contacts=False)
        print("specimen written into YADE's O (%d particles) for viewing/export" % scene.num_bodies)


def contrast_zeta(out, rows):
    """zeta_h, zeta_v fitted on a_i^2 over the probed states (trueaniso.zeta), from the probe
    rows and the held-state checkpoints; None with fewer than two complete states."""
    import numpy as np
    from trueaniso import dem, zeta
    by_state = {}
    for r in rows:
        by_state.setdefault(r["state"], {})[r["probe"]] = float(r["E"])
    E, A_n, A_s = [], [], []
    for sid, moduli in sorted(by_state.items()):
        ck = os.path.join(out, "states", "%s.npz" % sid)
        if set(moduli) != set("xyz") or not os.path.exists(ck):
            continue
        held, _ = specimen_file.load(ck)
        dem.refresh(held)
        a_n, a_s = zeta.parts_from_scene(held)
        E.append([moduli[a] for a in "xyz"])
        A_n.append(a_n)
        A_s.append(a_s)
    if len(E) < 2:
        return None
    fit = zeta.fit_contrast(np.array(E), np.array(A_n), np.array(A_s))
    return {k: v for k, v in fit.items() if not isinstance(v, np.ndarray)}


if __name__ == "__main__" or cli.in_yade():
    cli.guarded(main)
