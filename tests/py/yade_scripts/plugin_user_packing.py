"""A packing made in YADE the usual way, taken by TrueTriaxialServo to a state of its own
(test_yade_plugin.py::test_the_servo_reaches_a_state_from_a_yade_user_s_packing).

Usage: YADE_PREFIX=... yade-double -n -x plugin_user_packing.py N [servo options: name=value ...] OUT.json

N spheres of the paper's material from pack.SpherePack.makeCloud, consolidated to 100 kPa isotropic
at "infinite" friction (frictionAngle pi/2, sliding suppressed while consolidating: the usual way to
a loose packing) with our law and GlobalStiffnessTimeStepper at 0.4 (docs/yade-peer.md); then
TrueTriaxialServo at its loading friction 0.5 for b = 0.3 and sigma_z = 125 kPa at p = 100 kPa (a
state not in Table C1). When the friction drops the loose packing loses much of its stress; the
servo must bring it back and reach the state.

The consolidation is TrueTriaxialServo at b = 0, not PeriTriaxController: at this scale (a cell of
1.6 mm) PeriTriaxController's stiffness rule asks for a strain rate of (goal - stress) A/(k dt), a
length over a time, as a rate, about 600 times too large; it runs at its cap, alternating in sign
(maxStrainRate 200 /s: stuck at 760 kPa after 500,000 steps).
"""
import json
import math
import sys

from yade import O, pack, utils
from yade.wrapper import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, GlobalStiffnessTimeStepper,
                          Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider, InteractionLoop,
                          Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys, Law2_ScGeom_SimplifiedMindlinPhys_Mindlin,
                          NewtonIntegrator, TrueTriaxialServo)

N, out = int(sys.argv[1]), sys.argv[-1]
servo_options = {k: (int(v) if v.isdigit() else float(v)) for k, v in (a.split("=") for a in sys.argv[2:-1])}
G, NU, RHO, D50, P = 18e9, 0.15, 2500.0, 0.195e-3, 100e3
result = dict(N=N)

O.periodic = True
mat = O.materials.append(FrictMat(young=2 * G * (1 + NU), poisson=NU, density=RHO, frictionAngle=math.pi / 2))
side = (N * math.pi / 6 * D50 ** 3 / 0.3) ** (1.0 / 3.0)
sp = pack.SpherePack()
sp.makeCloud((0, 0, 0), (side, side, side), rMean=D50 / 2, rRelFuzz=0.1, num=N, periodic=True, seed=3)
sp.toSimulation(material=mat)
consolidation = TrueTriaxialServo(b=0, sigmaZ=P, meanStress=P, loadingFriction=1e23, maxStrain=1.0, pathRate=20.0,
                                  followTolerance=P, inertialNumber=1e-2, stressTolerance=1000.0, unbalancedTolerance=1e-2,
                                  label="consolidation")
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                    [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()], [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]),
    consolidation,
    GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.4, timeStepUpdateInterval=100),
    NewtonIntegrator(damping=0.4),
]
O.dt = 0.5 * utils.PWaveTimeStep()
while not (consolidation.reached or consolidation.failed):
    O.run(20000, True)
vs = sum(4 / 3 * math.pi * b.shape.radius ** 3 for b in O.bodies)
result["consolidation"] = dict(done=consolidation.reached, message=consolidation.message, steps=O.iter, e=(O.cell.volume - vs) / vs,
                               contacts=sum(1 for I in O.interactions if I.isReal),
                               stress=[-utils.getStress()[i][i] for i in range(3)])

O.engines = [e for e in O.engines if e is not consolidation]
start = O.iter
servo = TrueTriaxialServo(b=0.3, sigmaZ=125e3, meanStress=P, label="servo", **servo_options)
O.engines = O.engines[:-2] + [servo] + O.engines[-2:]
lowest = None
while not (servo.reached or servo.failed):
    O.run(100 if servo.steps < 10000 else 5000, True)  # finely at first: the stress drops within ~1000 steps
    p = sum(servo.stress[i] for i in range(3)) / 3
    lowest = p if lowest is None else min(lowest, p)
goal = servo.target
result["servo"] = dict(reached=servo.reached, failed=servo.failed, message=servo.message, steps=servo.steps,
                       iters=O.iter - start, stress=list(servo.stress), goal=list(goal),
                       error=max(abs(servo.stress[i] - goal[i]) for i in range(6)),
                       getStress=[-utils.getStress()[i][i] for i in range(3)], lowest_mean=lowest,
                       rateCap=servo.rateCap,
                       frictions=sorted({round(I.phys.tangensOfFrictionAngle, 12) for I in O.interactions if I.isReal}))
with open(out, "w") as f:
    json.dump(result, f)
