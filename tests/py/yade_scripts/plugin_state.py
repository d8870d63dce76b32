"""A specimen of ours taken to a true-triaxial state in YADE with the plugin's engines (our law,
TrueTriaxialServo, StressProbe, FabricRecorder), and what the tests compare.

Usage: YADE_PREFIX=... yade-double [-jN] -n -x plugin_state.py SPECIMEN.npz MODE B SIGMA_Z OUT.json
MODE:
  probe        reach the state, probe it with StressProbe on the given axes (z, x, y) and with our
               stepper's probe (triaxial.probe) on the same state imported through yade_bridge;
  save:N:FILE  run the servo N steps, O.save(FILE), then on to the state;
  load:FILE    O.load(FILE) (written by save) and on to the state;
               both record the servo and the cell AFTER_SAVE steps after the save (or the load);
  reach        reach the state only.
The servo runs with path rate 20 Pa a step (the tests' shortcut: 10x the studies' rate).
"""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O  # noqa: E402
from yade.wrapper import FabricRecorder, StressProbe, TrueTriaxialServo  # noqa: E402

from trueaniso import dem, engines, specimen_file, triaxial, yade_bridge  # noqa: E402

path, mode, b, sigma_z, out = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), sys.argv[-1]
DAMPING = 0.4
result = dict(mode=mode)


def servo_engine():
    return [e for e in O.engines if isinstance(e, TrueTriaxialServo)][0]


def insert_before_newton(engine):
    engines = list(O.engines)
    k = [i for i, e in enumerate(engines) if type(e).__name__ == "NewtonIntegrator"][0]
    O.engines = engines[:k] + [engine] + engines[k:]


# Steps after the save (or the load) at which both runs record the servo and the cell: few enough
# that round-off has not grown (the two sum forces in different orders), so the records compare
# to round-off and show any servo state the file did not carry.
AFTER_SAVE = 200


def snapshot():
    return dict(iter=O.iter, steps=servo.steps, stress=list(servo.stress), hSize=[list(r) for r in O.cell.hSize],
                positions=[list(b.state.pos) for b in O.bodies])


def run_to(done, chunk=5000, limit=2_000_000):
    start = O.iter
    while not done() and O.iter - start < limit:
        O.run(chunk, True)


if mode.startswith("load:"):
    O.load(mode.split(":", 1)[1])
    servo = servo_engine()
    result["loaded_at"] = O.iter
    O.run(AFTER_SAVE, True)
    result["after_save"] = snapshot()
else:
    scene, _ = specimen_file.load(path)
    yade_bridge.yade_scene_from(scene, damping=DAMPING, law="trueaniso")
    d50 = 2.0 * float(np.median(scene.radii))
    servo = TrueTriaxialServo(b=b, sigmaZ=sigma_z, meanStress=100e3, pathRate=20.0, stressTolerance=100.0,
                              maxStrainRate=dem.strain_rate_for_inertial_number(1e-3, d50, scene.density, 100e3),
                              label="servo")
    insert_before_newton(servo)
    insert_before_newton(FabricRecorder(iterPeriod=1000, label="fabric"))
    if mode.startswith("save:"):
        _, n, file = mode.split(":", 2)
        O.run(int(n), True)
        result["saved_at"] = O.iter
        O.save(file)
        O.run(AFTER_SAVE, True)
        result["after_save"] = snapshot()

t0 = time.time()
run_to(lambda: servo.reached or servo.failed)
result.update(reached=servo.reached, failed=servo.failed, message=servo.message, iter=O.iter,
              steps=servo.steps, stress=list(servo.stress), goal=list(servo.finalStress()),
              servo_time=time.time() - t0, hSize=[list(r) for r in O.cell.hSize],
              positions=[list(b.state.pos) for b in O.bodies])
fab = [e for e in O.engines if isinstance(e, FabricRecorder)][0]
result["fabric"] = dict(Zm=fab.Zm, B=[list(r) for r in fab.B], NcOverV=fab.NcOverV, voidRatio=fab.voidRatio,
                        records=fab.records)
# FabricRecorder at the held state against our fabric() of the same state imported through the
# bridge: one more step with the recorder due, then the import (at the positions after it).
fab.iterPeriod = 1
O.run(1, True)
mine, _ = yade_bridge.scene_from_yade(O)
f = engines.fabric(mine)
result["fabric_check"] = dict(recorder=dict(Zm=fab.Zm, B=[list(r) for r in fab.B], R=[list(r) for r in fab.R],
                                            H=[list(r) for r in fab.H], M=list(fab.M), e=fab.voidRatio,
                                            NcV=fab.NcOverV, Nc=fab.contacts),
                              ours=dict(Zm=f["Zm"], B=f["B"].tolist(), R=f["R"].tolist(), H=f["H"].tolist(),
                                        M=f["M"].ravel().tolist(), e=f["e"], NcV=f["NcV_count"], Nc=f["Nc"]))

if mode == "probe" and servo.reached:
    hold = np.array(servo.finalStress())
    # Our stepper on the state held in YADE (the contacts and their shear forces carried over).
    ours_scene, _ = yade_bridge.scene_from_yade(O)
    t0 = time.time()
    ours = triaxial.probe(ours_scene, hold, "z", damping=DAMPING)
    result["ours"] = dict(E=ours["E"], nu_zx=ours["nu_zx"], nu_zy=ours["nu_zy"], steps=ours["steps"],
                          time=time.time() - t0)
    # StressProbe in place of the servo.
    O.engines = [e for e in O.engines if not isinstance(e, TrueTriaxialServo)]
    probes = {}
    for axis in ("z", "x", "y"):
        p = StressProbe(axis=axis, holdStress=list(hold), label="probe")
        insert_before_newton(p)
        t0 = time.time()
        run_to(lambda: p.finished, chunk=1000)
        probes[axis] = dict(E=p.E, nu=list(p.nu), stage=p.stage, steps=p.steps, message=p.message,
                            lost=p.lostContacts, gamma=p.gamma, time=time.time() - t0)
        O.engines = [e for e in O.engines if not isinstance(e, StressProbe)]
    result["probes"] = probes
    result["restored_hSize"] = [list(r) for r in O.cell.hSize]

with open(out, "w") as f:
    json.dump(result, f)
