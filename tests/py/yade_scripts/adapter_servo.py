"""Our TrueTriaxialServo driving YADE's own simulation (Mindlin law, NewtonIntegrator, mu = 0.5)
through the PyRunner adapter, to state 19 (b = 0.5, sigma_z = 120 kPa); YADE's getStress() at the end.
Usage: yade-double -n -x adapter_servo.py SPECIMEN.npz OUT.json
"""
import json
import os
import sys
import time

# under yade-double __file__ names yade itself; the script path is argv[0]
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
import numpy as np  # noqa: E402
from yade import O, utils  # noqa: E402

from trueaniso import dem, engines, specimen_file, yade_adapter, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
scene, _ = specimen_file.load(path)
yade_bridge.yade_scene_from(scene, O, damping=0.4)
servo = engines.TrueTriaxialServo()
servo.set_goal(0.5, 120e3)
servo.stress_tolerance = 100.0
servo.unbalanced_tolerance = 1e-4
servo.max_strain_rate = dem.strain_rate_for_inertial_number(1e-3, 0.195e-3, 2500, 1e5)
t0 = time.time()
yade_adapter.attach(servo, engines.cell_stiffness(scene))
yade_adapter.run_until_done(servo, O, max_steps=400000)
stress = -np.diag(np.array(utils.getStress()))
with open(out, "w") as f:
    json.dump(dict(status=servo.status, steps=int(servo.steps), goal=servo.goal_stresses.tolist(),
                   yade_stress=stress.tolist(), unbalanced=utils.unbalancedForce(), overshoot=servo.overshoot.tolist(),
                   wall_time=time.time() - t0), f, indent=1)
