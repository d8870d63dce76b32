"""A true-triaxial state and its stiffness probes in a YADE session, with the trueaniso engines as
YADE classes (the plugin that ./setup.sh builds into build/yade-prefix):

    YADE_PREFIX=$PWD/build/yade-prefix yade-double -n -x pyscripts/examples/yade_true_triaxial.py [SPECIMEN.npz]

(without -n, YADE's GUI opens; the inspector shows the engines' attributes). The steps:
 1. a specimen consolidated at 100 kPa (a file of prepare_specimen.py; by default the
    repository's 300 spheres, tests/data/spheres-300-s6.npz), imported into YADE with our law;
 2. state 21 of Table C1 (b = 0.5, sigma_z = 140 kPa, p = 100 kPa) with friction 0.5
    (TrueTriaxialServo);
 3. the x, y, z stress probes (StressProbe: sliding suppressed, gamma of Eq. 12 up to 1e-6),
    each starting from the held state;
 4. the fabric B (Eq. 33) and M (Eq. 34) from FabricRecorder.
Printed, and saved to yade_true_triaxial.json and yade_true_triaxial.yade.gz (the scene at the
state, loadable with O.load in a session with the plugin).
"""
import json
import math
import os
import sys

from yade import O
from yade.wrapper import FabricRecorder, StressProbe, TrueTriaxialServo

RHO = 2500.0  # the paper's Table 1
P = 100e3
args = [a for a in sys.argv[1:] if not a.startswith("-")]


def strain_rate(inertial_number, d50):
    """Cell strain rate of inertial number I = rate d50 sqrt(rho/p) (I <= 1e-3: quasi-static)."""
    return inertial_number / (d50 * math.sqrt(RHO / P))


def run_until(engine, done, chunk=2000):
    while not done(engine):
        O.run(chunk, True)


def insert(engine):
    """An engine between InteractionLoop and NewtonIntegrator, where it reads this step's forces."""
    O.engines = O.engines[:-1] + [engine] + O.engines[-1:]


def remove(engine):
    O.engines = [e for e in O.engines if e is not engine]


# 1-2. A specimen consolidated at 100 kPa by our engines (prepare_specimen.py; the repository's
# 300-sphere one by default), imported with our law and a FabricRecorder.
HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path.insert(0, os.path.join(HERE, ".."))
from trueaniso import specimen_file, yade_bridge  # noqa: E402
path = args[0] if args else os.path.join(HERE, "..", "..", "tests", "data", "spheres-300-s6.npz")
scene, _ = specimen_file.load(path)
yade_bridge.yade_scene_from(scene, damping=0.4, law="trueaniso")
insert(FabricRecorder(iterPeriod=500, label="fabric"))
d50 = 2 * sorted(b.shape.radius for b in O.bodies)[len(O.bodies) // 2]
print("specimen %s: %d spheres, d50 %.3g mm" % (os.path.basename(path), len(O.bodies), d50 * 1e3))

fabric = [e for e in O.engines if isinstance(e, FabricRecorder)][0]

# 2. State 21 of Table C1, friction 0.5 (the servo sets it on every contact when it starts).
servo = TrueTriaxialServo(b=0.5, sigmaZ=140e3, meanStress=P, pathRate=10.0, stressTolerance=100.0,
                          maxStrainRate=strain_rate(1e-3, d50), label="servo")
insert(servo)
run_until(servo, lambda s: s.reached or s.failed)
if servo.failed:
    sys.exit("state 21 not reached: " + servo.message)
remove(servo)
hold = servo.finalStress()
print("state 21 held at step %d: stresses (%.1f, %.1f, %.1f) kPa, shear (%.2f, %.2f, %.2f) kPa"
      % ((O.iter,) + tuple(s / 1e3 for s in servo.stress)))
# The fabric at the state: one more step with the recorder due.
fabric.iterPeriod = 1
O.run(1, True)
B = [[fabric.B[i][j] for j in range(3)] for i in range(3)]
fab = dict(Zm=fabric.Zm, void_ratio=fabric.voidRatio, Nc_over_V=fabric.NcOverV, B=B, M=list(fabric.M))
fabric.iterPeriod = 500
O.save("yade_true_triaxial.yade.gz")

# 3. Probes: each starts from the held state and puts it back.
results = dict(state=21, b=0.5, sigma_z=140e3, p=P, steps_to_state=servo.steps, stress=list(servo.stress))
for axis in ("x", "y", "z"):
    probe = StressProbe(axis=axis, holdStress=hold, label="probe")
    insert(probe)
    run_until(probe, lambda s: s.finished, chunk=1000)
    remove(probe)
    if probe.stage != 4:
        sys.exit("probe %s failed: %s" % (axis, probe.message))
    others = [j for j in range(3) if "xyz"[j] != axis]
    results["E_" + axis] = probe.E
    for j in others:
        results["nu_%s%s" % (axis, "xyz"[j])] = probe.nu[j]
    print("probe %s: E = %.1f MPa, nu_%s%s = %.4f, nu_%s%s = %.4f (%d steps)"
          % (axis, probe.E / 1e6, axis, "xyz"[others[0]], probe.nu[others[0]], axis, "xyz"[others[1]],
             probe.nu[others[1]], probe.steps))

# 4. The fabric at the state.
results.update(fab)
print("fabric: Zm = %.3f, e = %.4f, B diagonal = (%.4g, %.4g, %.4g)" % (fab["Zm"], fab["void_ratio"], B[0][0],
                                                                         B[1][1], B[2][2]))
with open("yade_true_triaxial.json", "w") as f:
    json.dump(results, f, indent=1)
print("saved yade_true_triaxial.json and yade_true_triaxial.yade.gz")
