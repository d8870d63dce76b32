"""Our law as a YADE class (Law2_ScGeom_SimplifiedMindlinPhys_Mindlin) on a loaded pair of spheres,
against the paper's equations written out here and against YADE's packaged Hertz-Mindlin law.

Two spheres of radius 1 mm overlap by 2 um; sphere 2 slides tangentially at 1.9 mm/s for 200 steps
of 1 us (velocities imposed: both bodies' DOFs blocked), so that the shear force grows to a
quarter of the normal force; then the friction of the contact is lowered at run time to 0.1 and
the pair slides on for 50 steps. Every step records positions, forces and stiffnesses.
Usage: YADE_PREFIX=... yade-double -n -x plugin_law.py OUT.json
"""
import json
import math
import sys

from yade import O, utils
from yade.wrapper import (ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                          InteractionLoop, Bo1_Sphere_Aabb, Ip2_FrictMat_FrictMat_MindlinPhys,
                          Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator, PyRunner)
from yade import Vector3
from yade.wrapper import Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys, Law2_ScGeom_SimplifiedMindlinPhys_Mindlin

out = sys.argv[-1]
G, NU, R, DELTA0, V, DT = 18e9, 0.15, 1e-3, 2e-6, 1.8e-3, 1e-6
YOUNG = 2 * G * (1 + NU)
records = []


def record():
    i = O.interactions[0, 1]
    p1, p2 = O.bodies[0].state.pos, O.bodies[1].state.pos
    records.append(dict(p1=list(p1), p2=list(p2), normal=list(i.geom.normal),
                        N=list(i.phys.normalForce), Fs=list(i.phys.shearForce),
                        kn=i.phys.kn, ks=i.phys.ks, v=list(O.bodies[1].state.vel - O.bodies[0].state.vel),
                        phys=type(i.phys).__name__))


import __main__  # noqa: E402
__main__.record = record  # PyRunner commands run in __main__


def run(ours):
    del records[:]
    O.reset()
    mat = O.materials.append(FrictMat(young=YOUNG, poisson=NU, frictionAngle=math.atan(0.5), density=2500))
    O.bodies.append([utils.sphere((0, 0, 0), R, material=mat), utils.sphere((0, 0, 2 * R - DELTA0), R, material=mat)])
    for b in O.bodies:
        b.state.blockedDOFs = "xyzXYZ"
    O.bodies[1].state.vel = Vector3(V, 0.3 * V, 0)
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()]),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                        [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys() if ours else Ip2_FrictMat_FrictMat_MindlinPhys()],
                        [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin() if ours else Law2_ScGeom_MindlinPhys_Mindlin()]),
        PyRunner(command="record()", iterPeriod=1, initRun=True),
        NewtonIntegrator(damping=0.0),
    ]
    O.dt = DT
    O.run(200, True)
    O.interactions[0, 1].phys.tangensOfFrictionAngle = 0.1
    O.run(50, True)
    return list(records)


result = dict(ours=run(True), yade=run(False), G=G, nu=NU, young=YOUNG, r=R, dt=DT)
with open(out, "w") as f:
    json.dump(result, f)
