"""The bridge both ways for clumps: our clump specimen -> YADE's O (appendClumped) -> our scene,
our state written back into O, and YADE clumps that lost members refused.
Usage: yade-double -n -x bridge_clumps.py SPECIMEN.npz OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, utils  # noqa: E402

from trueaniso import dem, engines, specimen_file, yade_bridge, yade_clumps  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
ours, _ = specimen_file.load(path)
ids, members, report = yade_clumps.yade_clump_scene_from(ours, O)   # with our tangential forces
back, ids2 = yade_bridge.scene_from_yade(O)                         # dispatches to the clump import
dem.refresh(back)
ca, cb = ours.contact_arrays(), back.contact_arrays()
res = dict(
    report=report, n=ours.num_bodies, ids_same=ids2 == ids,
    yade_clumps=sum(1 for b in O.bodies if b.isClump),
    positions=float(np.abs(back.positions - ours.positions).max()),
    member_positions=float(np.abs(back.member_positions - ours.member_positions).max()),
    scale=float(ours.radii.max()),
    masses=float(np.abs(back.masses / ours.masses - 1).max()),
    inertia=float(np.abs(back.inertia / ours.inertia - 1).max()),
    volumes=float(np.abs(back.volumes / ours.volumes - 1).max()),
    void_ratio=[engines.void_ratio(ours), engines.void_ratio(back)],
    yade_mass_sum_over_union=float(np.mean([sum(O.bodies[m].state.mass for m in O.bodies[i].shape.members)
                                            / O.bodies[i].state.mass for i in ids])),
    stress_rel=float(np.linalg.norm(engines.stress(back) - engines.stress(ours)) / np.linalg.norm(engines.stress(ours))),
    yade_stress_rel=float(np.linalg.norm(-np.array(utils.getStress()) - engines.stress(ours))
                          / np.linalg.norm(engines.stress(ours))),
    contacts=[int(np.sum(ca["normal_force"] > 0)), int(np.sum(cb["normal_force"] > 0)),
              sum(1 for I in O.interactions if I.isReal)])
# Our dynamics moves the scene; write it into O and read it back.
c = dem.Chain(ours)
ours.strain_rate = [-20.0, 0.0, 0.0]
c.run(200)
yade_bridge.write_to_yade(ours, O, ids)
res["written_member_positions"] = float(np.abs(np.array([list(O.bodies[m].state.pos) for m in members])
                                               - ours.member_positions).max())
again, _ = yade_bridge.scene_from_yade(O, import_contacts=False)
res["reread_positions"] = float(np.abs(again.positions - ours.positions).max())
res["reread_orientations"] = float(np.abs(np.abs(np.sum(again.orientations * ours.orientations, axis=1)) - 1).max())
res["reread_velocities"] = float(np.abs(again.velocities - ours.velocities).max())
res["velocity_scale"] = float(np.abs(ours.velocities).max() + np.abs(ours.strain_rate[0] * ours.positions).max())
res["reread_angular_velocities"] = float(np.abs(again.angular_velocities - ours.angular_velocities).max())
res["angular_velocity_scale"] = float(np.abs(ours.angular_velocities).max())
# YADE runs the imported clumps: one step of its dynamics keeps every member at rigid distance.
O.dt = ours.dt
O.run(20, True)
rigid = 0.0
for i in ids:
    b = O.bodies[i]
    for m, (rel, _) in b.shape.members.items():
        placed = np.array(b.state.pos) + np.array(b.state.ori * rel)
        rigid = max(rigid, float(np.linalg.norm(placed - np.array(O.bodies[m].state.pos))))
res["yade_rigid_members"] = rigid
# A clump that lost a member after clumping (YADE removes it from the clump, keeps the mass).
victim = sorted(O.bodies[ids[0]].shape.members)[0]
O.bodies.erase(victim)
try:
    yade_bridge.scene_from_yade(O)
    res["missing_member_error"] = None
except yade_bridge.BridgeError as exc:
    res["missing_member_error"] = str(exc)
with open(out, "w") as f:
    json.dump(res, f, indent=1)
