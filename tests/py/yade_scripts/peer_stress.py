"""A packing made in YADE (makeCloud, then the cell squeezed through O.cell.velGrad until the mean
stress from utils.getStress() reaches P, Hertz-Mindlin law) imported through the bridge: our
Love-Weber stress against YADE's utils.getStress() on the same configuration, the whole tensor.
With SHEAR_RATE > 0 the velGrad also shears the cell (xz and yz at that rate, xy at half of it, and
a spin), so that hSize ends with off-diagonal terms and the stress with shear components.
Usage: yade-double -n -x peer_stress.py N [SHEAR_RATE [P]] OUT.json   (defaults 0 and 50 kPa)
"""
import json
import os
import sys

# under yade-double __file__ names yade itself; the script path is argv[0]
HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, GlobalStiffnessTimeStepper, Vector3, Matrix3, utils  # noqa: E402

from trueaniso import engines as E, yade_bridge  # noqa: E402
from yade_scenes import mindlin_cloud  # noqa: E402

n = int(sys.argv[1])
out = sys.argv[-1]
shear = float(sys.argv[2]) if len(sys.argv) > 3 else 0.0
pressure = float(sys.argv[3]) if len(sys.argv) > 4 else 50e3
mindlin_cloud(n, seed=1, solid_fraction=0.35, extra_engines=[GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.5)])
newton = O.engines[-1]
O.dt = 1e-8
rate = 30.0  # 1/s: inertial number ~1e-3 at 50 kPa for these grains
# a general velocity gradient when shearing: x moves with z and y, y with z, plus a spin about z
O.cell.velGrad = Matrix3(-rate, 0.5 * shear + 0.2 * shear, shear, -0.2 * shear, -rate, shear, 0, 0, -rate)
while -np.trace(np.array(utils.getStress())) / 3 < pressure and O.iter < 400000:
    O.run(500, True)

# Forces at the current positions, at rest. YADE applies a new velGrad at the end of the next
# step, so: zero velGrad, take one step; then zero the velocities and take one step without
# integration, where no tangential increment can arise.
O.cell.velGrad = Matrix3.Zero
O.step()
for b in O.bodies:
    b.state.vel = Vector3(0, 0, 0)
    b.state.angVel = Vector3(0, 0, 0)
newton.dead = True
O.step()
assert np.abs(np.array(O.cell.velGrad)).max() == 0
yade_stress = np.array(utils.getStress())

scene, ids = yade_bridge.scene_from_yade(O)
sim = E.Simulation(scene)
sim.add(E.ContactDetection())
sim.add(E.ContactForces())
sim.run(1)
ours = E.stress(scene)
ours_N = np.sort(scene.contact_arrays()["normal_force"])
ours_N = ours_N[ours_N > 0]
yade_N = np.sort([I.phys.normalForce.norm() for I in O.interactions if I.isReal])
rel = np.linalg.norm(ours + yade_stress) / np.linalg.norm(yade_stress)
with open(out, "w") as f:
    json.dump(dict(n=len(ids), yade_iter=O.iter, yade_stress=yade_stress.tolist(), ours_stress=ours.tolist(),
                   rel_stress=float(rel), max_abs_error=float(np.abs(ours + yade_stress).max()),
                   hSize=np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)]).tolist(),
                   ours_cell=np.asarray(scene.cell).tolist(), ours_orthorhombic=bool(scene.orthorhombic),
                   image_contacts=int(np.count_nonzero(np.any(scene.contact_arrays()["shift"] != 0, axis=1)
                                                       & (scene.contact_arrays()["normal_force"] > 0))), contacts_yade=len(yade_N), contacts_ours=len(ours_N),
                   max_rel_normal_force=float(np.max(np.abs(ours_N - yade_N) / yade_N)) if len(ours_N) == len(yade_N) else None,
                   shear_share=float(np.mean([I.phys.shearForce.norm() / I.phys.normalForce.norm()
                                              for I in O.interactions if I.isReal])),
                   yade_avg_num_interactions=utils.avgNumInteractions(skipFree=True),
                   ours_Zm=E.coordination(scene)["Zm"],
                   # YADE's O.forces are those of the step without integration: the same forces
                   yade_unbalanced=utils.unbalancedForce(), ours_unbalanced=E.unbalanced_force(scene)),
              f, indent=1)
