"""The default study, run by ./main.sh:

    yade-double -n -x pyscripts/run_study.py [--n 1000] [--seed 1] [--out results/default]

Today: prepare a sphere specimen consolidated isotropically to 100 kPa (docs/specimens.md) and
write its state. Every stage writes its results atomically and is skipped when its output is
already there, so an interrupted study resumes where it stopped.
"""
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__)))
from trueaniso import atomic, cli, specimen, specimen_file  # noqa: E402


def options():
    p = cli.Parser(description="trueaniso default study")
    p.add_argument("--n", type=int, default=1000, help="spheres in the specimen")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--out", default="results/default", help="results directory")
    return cli.parse(p)


def main():
    o = options()
    if o.n < 100:
        raise cli.InputError("--n must be >= 100 for a study specimen")
    os.makedirs(o.out, exist_ok=True)
    t0 = time.time()
    path = os.path.join(o.out, "specimen.npz")
    if os.path.exists(path):
        try:
            scene, meta = specimen_file.load(path)
            print("specimen: kept %s" % path)
        except specimen_file.SpecimenFileError as exc:
            raise cli.InputError("%s is not usable (%s); remove it to prepare it again" % (path, exc))
    else:
        print("specimen: preparing %d spheres (seed %d) ..." % (o.n, o.seed), flush=True)
        scene, log = specimen.prepare_spheres(o.n, seed=o.seed)
        specimen_file.save(path, scene, seed=o.seed, parameters=log, summary=specimen.state(scene))
        print("specimen: saved %s (%.1f s)" % (path, time.time() - t0))
    st = specimen.state(scene)
    atomic.write_json(os.path.join(o.out, "specimen_state.json"), st)
    print("state: e = %.4f, Zm = %.3f, sigma = (%.2f, %.2f, %.2f) kPa, unbalanced = %.2e"
          % (st["void_ratio"], st["Zm"], st["sigma_x"] / 1e3, st["sigma_y"] / 1e3, st["sigma_z"] / 1e3,
             st["unbalanced"]))
    if cli.in_yade():
        from trueaniso import yade_bridge
        yade_bridge.yade_scene_from(scene, import_contacts=False)
        print("state written into YADE's O (%d spheres) for viewing/export" % scene.num_bodies)


if __name__ == "__main__" or cli.in_yade():
    cli.guarded(main)
