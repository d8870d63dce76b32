"""The same specimen state probed on z three ways:
 ours   - our StressProbe on our stepper;
 yade   - as a YADE user would: YADE's Mindlin law and NewtonIntegrator, friction 1e23, the
          state relaxed then the z stress raised by the same increment with PeriTriaxController;
 adapter- our StressProbe driving YADE's cell through the PyRunner adapter.
Usage: yade-double -n -x peer_probe.py SPECIMEN.npz OUT.json
"""
import json
import math
import os
import sys
import time

# under yade-double __file__ names yade itself; the script path is argv[0]
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
import numpy as np  # noqa: E402
from yade import O, PeriTriaxController, utils  # noqa: E402

from trueaniso import dem, engines, specimen_file, triaxial, yade_adapter, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
scene, _ = specimen_file.load(path)
hold = np.diag(engines.stress(scene)).copy()
damping = 0.4

# ours
ours = triaxial.probe(scene, hold, "z", damping=damping)
inc = ours["d_stress"][2]


def yade_state():
    s, _ = specimen_file.load(path)
    ids = yade_bridge.yade_scene_from(s, O, damping=damping)
    yade_adapter.set_friction(O, 1e23)
    return s


def log_strain(ref):
    h = np.array([O.cell.hSize[k][k] for k in range(3)])
    return -np.log(h / ref)


# YADE's own way
yade_state()
ref_h = np.array([O.cell.hSize[k][k] for k in range(3)])
t0 = time.time()
# Stress every step (globUpdate=1; YADE extrapolates it in between otherwise) and a relative
# tolerance of 1e-5 (1 Pa at 100 kPa, 0.3 % of the ~300 Pa increment); with the defaults (3e-5,
# 5) or 1e-6 the controller reaches its goal late or never.
triax = PeriTriaxController(goal=tuple(-hold), stressMask=7, relStressTol=1e-5, absStressTol=1e3, globUpdate=1,
                            maxUnbalanced=1e-5, maxStrainRate=(10, 10, 10), doneHook="O.pause()", label="triax")
O.engines = O.engines[:-1] + [triax] + O.engines[-1:]
O.run(400_000, True)
relax_steps = O.iter
s0 = -np.diag(np.array(utils.getStress()))
e0 = log_strain(ref_h)
triax.goal = tuple(-(hold + np.array([0, 0, inc])))
start = O.iter
O.run(400_000, True)
ds = -np.diag(np.array(utils.getStress())) - s0
de = log_strain(ref_h) - e0
yade = dict(E=float(ds[2] / de[2]), nu_zx=float(-de[0] / de[2]), nu_zy=float(-de[1] / de[2]),
            d_stress=ds.tolist(), d_strain=de.tolist(), relax_steps=int(relax_steps),
            probe_steps=int(O.iter - start), wall_time=time.time() - t0, dt=O.dt)

# our probe through the adapter, YADE's dynamics
s = yade_state()
t0 = time.time()
probe = engines.StressProbe()
probe.axis, probe.sign = 2, 1
probe.max_strain_rate = 10.0
probe.begin(hold)
yade_adapter.attach(probe, engines.cell_stiffness(s))
yade_adapter.run_until_done(probe, O)
adapter = dict(E=float(probe.young_modulus), nu_zx=float(probe.poisson_ratio(0)), nu_zy=float(probe.poisson_ratio(1)),
               stage=probe.stage, steps=int(probe.steps), wall_time=time.time() - t0, d_stress=probe.d_stress.tolist())

with open(out, "w") as f:
    json.dump(dict(n=scene.num_bodies, increment=inc, ours=ours, yade=yade, adapter=adapter), f, indent=1)
