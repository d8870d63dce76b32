"""A YADE packing (makeCloud, radii then grown by a common factor so that the spheres overlap and
carry Hertz-Mindlin forces) imported through the bridge: our fabric against YADE's own
utils.avgNumInteractions(skipFree=True), utils.fabricTensor() and utils.porosity(), and against
the same measures written in plain Python over O.interactions (trueaniso.fabric).
Usage: yade-double -n -x peer_fabric.py N OUT.json
"""
import json
import math
import os
import sys

# under yade-double __file__ names yade itself; the script path is argv[0]
HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, utils  # noqa: E402

from trueaniso import engines as E, fabric, yade_bridge  # noqa: E402
from yade_scenes import mindlin_cloud  # noqa: E402

n = int(sys.argv[1])
out = sys.argv[-1]
side = mindlin_cloud(n, seed=4, solid_fraction=0.30)
# Grow every radius by the same factor to a solid fraction of 0.63: a dense overlapping network
# (Zm ~ 5-6) with rattlers and particles of one contact, in one collider pass.
solid = sum(4.0 / 3.0 * math.pi * b.shape.radius ** 3 for b in O.bodies)
grow = (0.63 * side ** 3 / solid) ** (1.0 / 3.0)
for b in O.bodies:
    b.shape.radius *= grow
O.engines[-1].dead = True  # forces at the given positions only
O.dt = 1e-9
O.step()

yade_Zm = utils.avgNumInteractions(skipFree=True)
yade_R = np.array(utils.fabricTensor()[0])
yade_porosity = utils.porosity()
python = fabric.fabric_from_interactions(O)

scene, ids = yade_bridge.scene_from_yade(O)
sim = E.Simulation(scene)
sim.add(E.ContactDetection())
sim.add(E.ContactForces())
sim.run(1)
ours = fabric.fabric(scene)


def plain(d):
    return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in d.items()}


with open(out, "w") as f:
    json.dump(dict(n=len(ids), yade_Zm=yade_Zm, yade_R=yade_R.tolist(), yade_porosity=yade_porosity,
                   yade_real_interactions=sum(1 for I in O.interactions if I.isReal),
                   python=plain(python), ours=plain(ours)), f, indent=1)
