"""The same specimen state probed on z three ways, each holding the cell's shear strains as YADE's
PeriTriaxController does (control_shear=False; the full-cell probe holds the shear stresses
instead, compared with the adapter in adapter_probe_restore.py):
 ours   - our StressProbe on our stepper;
 yade   - as a YADE user would: YADE's Mindlin law and NewtonIntegrator, friction 1e23, the
          state relaxed then the z stress raised by the same increment with PeriTriaxController;
 adapter- our StressProbe driving YADE's cell through the PyRunner adapter.
Usage: yade-double -n -x peer_probe.py SPECIMEN.npz OUT.json
"""
import json
import os
import sys
import time

# under yade-double __file__ names yade itself; the script path is argv[0]
HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O  # noqa: E402

from trueaniso import engines, specimen_file, triaxial, yade_adapter, yade_bridge  # noqa: E402
from yade_scenes import yade_user_probe  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
scene, _ = specimen_file.load(path)
hold = np.diag(engines.stress(scene)).copy()
damping = 0.4

# ours
ours = triaxial.probe(scene, hold, "z", damping=damping, control_shear=False)
inc = ours["d_stress"][2]


def yade_state():
    s, _ = specimen_file.load(path)
    yade_bridge.yade_scene_from(s, O, damping=damping)
    yade_adapter.set_friction(O, 1e23)
    return s


# YADE's own way
yade_state()
yade = yade_user_probe(hold, inc, axis=2)

# our probe through the adapter, YADE's dynamics
s = yade_state()
t0 = time.time()
probe = engines.StressProbe()
probe.axis, probe.sign = 2, 1
probe.control_shear = False
probe.max_strain_rate = 10.0
probe.begin(hold)
yade_adapter.attach(probe, engines.cell_stiffness(s))
yade_adapter.run_until_done(probe, O)
adapter = dict(E=float(probe.young_modulus), nu_zx=float(probe.poisson_ratio(0)), nu_zy=float(probe.poisson_ratio(1)),
               stage=probe.stage, steps=int(probe.steps), wall_time=time.time() - t0, d_stress=probe.d_stress.tolist())

with open(out, "w") as f:
    json.dump(dict(n=scene.num_bodies, increment=inc, ours=ours, yade=yade, adapter=adapter), f, indent=1)
