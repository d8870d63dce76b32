# The ABI self-test of a freshly built libtrueanisoYade.so, run by cmake/yade_plugin.sh in
# yade-double before the plugin is installed:
#   YADE_PREFIX=<stage prefix> yade-double -n -x engines/yade/selftest.py
# A plugin compiled with one of YADE's definitions wrong does not crash: it reads the scene at the
# wrong offsets. So the plugin must read exactly what YADE's own code reads:
#  1. an engine records scene->iter, time, dt and the cell volume each step; Python's O.iter,
#     O.time, O.dt and O.cell.volume of the same steps must be equal to the bit;
#  2. our law on a small strained packing against YADE's packaged Law2_ScGeom_MindlinPhys_Mindlin
#     on the same packing: the same contacts, the normal and shear forces equal to 1e-6 of the
#     largest force. The two laws differ only in how the shear force is turned with the contact
#     (an exact rotation against YADE's small-angle update), O(angle^2) per step: about 1e-9 of
#     the force over these 150 steps (3e-8 over 300, 6e-7 over 300 steps twice as long: the
#     path is kept short for that margin); a scene read at the wrong offsets gives O(1) errors.
# Exit status 0: passed. Otherwise the last line of stderr says what failed.
import math
import os
import sys

from yade import O, pack, utils
from yade.wrapper import (ForceResetter, InsertionSortCollider, InteractionLoop, Bo1_Sphere_Aabb,
                          Ig2_Sphere_Sphere_ScGeom, Ip2_FrictMat_FrictMat_MindlinPhys,
                          Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator, PyRunner, FrictMat)
from yade import Matrix3, Vector3


def fail(why):
    sys.stdout.flush()
    sys.stderr.write("self-test: " + why + "\n")
    sys.stderr.flush()
    os._exit(1)


try:
    from yade.wrapper import (TrueanisoAbiCheck, Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys,
                              Law2_ScGeom_SimplifiedMindlinPhys_Mindlin)
except ImportError as e:
    fail("the plugin's classes are not registered (%s)" % e)


def packing(ours):
    """32 spheres in a periodic cell, grown into overlaps and strained for 150 steps."""
    O.reset()
    O.periodic = True
    O.cell.setBox(1, 1, 1)
    sp = pack.SpherePack()
    sp.makeCloud((0, 0, 0), (1, 1, 1), rMean=0.12, rRelFuzz=0.2, periodic=True, seed=5, num=32)
    mat = O.materials.append(FrictMat(young=2 * 18e9 * 1.15, poisson=0.15, frictionAngle=math.atan(0.5),
                                      density=2500))
    sp.toSimulation(material=mat)
    for b in O.bodies:  # overlaps from the start: a loaded network within a few hundred small steps
        b.shape.radius *= 1.3
    ip2 = Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys() if ours else Ip2_FrictMat_FrictMat_MindlinPhys()
    law = Law2_ScGeom_SimplifiedMindlinPhys_Mindlin() if ours else Law2_ScGeom_MindlinPhys_Mindlin()
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()]),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [ip2], [law]),
        NewtonIntegrator(damping=0.2),
    ]
    O.dt = 1e-7
    O.cell.velGrad = Matrix3(-8, 0.5, 0, 0.5, -7, 0.3, 0, 0.3, -9)
    O.run(150, True)
    forces = {}
    for i in O.interactions:
        if i.isReal:
            forces[(i.id1, i.id2)] = (tuple(i.phys.normalForce), tuple(i.phys.shearForce))
    return forces


# 1. The engine's view of the scene.
O.reset()
O.periodic = True
O.cell.setBox(2, 3, 4)
O.cell.velGrad = Matrix3(-0.1, 0, 0, 0, 0.05, 0, 0, 0, 0.02)
O.dt = 1e-3
check = TrueanisoAbiCheck()
seen = []
import __main__
__main__.seen = seen  # PyRunner commands run in __main__
O.engines = [ForceResetter(), check,
             PyRunner(command="seen.append((O.iter, O.time, O.dt, O.cell.volume))", iterPeriod=1, initRun=True),
             NewtonIntegrator()]
O.bodies.append([utils.sphere((0.5, 0.5, 0.5), 0.1), utils.sphere((1, 1, 1), 0.1)])
O.run(25, True)
mine = list(zip(check.iters, check.times, check.dts, check.cellVolumes))
if len(mine) != 25 or len(seen) != 25:
    fail("in 25 steps the engine ran %d times, a PyRunner %d times" % (len(mine), len(seen)))
for a, b in zip(mine, seen):
    if a[0] != b[0] or a[1] != b[1] or a[2] != b[2] or a[3] != b[3]:
        fail("the engine reads iter/time/dt/volume %s where YADE has %s" % (a, b))
if check.bodyCount != 2:
    fail("the engine sees %d bodies, YADE 2" % check.bodyCount)

# 2. The law against YADE's Mindlin.
yade_forces = packing(False)
our_forces = packing(True)
if len(yade_forces) < 20:
    fail("the test packing has only %d contacts" % len(yade_forces))
if set(yade_forces) != set(our_forces):
    fail("our law's contacts differ from YADE's (%d against %d)" % (len(our_forces), len(yade_forces)))
scale = max(math.sqrt(sum(x * x for x in f[0])) for f in yade_forces.values())
worst = 0.0
for key, (fn, fs) in yade_forces.items():
    gn, gs = our_forces[key]
    for a, b in zip(fn + fs, gn + gs):
        worst = max(worst, abs(a - b))
shear = max(math.sqrt(sum(x * x for x in f[1])) for f in yade_forces.values())
if not (scale > 0 and shear > 1e-3 * scale):
    fail("the test packing carries no shear force (largest normal %g, shear %g N)" % (scale, shear))
if not worst <= 1e-6 * scale:
    fail("our law's forces differ from YADE's Mindlin by %.3g of the largest force (allowed 1e-6)" % (worst / scale))
print("self-test passed: engine reads iter/time/dt/volume as YADE; law vs YADE Mindlin on %d contacts (largest shear "
      "%.2g of the largest normal force): %.2g of the largest force" % (len(yade_forces), shear / scale, worst / scale))
sys.stdout.flush()
os._exit(0)
