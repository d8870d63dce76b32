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
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
import numpy as np  # noqa: E402
from yade import (O, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,  # noqa: E402
                  InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_MindlinPhys,
                  Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator, Matrix3, pack, utils)

from trueaniso import engines as E, fabric, yade_bridge  # noqa: E402

n = int(sys.argv[1])
out = sys.argv[-1]
G, nu = 18e9, 0.15
O.periodic = True
mat = O.materials.append(FrictMat(young=2 * G * (1 + nu), poisson=nu, density=2500,
                                  frictionAngle=math.atan(0.5)))
r = 0.0975e-3
side = (n * 4.0 / 3.0 * math.pi * r ** 3 / 0.30) ** (1.0 / 3.0)
O.cell.hSize = Matrix3(side, 0, 0, 0, side, 0, 0, 0, side)
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (side, side, side), rMean=r, rRelFuzz=0.2, periodic=True, seed=4, num=n)
sp.toSimulation(material=mat)
# Grow every radius by the same factor to a solid fraction of 0.63: a dense overlapping network
# (Zm ~ 5-6) with rattlers and particles of one contact, in one collider pass.
solid = sum(4.0 / 3.0 * math.pi * b.shape.radius ** 3 for b in O.bodies)
grow = (0.63 * side ** 3 / solid) ** (1.0 / 3.0)
for b in O.bodies:
    b.shape.radius *= grow
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                    [Ip2_FrictMat_FrictMat_MindlinPhys()], [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.4, dead=True),  # forces at the given positions only
]
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
