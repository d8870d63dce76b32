"""A packing saved by YADE (yade_save_packing.py) and restored with O.load in this fresh
yade-double, imported through the bridge:
 - our Love-Weber stress against YADE's utils.getStress() on the loaded configuration;
 - our z probe on the imported scene against YADE's own probe (PeriTriaxController, its Mindlin
   law) on the loaded scene, with the same held stresses and increment.
Usage: yade-double -n -x peer_oload.py PACK.yade.gz OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, GlobalStiffnessTimeStepper, NewtonIntegrator, PeriTriaxController, utils  # noqa: E402

from trueaniso import engines, triaxial, yade_adapter, yade_bridge  # noqa: E402
from yade_scenes import yade_user_probe  # noqa: E402

pack, out = sys.argv[1], sys.argv[-1]
O.load(pack)
res = dict(material_ids=sorted({b.material.id for b in O.bodies}))
# The saved interaction forces belong to the positions before the last integration. YADE's forces
# at the loaded positions: one step with the integrator and controllers dead and dt = 0, so that
# no tangential increment arises (what our dem.refresh does on our side). dt = 0 itself gives NaN in
# YADE's law; 1e-20 s makes every increment (velocity x dt) ~1e-20 of its size.
dt = O.dt
moving = [e for e in O.engines if isinstance(e, (NewtonIntegrator, PeriTriaxController, GlobalStiffnessTimeStepper))]
for e in moving:
    e.dead = True
O.dt = 1e-20
O.step()
for e in moving:
    e.dead = False
O.dt = dt
yade_stress = -np.array(utils.getStress())
scene, ids = yade_bridge.scene_from_yade(O)  # evaluated by our law at the loaded positions (no dem.refresh
ours = engines.stress(scene)                   # needed: unevaluated, this would read zero)
res["unbalanced"] = float(engines.unbalanced_force(scene))
res["stiffness"] = [float(v) for v in engines.cell_stiffness(scene)]
res.update(n=len(ids), yade_stress=yade_stress.tolist(), ours_stress=ours.tolist(),
           stress_error=float(np.abs(ours - yade_stress).max()), friction=scene.friction,
           shear_modulus=scene.shear_modulus)

# The probe: both sides hold our measured stresses and add our probe's increment on z. YADE's
# PeriTriaxController holds the cell's shear strains (this packing carries ~10 kPa of shear stress,
# which it never controlled), so ours does the same here (control_shear=False): the same probe.
hold = np.diag(ours).copy()
mine = triaxial.probe(scene, hold, "z", damping=O.engines[-1].damping, control_shear=False)
# YADE's side: its consolidation engines off, a fixed step, friction 1e23 (sliding suppressed).
O.engines = [e for e in O.engines if not isinstance(e, (PeriTriaxController, GlobalStiffnessTimeStepper))]
yade_adapter.set_friction(O, 1e23)
theirs = yade_user_probe(hold, mine["d_stress"][2], axis=2)
res.update(ours=mine, yade=theirs)
with open(out, "w") as f:
    json.dump(res, f, indent=1)
