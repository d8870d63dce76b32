"""The plugin's classes on clumps as a YADE user makes them (docs/studies/yade-peer.md): 300 spheres
from makeCloud made dimers and trimers by replaceByClumps, consolidated and taken to state 21 with
the plugin's servo, then each class's reading against YADE's own: the servo's stress against
utils.getStress() (the same step, the integrator off), FabricRecorder's Zm against
utils.avgNumInteractions(skipFree=True), StressProbe's E_z against getStress's increment over the
strain of YADE's cell between the ramp's start and the probe's end. One seed (7), one thread.

    YADE_PREFIX=$PWD/build/yade-prefix yade-double -j1 -n -x bench/yade_clump_trial.py --json OUT.json
"""
import json
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso importable)

from trueaniso import cli  # noqa: E402

parser = cli.Parser(description=cli.description(__doc__))
parser.add_argument("--json", required=True, help="where the readings are written")
o = cli.parse(parser)
try:
    from yade import O, pack, utils
except ImportError:
    cli.fail("this script runs in YADE with the plugin: YADE_PREFIX=build/yade-prefix yade-double -n -x %s --json OUT"
             % sys.argv[0])
from yade.wrapper import (  # noqa: E402
    Bo1_Sphere_Aabb, FabricRecorder, ForceResetter, FrictMat, GlobalStiffnessTimeStepper, Ig2_Sphere_Sphere_ScGeom,
    InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys,
    Law2_ScGeom_SimplifiedMindlinPhys_Mindlin, NewtonIntegrator, PyRunner, StressProbe, TrueTriaxialServo)

N = 300
G, NU, RHO, P, D50 = 18e9, 0.15, 2500.0, 100e3, 0.2e-3
O.periodic = True
mat = O.materials.append(FrictMat(young=2 * G * (1 + NU), poisson=NU, density=RHO, frictionAngle=math.atan(0.5)))
side = (N * math.pi / 6 * D50 ** 3 / 0.25) ** (1 / 3)
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (side, side, side), rMean=D50 / 2, rRelFuzz=0.1, num=N, periodic=True, seed=7)
sp.toSimulation(material=mat)
dimer = utils.clumpTemplate(relRadii=[1, 1], relPositions=[(-0.5, 0, 0), (0.5, 0, 0)])
trimer = utils.clumpTemplate(relRadii=[1, 1, 1], relPositions=[(-1, 0, 0), (0, 0, 0), (1, 0, 0)])
O.bodies.replaceByClumps([dimer, trimer], [0.5, 0.5])
clumps = [b for b in O.bodies if b.isClump]
sizes = {}
for c in clumps:
    sizes[len(c.shape.members)] = sizes.get(len(c.shape.members), 0) + 1
O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
             InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                             [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()], [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]),
             GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.4, timeStepUpdateInterval=100),
             NewtonIntegrator(damping=0.4)]
O.dt = 0.5 * utils.PWaveTimeStep()
while -utils.getStress().trace() / 3 > 1e3 or O.iter == 0:
    O.run(2000, True)


def insert(e):
    O.engines = O.engines[:-2] + [e] + O.engines[-2:]


cons = TrueTriaxialServo(b=0, sigmaZ=P, meanStress=P, loadingFriction=0.02, maxStrain=1.0, pathRate=20.0,
                         followTolerance=P, inertialNumber=1e-2, stressTolerance=1000.0, unbalancedTolerance=1e-2)
insert(cons)
while not (cons.reached or cons.failed):
    O.run(20000, True)
assert cons.reached, cons.message
O.engines = [e for e in O.engines if e is not cons]
servo = TrueTriaxialServo(b=0.5, sigmaZ=140e3, meanStress=P, stressTolerance=100.0)
insert(servo)
while not (servo.reached or servo.failed):
    O.run(5000, True)
assert servo.reached, servo.message
res = dict(clumps=len(clumps), sizes=sizes, members=sum(1 for b in O.bodies if b.isClumpMember),
           servo_steps=servo.steps, consolidation_steps=cons.steps)
res["servo_stress"] = list(servo.stress)[:3]
gs = utils.getStress()
res["getStress_after_run"] = [-gs[i][i] for i in range(3)]
# one more servo step with the integrator dead: getStress reads the forces and positions the servo read
newton = O.engines[-1]
newton.dead = True
servo.pauseWhenDone = False
# a reached servo does nothing more: a fresh one reads the held state
O.engines = [e for e in O.engines if e is not servo]
reader = TrueTriaxialServo(b=0.5, sigmaZ=140e3, meanStress=P, stressTolerance=100.0)
insert(reader)
O.run(1, True)
gs = utils.getStress()
res["same_step"] = dict(servo=list(reader.stress), getStress=[-gs[0][0], -gs[1][1], -gs[2][2], -gs[1][2], -gs[0][2], -gs[0][1]])
O.engines = [e for e in O.engines if e is not reader]
newton.dead = False
fab = FabricRecorder()
insert(fab)
fab()
res["fabric"] = dict(Zm=fab.Zm, particles=fab.particles, contacts=fab.contacts, e=fab.voidRatio,
                     yade_avgNumInteractions=utils.avgNumInteractions(skipFree=True), message=fab.message)
O.engines = [e for e in O.engines if e is not fab]
probe = StressProbe(axis="z", holdStress=servo.finalStress(), restoreState=False)
insert(probe)
seen = {}


def M(m):
    return np.array([[m[i][j] for j in range(3)] for i in range(3)])
def watch():
    """YADE's stress and cell at the step the ramp begins (stage 2) and the probe ends (4), after the probe."""
    if probe.stage in (2, 4) and probe.stage not in seen:
        seen[probe.stage] = dict(s=-M(utils.getStress()), h=M(O.cell.hSize))


O.engines = O.engines + [PyRunner(iterPeriod=1, command="watch()")]
O.engines = O.engines[:-3] + [O.engines[-1]] + O.engines[-3:-1]  # PyRunner right after the probe
while not probe.finished:
    O.run(1000, True)
F = seen[4]["h"] @ np.linalg.inv(seen[2]["h"])
eps = -(0.5 * (F + F.T) - np.eye(3))
ds = seen[4]["s"] - seen[2]["s"]
res["probe"] = dict(E_z=probe.E, steps=probe.steps, stage=probe.stage, yade_E_z=ds[2, 2] / eps[2, 2],
                    rel=abs(probe.E - ds[2, 2] / eps[2, 2]) / probe.E)
print(json.dumps(res))
with open(o.json, "w") as f:
    json.dump(res, f, indent=1)
