"""Every refusal of the plugin's classes as a Python exception, and the scene as the refused engine
found it (test_yade_plugin.py::test_refusals_*).

Usage: YADE_PREFIX=... yade-double -n -x plugin_refusals.py SPECIMEN.npz OUT.json
Writes {case: {"error": "ExceptionType: message" or None, ...what the case measured}}.
"""
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
from yade import O, utils  # noqa: E402
from yade.wrapper import (Bo1_Sphere_Aabb, Bo1_Wall_Aabb, FabricRecorder, ForceResetter, FrictMat,  # noqa: E402
                          Ig2_Sphere_Sphere_ScGeom, Ig2_Wall_Sphere_ScGeom,
                          InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys,
                          Law2_ScGeom_SimplifiedMindlinPhys_Mindlin, NewtonIntegrator, PeriTriaxController,
                          StressProbe, TrueTriaxialServo)

from trueaniso import specimen_file, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
result = {}


def error(f):
    try:
        f()
    except Exception as e:  # what a user's script would see
        return "%s: %s" % (type(e).__name__, e)
    return None


def specimen():
    scene, _ = specimen_file.load(path)
    yade_bridge.yade_scene_from(scene, damping=0.4, law="trueaniso")


def insert(engine):
    O.engines = O.engines[:-1] + [engine] + O.engines[-1:]


def frictions():
    return sorted({round(I.phys.tangensOfFrictionAngle, 12) for I in O.interactions if I.isReal})


def scene_state():
    """What a refused or reset engine must leave as it found it."""
    return dict(frictions=frictions(), velGrad=[list(O.cell.velGrad[i]) for i in range(3)],
                blocked=sorted({b.state.blockedDOFs for b in O.bodies}), hSize=[list(O.cell.hSize[i]) for i in range(3)])


# --- attributes: at construction and at assignment, the attribute named, the old value kept
def assign(obj, name, value):
    def f():
        setattr(obj, name, value)
    return f


servo = TrueTriaxialServo(b=0.5, sigmaZ=140e3)
probe = StressProbe()
recorder = FabricRecorder()
cases = {
    "servo_b_2": lambda: TrueTriaxialServo(b=2),
    "servo_sigmaZ_0": lambda: TrueTriaxialServo(sigmaZ=0),
    "servo_combination": lambda: TrueTriaxialServo(b=0, sigmaZ=300e3, meanStress=100e3),
    "servo_pathRate_nan": assign(servo, "pathRate", float("nan")),
    "servo_b_assigned": assign(servo, "b", 2.0),
    "servo_maxSteps_0": lambda: TrueTriaxialServo(maxSteps=0),
    "servo_loadingFriction_0": lambda: TrueTriaxialServo(loadingFriction=0),
    "probe_axis_w": lambda: StressProbe(axis="w"),
    "probe_axis_7": lambda: StressProbe(axis=7),
    "probe_axis_assigned": assign(probe, "axis", "q"),
    "probe_sign_0": lambda: StressProbe(sign=0),
    "probe_gamma_0": lambda: StressProbe(gammaTarget=0),
    "probe_gamma_nan": lambda: StressProbe(gammaTarget=float("nan")),
    "probe_rampSteps_0": lambda: StressProbe(rampSteps=0),
    "probe_settleSteps_0": lambda: StressProbe(settleSteps=0),
    "probe_increment_nan": lambda: StressProbe(increment=float("nan")),
    "probe_hold_inf": lambda: StressProbe(holdStress=(1e5, float("inf"), 1e5, 0, 0, 0)),
    "probe_hold_negative": lambda: StressProbe(holdStress=(1e5, -1e3, 1e5, 0, 0, 0)),
    "ip2_rolling_negative": lambda: Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys(rollingStiffness=-1),
    "fabric_period_0": lambda: FabricRecorder(iterPeriod=0),
    "fabric_period_negative": lambda: FabricRecorder(iterPeriod=-1),
    "fabric_period_assigned_0": assign(recorder, "iterPeriod", 0),
    "servo_update_refused": lambda: servo.updateAttrs(dict(b=0.2, sigmaZ=-3.0)),
    # values of the wrong type, and results (read-only) given
    "type_servo_b_str": lambda: TrueTriaxialServo(b="0.5"),
    "type_servo_b_assigned_str": assign(servo, "b", "0.5"),
    "type_servo_maxSteps_float": lambda: TrueTriaxialServo(maxSteps=1.5),
    "type_probe_hold_5": lambda: StressProbe(holdStress=(1e5, 1e5, 1e5, 0, 0)),
    "type_probe_hold_assigned_5": assign(probe, "holdStress", (1e5, 1e5, 1e5, 0, 0)),
    "type_probe_restrain_str": lambda: StressProbe(restrainRotations="yes"),
    "type_fabric_period_str": lambda: FabricRecorder(iterPeriod="100"),
    "type_ip2_str": lambda: Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys(rollingStiffness="1"),
    "readonly_servo_reached": lambda: TrueTriaxialServo(reached=True),
    "readonly_servo_reached_assigned": assign(servo, "reached", True),
    "readonly_servo_updated": lambda: servo.updateAttrs(dict(reached=True)),
}
for name, f in cases.items():
    result[name] = dict(error=error(f))
result["servo_after_refusals"] = dict(b=servo.b, sigmaZ=servo.sigmaZ, pathRate=servo.pathRate, reached=servo.reached)
result["recorder_after_refusals"] = dict(iterPeriod=recorder.iterPeriod)
result["probe_hold_after_refusals"] = dict(holdStress=[x if x == x else None for x in probe.holdStress])
result["probe_after_refusals"] = dict(axis=probe.axis)
result["probe_axis_int"] = dict(axis=StressProbe(axis=2).axis, error=None)
result["probe_hold_partial"] = dict(error=error(lambda: StressProbe(holdStress=(float("nan"), 1e5, 1e5, 0, 0, 0))))
result["defaults"] = dict(probeFriction=StressProbe().probeFriction, iterPeriod=FabricRecorder().iterPeriod,
                          loadingFriction=TrueTriaxialServo().loadingFriction)

# --- the scene decides: refused at the first step, before the engine changes anything
specimen()
O.run(2, True)
before = scene_state()
for name, make in (("servo_and_probe", lambda: [TrueTriaxialServo(b=0.5, sigmaZ=140e3), StressProbe(axis="z")]),
                   ("probe_and_servo", lambda: [StressProbe(axis="z", restrainRotations=True),
                                                TrueTriaxialServo(b=0.5, sigmaZ=140e3)]),
                   ("servo_and_peritriax", lambda: [TrueTriaxialServo(b=0.5, sigmaZ=140e3),
                                                    PeriTriaxController(goal=(-1e5, -1e5, -1e5), stressMask=7)])):
    saved = list(O.engines)
    for e in make():
        insert(e)
    result[name] = dict(error=error(lambda: O.run(5, True)), after=scene_state(), before=before)
    O.engines = saved
# A probe whose held stresses (NaN: measured now) are not > 0: a scene without stress (the spheres
# shrunk apart).
for b in O.bodies:
    b.shape.radius *= 0.5
O.run(2, True)
before = scene_state()
insert(StressProbe(axis="z", restrainRotations=True))
result["probe_unloaded_hold"] = dict(error=error(lambda: O.run(5, True)), after=scene_state(), before=before)

# --- a hold given in part: its NaN entries take the stress measured at the first step
specimen()
O.run(2, True)
newton = O.engines[-1]
newton.dead = True  # positions held: getStress after the step reads the forces the probe read
part = StressProbe(axis="z", holdStress=(float("nan"), 61e3, 139e3, float("nan"), 0.0, 0.0))
insert(part)
O.run(1, True)
gs = utils.getStress()
result["probe_hold_partial_run"] = dict(error=None, held=list(part.heldStress), given=list(part.holdStress),
                                        measured=[-gs[0][0], -0.5 * (gs[1][2] + gs[2][1])])
newton.dead = False

# --- reset() mid-probe puts the held state back
specimen()
O.run(2, True)
held = scene_state()
held_pos = [list(b.state.pos) for b in O.bodies]
probe = StressProbe(axis="z", restrainRotations=True)
insert(probe)
O.run(200, True)
mid = scene_state()
mid["stage"] = probe.stage
probe.reset()
result["reset_mid_probe"] = dict(error=None, held=held, mid=mid, after=scene_state(),
                                 moved=max(max(abs(a - b) for a, b in zip(p, list(q.state.pos)))
                                           for p, q in zip(held_pos, O.bodies)),
                                 stage=probe.stage, finished=probe.finished)
# a corrected probe after a refused one runs
O.engines = [e for e in O.engines if e is not probe]
bad = StressProbe(axis="z")
err = error(assign(bad, "sign", 0))
insert(bad)
O.run(50, True)
result["corrected_probe_runs"] = dict(error=err, stage=bad.stage, steps=bad.steps, sign=bad.sign)
O.engines = [e for e in O.engines if e is not bad]

# --- FabricRecorder: its default period records; not periodic and no contacts
specimen()
fab = FabricRecorder()
insert(fab)
O.run(250, True)
result["fabric_default_period"] = dict(error=None, records=fab.records, Zm=fab.Zm, message=fab.message)
# the void ratio from the radii as they are at each record (a script may grow its particles)
e_before = fab.voidRatio
for b in O.bodies:
    b.shape.radius *= 0.99
fab()
vs = sum(4.0 / 3.0 * math.pi * b.shape.radius ** 3 for b in O.bodies)
result["fabric_radii_changed"] = dict(before=e_before, after=fab.voidRatio, expected=(O.cell.volume - vs) / vs)
for I in list(O.interactions):
    O.interactions.erase(I.id1, I.id2)
O.engines = [e for e in O.engines if type(e).__name__ != "InsertionSortCollider"]  # nothing comes back
fab()
result["fabric_no_contacts"] = dict(error=None, Zm=fab.Zm, message=fab.message, contacts=fab.contacts,
                                    B=[list(fab.B[i]) for i in range(3)], voidRatio=fab.voidRatio)


def aperiodic(engine):
    O.reset()
    mat = O.materials.append(FrictMat(young=4.14e10, poisson=0.15, density=2500, frictionAngle=0.46))
    O.bodies.append([utils.sphere((0, 0, 0), 1e-4, material=mat), utils.sphere((1.99e-4, 0, 0), 1e-4, material=mat)])
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                                 [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()],
                                 [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]),
                 engine, NewtonIntegrator(damping=0.4)]
    O.dt = 1e-9
    return error(lambda: O.run(3, True))


for name, e in (("servo_aperiodic", TrueTriaxialServo()), ("probe_aperiodic", StressProbe()),
                ("fabric_aperiodic", FabricRecorder(iterPeriod=1)),
                ("fabric_aperiodic_default_period", FabricRecorder())):  # refused at the first step, not the 100th
    result[name] = dict(error=aperiodic(e), frictions=frictions(), iter=O.iter)

# a periodic scene without particles
O.reset()
O.periodic = True
O.cell.hSize = utils.Matrix3(1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3)
empty = FabricRecorder()
result["fabric_empty_scene"] = dict(error=error(lambda: empty()), records=empty.records, message=empty.message)


# --- materials: two of them, and one out of range, in YADE's parallel interaction loop
def pair(m1, m2, gap=-2e-7, walls=False, grid_node=False):
    O.reset()
    a = O.materials.append(m1)
    b = O.materials.append(m2)
    r = 1e-4
    O.bodies.append(utils.sphere((0, 0, 0), r, material=a))
    if walls:
        O.bodies.append(utils.wall(r + gap, axis=0, material=b))
        bounds, geoms = [Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()], [Ig2_Wall_Sphere_ScGeom()]
    elif grid_node:
        # a GridNode is a Sphere to YADE's dispatch (Ig2_Sphere_Sphere_ScGeom makes the geometry),
        # not to our law; YADE's collider gives it no bound, so the interaction is made by hand
        from yade import gridpfacet
        O.bodies.append(gridpfacet.gridNode((2 * r + gap, 0, 0), r, material=b))
        bounds, geoms = [Bo1_Sphere_Aabb()], [Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)]
    else:
        O.bodies.append(utils.sphere((2 * r + gap, 0, 0), r, material=b))
        bounds, geoms = [Bo1_Sphere_Aabb()], [Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)]
    for bd in O.bodies:
        bd.state.blockedDOFs = "xyzXYZ"
    O.engines = [ForceResetter(), InsertionSortCollider(bounds),
                 InteractionLoop(geoms, [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()],
                                 [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]),
                 NewtonIntegrator(damping=0.4)]
    O.dt = 1e-9
    if grid_node:
        utils.createInteraction(0, 1)  # our Ip2 meets the GridNode here, outside a run, first
    started = time.monotonic()
    err = error(lambda: O.run(3, True))
    seconds = time.monotonic() - started
    I = [i for i in O.interactions if i.isReal]
    p = I[0].phys if I else None
    return dict(error=err, seconds=seconds, N=p.normalForce.norm() if p else None, kn=p.kn if p else None, ks=p.ks if p else None,
                rbar=p.rbar if p else None, mu=p.tangensOfFrictionAngle if p else None,
                delta=I[0].geom.penetrationDepth if I else None, iter=O.iter, refused=p.refused if p else None)


def fm(young, poisson, angle=math.atan(0.5)):
    return FrictMat(young=young, poisson=poisson, density=2500, frictionAngle=angle)


result["two_materials"] = pair(fm(4.14e10, 0.15), fm(2 * 70e9 * 1.3, 0.3, math.atan(0.3)))
result["poisson_half"] = pair(fm(4.14e10, 0.15), fm(4.14e10, 0.5))
result["young_nan"] = pair(fm(float("nan"), 0.15), fm(4.14e10, 0.15))
result["poisson_minus_one"] = pair(fm(4.14e10, -1.0), fm(4.14e10, 0.15))
# corrected, the same scene goes on: the refused contact is made again
O.materials[0].poisson = 0.15
result["corrected_material"] = dict(error=error(lambda: O.run(3, True)),
                                    N=[i.phys.normalForce.norm() for i in O.interactions if i.isReal][0])
result["wall"] = pair(fm(4.14e10, 0.15), fm(4.14e10, 0.15), walls=True)
result["grid_node"] = pair(fm(4.14e10, 0.15), fm(4.14e10, 0.15), grid_node=True)
# the same scene run again, not corrected: the same refusal, raised again
started = time.monotonic()
result["grid_node_again"] = dict(error=error(lambda: O.run(3, True)), seconds=time.monotonic() - started,
                                 iter=O.iter)
result["process_alive"] = True

with open(out, "w") as f:
    json.dump(result, f, indent=1)
