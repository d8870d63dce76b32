"""The bridge both ways: our specimen -> YADE's O -> our scene, and our state written back into O.
Usage: yade-double -n -x bridge_roundtrip.py SPECIMEN.npz OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, utils  # noqa: E402

from trueaniso import dem, engines, specimen_file, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
ours, _ = specimen_file.load(path)
ids = yade_bridge.yade_scene_from(ours, O)            # with our tangential forces
back, ids2 = yade_bridge.scene_from_yade(O)           # and back again, with YADE's
dem.refresh(back)
res = dict(
    positions=float(np.abs(back.positions - ours.positions).max()),
    radii=float(np.abs(back.radii - ours.radii).max()),
    cell=float(np.abs(back.cell - ours.cell).max()),
    stress_rel=float(np.linalg.norm(engines.stress(back) - engines.stress(ours)) / np.linalg.norm(engines.stress(ours))),
    yade_stress_rel=float(np.linalg.norm(-np.array(utils.getStress()) - engines.stress(ours))
                          / np.linalg.norm(engines.stress(ours))),
    contacts=[engines.coordination(ours)["Nc"], engines.coordination(back)["Nc"]])
# Move our scene (a few hundred steps of our dynamics at 0.99 of the cell) and show it in YADE.
c = dem.Chain(ours)
# y moves with z too (a shear rate of 10 /s in the yz plane): the cell written into YADE is sheared
ours.velocity_gradient = np.array([[-20.0, 0.0, 0.0], [0.0, 0.0, 10.0], [0.0, 0.0, 0.0]])
c.run(200)
yade_bridge.write_to_yade(ours, O, ids)
res["written_positions"] = float(np.abs(np.array([list(O.bodies[i].state.pos) for i in ids]) - ours.positions).max())
res["written_cell"] = float(np.abs(np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)]) - ours.cell).max())
res["scale"] = float(ours.radii.max())
res["written_cell_yz"] = float(O.cell.hSize[1][2])
res["written_cell_yz_expected"] = float(ours.cell[1, 2])
# Read what was written back: YADE holds total velocities and velGrad; our fluctuations and
# strain rate must come back unchanged (the affine part x velGrad is added, then removed).
again, _ = yade_bridge.scene_from_yade(O, import_contacts=False)
res["reread_positions"] = float(np.abs(again.positions - ours.positions).max())
res["reread_velocities"] = float(np.abs(again.velocities - ours.velocities).max())
res["velocity_scale"] = float(np.abs(ours.velocities).max() + np.abs(ours.positions @ ours.velocity_gradient.T).max())
res["reread_strain_rate"] = [float(v) for v in np.diag(again.velocity_gradient - ours.velocity_gradient)]
res["reread_velocity_gradient"] = float(np.abs(again.velocity_gradient - ours.velocity_gradient).max())
# One YADE step (its Mindlin law, our state): the scheduled velGrad is adopted and the affine
# field added once, so the fluctuations change only by one step of dynamics (a double-counted
# field would add rate x, ~velocity_scale); YADE's cell starts moving one step later.
h0 = O.cell.hSize[0][0]
O.dt = ours.dt
O.step()
res["cell_first_step"] = float(O.cell.hSize[0][0] - h0)
after, _ = yade_bridge.scene_from_yade(O, import_contacts=False)
res["after_step_strain_rate"] = [float(v) for v in np.diag(after.velocity_gradient)]
# Slope of the velocity change against position along x: 0 if the affine field is added once,
# the strain rate (-20 /s) if it were counted twice. Contact forces add scatter, not a slope.
dv, x = (after.velocities - ours.velocities)[:, 0], ours.positions[:, 0] - ours.positions[:, 0].mean()
res["after_step_affine_slope"] = float(dv @ x / (x @ x))
O.step()
rate = np.diag(ours.velocity_gradient)
res["cell_second_step_rel"] = float((O.cell.hSize[0][0] - h0) / (h0 * ours.dt * rate[0]) - 1.0)
res["strain_rate"] = [float(v) for v in rate]
with open(out, "w") as f:
    json.dump(res, f, indent=1)
