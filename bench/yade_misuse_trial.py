"""The plugin's refusals tried as a YADE user meets them (docs/studies/yade-peer.md): wrong values and
types at construction, assignment and updateAttrs; on a loaded packing (the cloud example's scene,
pyscripts/examples/yade_cloud_state21.py) two controllers of the cell, a probe corrected after a
refusal, reset() mid-probe, a hold given in part, the loading friction on contacts made later, the
recorder's default period; scenes that are not periodic or empty; two materials and materials out of
range; a sphere on a wall. Writes each case's exception (or None) and what it measured.

    YADE_PREFIX=$PWD/build/yade-prefix yade-double -j1 -n -x bench/yade_misuse_trial.py --scene STATE21.yade.gz --json OUT.json
"""
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso importable)

from trueaniso import cli  # noqa: E402

parser = cli.Parser(description=cli.description(__doc__))
parser.add_argument("--scene", required=True, help="a YADE scene at state 21 (yade_cloud_state21.py writes OUTDIR/state21.yade.gz)")
parser.add_argument("--json", required=True, help="where each case's exception and readings are written")
o = cli.parse(parser)
try:
    from yade import O, utils
except ImportError:
    cli.fail("this script runs in YADE with the plugin: YADE_PREFIX=build/yade-prefix yade-double -n -x %s "
             "--scene S.yade.gz --json OUT" % sys.argv[0])
from yade.wrapper import (  # noqa: E402
    Bo1_Sphere_Aabb, Bo1_Wall_Aabb, FabricRecorder, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
    Ig2_Wall_Sphere_ScGeom, InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys,
    Law2_ScGeom_SimplifiedMindlinPhys_Mindlin, NewtonIntegrator, PeriTriaxController, StressProbe,
    TrueTriaxialServo)

SCENE = o.scene
res = {}


def err(f):
    try:
        f()
    except Exception as e:
        return "%s: %s" % (type(e).__name__, str(e).splitlines()[0][:220])
    return None


def setter(o, n, v):
    return lambda: setattr(o, n, v)


nan, inf = float("nan"), float("inf")
# --- construction and assignment
s = TrueTriaxialServo(b=0.5, sigmaZ=140e3)
p = StressProbe()
cases = dict(
    servo_b_2=lambda: TrueTriaxialServo(b=2), servo_sigmaZ_0=lambda: TrueTriaxialServo(sigmaZ=0),
    servo_sigmaZ_neg=lambda: TrueTriaxialServo(sigmaZ=-1e5), servo_b_str=lambda: TrueTriaxialServo(b='0.5'),
    servo_b_assign_str=setter(s, "b", "0.5"), servo_b_assign_2=setter(s, "b", 2.0),
    servo_maxSteps_float=lambda: TrueTriaxialServo(maxSteps=1.5), servo_reached=lambda: TrueTriaxialServo(reached=True),
    servo_reached_assign=setter(s, "reached", True), servo_update=lambda: s.updateAttrs(dict(b=0.2, sigmaZ=-3)),
    probe_axis_w=lambda: StressProbe(axis="w"), probe_axis_2p5=lambda: StressProbe(axis=2.5),
    probe_axis_assign=setter(p, "axis", "q"),
    probe_sign_0=lambda: StressProbe(sign=0), probe_gamma_0=lambda: StressProbe(gammaTarget=0),
    probe_gamma_nan=lambda: StressProbe(gammaTarget=nan), probe_ramp_0=lambda: StressProbe(rampSteps=0),
    probe_settle_0=lambda: StressProbe(settleSteps=0), probe_increment_nan=lambda: StressProbe(increment=nan),
    probe_hold_inf=lambda: StressProbe(holdStress=(1e5, inf, 1e5, 0, 0, 0)),
    probe_hold_5=lambda: StressProbe(holdStress=(1e5, 1e5, 1e5, 0, 0)),
    probe_hold_assign_5=setter(p, "holdStress", (1e5, 1e5, 1e5, 0, 0)),
    probe_sign_float=lambda: StressProbe(sign=1.5),
    fabric_period_0=lambda: FabricRecorder(iterPeriod=0), fabric_period_neg=lambda: FabricRecorder(iterPeriod=-1),
    fabric_assign_0=setter(FabricRecorder(), "iterPeriod", 0),
    ip2_rolling_neg=lambda: Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys(rollingStiffness=-1),
    ip2_rolling_str=lambda: Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys(rollingStiffness="1"),
)
res["construction"] = {k: err(f) for k, f in cases.items()}
res["kept_after_refusals"] = dict(servo_b=s.b, servo_sigmaZ=s.sigmaZ, probe_axis=p.axis, probe_hold=list(p.holdStress))
res["axis_2"] = StressProbe(axis=2).axis
res["fabric_default_period"] = FabricRecorder().iterPeriod



# --- on a YADE user's loaded packing
def load():
    O.load(SCENE)
    O.engines = [e for e in O.engines if type(e).__name__ not in ("FabricRecorder", "TrueTriaxialServo", "StressProbe")]


def insert(e):
    O.engines = O.engines[:-2] + [e] + O.engines[-2:]


def state():
    return dict(frictions=sorted({round(I.phys.tangensOfFrictionAngle, 12) for I in O.interactions if I.isReal}),
                velGrad=[list(O.cell.velGrad[i]) for i in range(3)],
                blocked=sorted({b.state.blockedDOFs for b in O.bodies}))


load()
O.run(2, True)
before = state()
for name, es in (("servo_and_probe", [TrueTriaxialServo(b=0.5, sigmaZ=140e3), StressProbe(axis="z", restrainRotations=True)]),
                 ("probe_and_peritriax", [StressProbe(axis="z", restrainRotations=True), PeriTriaxController(goal=(-1e5,) * 3, stressMask=7)])):
    saved = list(O.engines)
    for e in es:
        insert(e)
    it = O.iter
    e = err(lambda: O.run(5, True))
    res[name] = dict(error=e, unchanged=state() == before, iters=O.iter - it)
    O.engines = saved
# a probe refused by assignment in O.engines, then corrected
probe = StressProbe(axis="z")
insert(probe)
res["probe_sign_assign_in_scene"] = dict(error=err(setter(probe, "sign", 0)), sign=probe.sign, unchanged=state() == before)
O.run(50, True)
res["corrected_probe_runs"] = dict(stage=probe.stage, steps=probe.steps)
# reset mid-probe
probe.reset()
after = state()
res["reset_mid_probe"] = dict(unchanged=after == before, after=after if after != before else None)
O.engines = [e for e in O.engines if e is not probe]
# a hold in part: NaN entries take the stress measured at the start; read after one step, integrator off
newton = O.engines[-1]
newton.dead = True
part = StressProbe(axis="z", holdStress=(nan, 61e3, 139e3, nan, 0.0, 0.0))
insert(part)
O.run(1, True)
gs = utils.getStress()
res["hold_partial"] = dict(held=list(part.heldStress), measured_xx=-gs[0][0], measured_yz=-0.5 * (gs[1][2] + gs[2][1]))
O.engines = [e for e in O.engines if e is not part]
newton.dead = False
part.reset()
res["hold_partial_reset_unchanged"] = state() == before
# loading friction reaches contacts made later: material friction 0.3, servo 0.5, to another state
load()
for m in O.materials:
    m.frictionAngle = math.atan(0.3)
first = {(I.id1, I.id2) for I in O.interactions if I.isReal}
servo = TrueTriaxialServo(b=0.25, sigmaZ=120e3, meanStress=100e3)
insert(servo)
while not (servo.reached or servo.failed):
    O.run(5000, True)
later = [I for I in O.interactions if I.isReal and (I.id1, I.id2) not in first]
res["loading_friction"] = dict(reached=servo.reached, made_later=len(later),
                               frictions=sorted({round(I.phys.tangensOfFrictionAngle, 12) for I in O.interactions if I.isReal}))
# FabricRecorder default period, and against YADE's count
fab = FabricRecorder()
insert(fab)
O.run(150, True)
res["fabric_default"] = dict(records=fab.records, Zm=fab.Zm, yade=utils.avgNumInteractions(skipFree=True), message=fab.message)


# non-periodic and empty scenes
def aperiodic(engine, bodies=True):
    O.reset()
    m = O.materials.append(FrictMat(young=4.14e10, poisson=0.15, density=2500, frictionAngle=0.46))
    if bodies:
        O.bodies.append([utils.sphere((0, 0, 0), 1e-4, material=m), utils.sphere((1.99e-4, 0, 0), 1e-4, material=m)])
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                                 [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()], [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]),
                 engine, NewtonIntegrator(damping=0.4)]
    O.dt = 1e-9
    e = err(lambda: O.run(3, True))
    return dict(error=e, iter=O.iter, frictions=sorted({round(I.phys.tangensOfFrictionAngle, 12) for I in O.interactions if I.isReal}))


res["aperiodic"] = {n: aperiodic(e) for n, e in (("servo", TrueTriaxialServo()), ("probe", StressProbe()), ("fabric", FabricRecorder()))}
O.reset()
O.periodic = True
O.cell.hSize = utils.Matrix3(1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3)
f = FabricRecorder()
O.engines = [f]
e = err(lambda: f())
res["empty_scene"] = dict(error=e, Zm=f.Zm, e=f.voidRatio, message=f.message, meanNormalForce=f.meanNormalForce, NcV36=f.NcOverVEq36)


# materials: a second one, and ones out of range
def pair(m1, m2, wall=False):
    O.reset()
    a, b = O.materials.append(m1), O.materials.append(m2)
    r = 1e-4
    O.bodies.append(utils.sphere((0, 0, 0), r, material=a))
    if wall:
        O.bodies.append(utils.wall(r - 2e-7, axis=0, material=b))
        bo, ig = [Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()], [Ig2_Wall_Sphere_ScGeom()]
    else:
        O.bodies.append(utils.sphere((2 * r - 2e-7, 0, 0), r, material=b))
        bo, ig = [Bo1_Sphere_Aabb()], [Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)]
    for x in O.bodies:
        x.state.blockedDOFs = "xyzXYZ"
    O.engines = [ForceResetter(), InsertionSortCollider(bo), InteractionLoop(ig, [Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys()],
                 [Law2_ScGeom_SimplifiedMindlinPhys_Mindlin()]), NewtonIntegrator(damping=0.4)]
    O.dt = 1e-9
    e = err(lambda: O.run(3, True))
    I = [i for i in O.interactions if i.isReal]
    return dict(error=e, N=I[0].phys.normalForce.norm() if I else None, mu=I[0].phys.tangensOfFrictionAngle if I else None)


def fm(y, nu, a=math.atan(0.5)):
    return FrictMat(young=y, poisson=nu, density=2500, frictionAngle=a)


res["two_materials"] = pair(fm(4.14e10, 0.15), fm(1.8e11, 0.3, math.atan(0.3)))
res["young_nan"] = pair(fm(nan, 0.15), fm(4.14e10, 0.15))
res["poisson_m1"] = pair(fm(4.14e10, -1.0), fm(4.14e10, 0.15))
res["poisson_1"] = pair(fm(4.14e10, 1.0), fm(4.14e10, 0.15))
res["wall"] = pair(fm(4.14e10, 0.15), fm(4.14e10, 0.15), wall=True)
res["process_alive"] = True
print(json.dumps(res))
with open(o.json, "w") as fh:
    json.dump(res, fh, indent=1)
