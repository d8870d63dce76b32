"""Clumps in YADE with the trueaniso plugin's classes: a makeCloud packing whose spheres become the
paper's clump2 dimers (or clump1 trimers) by replaceByClumps, consolidated to 100 kPa, taken to
state 21 of Table C1, probed on z, x and y, its fabric recorded. Nothing from this repository is
needed but the plugin (./setup.sh builds it into build/yade-prefix):

    YADE_PREFIX=$PWD/build/yade-prefix yade-double -n -x pyscripts/examples/yade_clumps_state21.py OUTDIR [N] [clump1|clump2]

N clumps (default 200) of the template (default clump2: two equal balls one radius apart, aspect
ratio 1.5; clump1: three in a row, one radius apart, aspect ratio 2; docs/specimens.md), scaled so
that a clump has the volume of the sphere it replaces (D50 0.216 mm for clump2, 0.195 mm for
clump1: the paper's Table 1). Writes OUTDIR/state21-<template>.json and the scene at the state,
OUTDIR/state21-<template>.yade.gz.

A clump is one particle to every class here, as in the paper: the servo's and the probe's stress
takes the contacts' branch vectors between clump centres (YADE's utils.getStress() takes the same,
and the script prints both), and FabricRecorder counts a clump once in Zm, its contacts with every
other particle in Nc, and its solid volume as the union of its balls.

The time step: GlobalStiffnessTimeStepper at factor 0.4 (yade_cloud_state21.py says why not YADE's
usual 0.8), which sums the stiffness of every member's contacts onto its clump and takes the
clump's mass and inertia. PWaveTimeStep() knows nothing of either: it takes the material's modulus
for a contact stiffness and the members for particles.
"""
import json
import math
import os
import sys

from yade import O, pack, utils
try:
    from yade.wrapper import (Bo1_Sphere_Aabb, FabricRecorder, ForceResetter, FrictMat, GlobalStiffnessTimeStepper,
                              Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                              Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys, Law2_ScGeom_SimplifiedMindlinPhys_Mindlin,
                              NewtonIntegrator, StressProbe, TrueTriaxialServo)
except ImportError:  # YADE without the trueaniso plugin
    sys.exit("this example needs the trueaniso YADE plugin: YADE_PREFIX=<repository>/build/yade-prefix yade-double "
             "-n -x %s OUTDIR (./setup.sh builds the plugin when the YADE source can be had)" % sys.argv[0])

args = [a for a in sys.argv[1:] if not a.startswith("-")]
if not args:
    sys.exit("usage: yade-double -n -x yade_clumps_state21.py OUTDIR [N] [clump1|clump2]")
OUT = args[0]
N = int(args[1]) if len(args) > 1 else 200
NAME = args[2] if len(args) > 2 else "clump2"
# The paper's two clump templates (centres and radii in units of the member radius) and D50.
TEMPLATES = {"clump2": (dict(relRadii=[1, 1], relPositions=[(-0.5, 0, 0), (0.5, 0, 0)]), 0.216e-3),
             "clump1": (dict(relRadii=[1, 1, 1], relPositions=[(-1, 0, 0), (0, 0, 0), (1, 0, 0)]), 0.195e-3)}
if NAME not in TEMPLATES:
    sys.exit("the template is clump1 or clump2, not %r" % NAME)
template, D50 = TEMPLATES[NAME]
os.makedirs(OUT, exist_ok=True)
G, NU, RHO, P, MU = 18e9, 0.15, 2500.0, 100e3, 0.5
MU_DENSE = 0.02  # friction while consolidating: a dense packing, as the paper's (yade_cloud_state21.py)

O.periodic = True
mat = O.materials.append(FrictMat(young=2 * G * (1 + NU), poisson=NU, density=RHO, frictionAngle=math.atan(MU)))
side = (N * math.pi / 6 * D50 ** 3 / 0.25) ** (1.0 / 3.0)  # spheres at solid fraction 0.25
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (side, side, side), rMean=D50 / 2, rRelFuzz=0.1, num=N, periodic=True, seed=1)
sp.toSimulation(material=mat)
# Each sphere becomes a clump of the same volume, randomly oriented (YADE scales the template).
O.bodies.replaceByClumps([utils.clumpTemplate(**template)], [1.0])
clumps = [b for b in O.bodies if b.isClump]
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                    [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()], [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]),
    GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.4, timeStepUpdateInterval=100),
    NewtonIntegrator(damping=0.4),
]
O.dt = 0.5 * utils.PWaveTimeStep()  # the first step only: the stepper takes over
# replaceByClumps leaves neighbours overlapping (a clump is longer than the sphere it replaces):
# they push apart first, in the cell as it is. A servo started now would take their transient
# stress (tens of MPa) for the start of its path and hold it.
while -utils.getStress().trace() / 3 > 1e3 or O.iter == 0:
    O.run(2000, True)
print("overlaps resolved after %d steps" % O.iter)
# Consolidation: the servo at b = 0, sigma_z = p = 100 kPa (isotropic) from the cloud (see
# yade_cloud_state21.py): at the rate of inertial number 1e-2 until the clumps touch, then along
# the path, at friction 0.02 (dense).
consolidation = TrueTriaxialServo(b=0, sigmaZ=P, meanStress=P, loadingFriction=MU_DENSE, maxStrain=1.0, pathRate=20.0,
                                  followTolerance=P, inertialNumber=1e-2, stressTolerance=1000.0, unbalancedTolerance=1e-2,
                                  label="consolidation")
O.engines = O.engines[:-2] + [consolidation] + O.engines[-2:]
while not (consolidation.reached or consolidation.failed):
    O.run(20000, True)
    print("consolidating: step %d, p = %.1f kPa" % (O.iter, -utils.getStress().trace() / 3e3), flush=True)
if consolidation.failed:
    sys.exit("not consolidated: " + consolidation.message)
O.engines = [e for e in O.engines if e is not consolidation]
pwave = utils.PWaveTimeStep()
print("%d %s clumps consolidated in %d steps; time step %.3g s, PWaveTimeStep() %.3g s"
      % (len(clumps), NAME, O.iter, O.dt, pwave))


def insert(engine):
    """Our engines go after InteractionLoop and before NewtonIntegrator (they read this step's forces)."""
    O.engines = O.engines[:-2] + [engine] + O.engines[-2:]


def run_until(done, chunk=5000):
    while not done():
        O.run(chunk, True)


servo = TrueTriaxialServo(b=0.5, sigmaZ=140e3, meanStress=P, stressTolerance=100.0, label="servo")
insert(servo)
run_until(lambda: servo.reached or servo.failed)
if servo.failed:
    sys.exit("state 21 not reached: " + servo.message)
O.engines = [e for e in O.engines if e is not servo]
print("state 21 held after %d servo steps: stresses (%.2f, %.2f, %.2f) kPa, YADE's getStress (%.2f, %.2f, %.2f) kPa"
      % ((servo.steps,) + tuple(servo.stress[i] / 1e3 for i in range(3))
         + tuple(-utils.getStress()[i][i] / 1e3 for i in range(3))))

fabric = FabricRecorder(label="fabric")
insert(fabric)
fabric()
stem = os.path.join(OUT, "state21-" + NAME)
O.save(stem + ".yade.gz")
results = dict(state=21, template=NAME, clumps=fabric.particles, servo_steps=servo.steps, stress=list(servo.stress),
               consolidation_steps=consolidation.steps, dt=O.dt, PWaveTimeStep=pwave,
               Zm=fabric.Zm, void_ratio=fabric.voidRatio, contacts=fabric.contacts,
               B=[list(fabric.B[i]) for i in range(3)], M=list(fabric.M))
print("fabric: Zm = %.3f (clumps as particles), e = %.4f (union volumes), B diagonal (%.4g, %.4g, %.4g)"
      % (fabric.Zm, fabric.voidRatio, fabric.B[0][0], fabric.B[1][1], fabric.B[2][2]))

for axis in ("z", "x", "y"):
    probe = StressProbe(axis=axis, holdStress=servo.finalStress(), label="probe")
    insert(probe)
    run_until(lambda: probe.finished, chunk=1000)
    O.engines = [e for e in O.engines if e is not probe]
    if probe.stage != 4:
        sys.exit("probe %s failed: %s" % (axis, probe.message))
    results["E_" + axis] = probe.E
    results["nu_" + axis] = [probe.nu[j] for j in range(3)]
    print("probe %s: E = %.1f MPa (%d steps)" % (axis, probe.E / 1e6, probe.steps))

with open(stem + ".json", "w") as f:
    json.dump(results, f, indent=1)
print("wrote %s.json and %s.yade.gz" % (stem, stem))
