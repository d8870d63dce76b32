"""Two spheres in contact, sphere 2 spun about an axis off the normal, positions fixed: YADE's
Law2_ScGeom_MindlinPhys_Mindlin(includeMoment=True) with Ip2_FrictMat_FrictMat_MindlinPhys(krot,
eta) against our rolling resistance (docs/rolling.md), step by step. YADE's krot is a constant
stiffness and its cap eta R N; at a fixed overlap ours is k_r = beta k_s rbar^2 and eta_r rbar N,
so krot and eta are set to the same numbers. Usage: yade-double -n -x peer_rolling.py OUT.json
"""
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))
import numpy as np  # noqa: E402
from yade import O, Vector3  # noqa: E402

from yade_scenes import two_spheres_both  # noqa: E402

out = sys.argv[-1]
r1, r2, delta0 = 1.0e-4, 0.8e-4, 1e-6
box, dt, steps = 2e-3, 1e-8, 400
beta, eta_r = 0.3, 0.05
spin = np.array([0.0, 3000.0, -2000.0])  # rad/s about y and z, normal along x

ours, ids, sim = two_spheres_both(r1, r2, delta0, box, dt, 1e23, rolling_stiffness=beta, rolling_friction=eta_r)
sim.run(1)  # the contact at rest: its k_s and N fix k_r and the cap
ca = ours.contact_arrays()
N0 = float(ca["normal_force"][0])
ks = float(ca["kn"][0]) * 2 * (1 - 0.15) / (2 - 0.15)
rbar = float(ca["rbar"][0])
kr, cap = beta * ks * rbar ** 2, eta_r * rbar * N0

loop = O.engines[2]
loop.physDispatcher.functors[0].krot = kr
loop.lawDispatcher.functors[0].includeMoment = True
O.step()  # YADE's interaction at rest
I = O.interactions[ids[0], ids[1]]
# YADE's cap is eta times its own radius times N: eta set so that it equals eta_r rbar N.
radius_yade = I.phys.maxBendPl  # with eta = 0 this is 0; read the radius YADE uses instead
loop.physDispatcher.functors[0].eta = 1.0
O.interactions.erase(ids[0], ids[1])
O.step()
I = O.interactions[ids[0], ids[1]]
R_yade = float(I.phys.maxBendPl)  # eta = 1: the lever YADE multiplies eta by
I.phys.maxBendPl = eta_r * rbar  # the same cap, eta_r rbar per unit N

rows = []
O.bodies[ids[1]].state.angVel = Vector3(*spin)
w = np.zeros((2, 3))
w[1] = spin
ours.angular_velocities = w
for k in range(steps):
    O.step()
    sim.run(1)
    I = O.interactions[ids[0], ids[1]]
    sign = 1.0 if I.id1 == ids[0] else -1.0  # YADE's momentBend is on body id2's side
    my = sign * np.array(I.phys.momentBend)
    mo = ours.contact_arrays()["rolling_moment"][0]
    rows.append(dict(yade=my.tolist(), ours=mo.tolist(), yade_kr=float(I.phys.kr),
                     yade_N=float(I.phys.normalForce.norm())))

y = np.array([r["yade"] for r in rows])
o = np.array([r["ours"] for r in rows])
scale = np.maximum(np.linalg.norm(y, axis=1), 1e-300)
with open(out, "w") as f:
    json.dump(dict(steps=steps, kr=kr, cap=cap, R_yade=R_yade, rbar=rbar, yade_kr=rows[0]["yade_kr"],
                   max_rel_moment=float((np.linalg.norm(y - o, axis=1) / scale).max()),
                   max_rel_moment_same_sign=float((np.linalg.norm(y + o, axis=1) / scale).max()),
                   final_yade=rows[-1]["yade"], final_ours=rows[-1]["ours"],
                   capped_steps_yade=int(np.sum(np.linalg.norm(y, axis=1) >= cap * (1 - 1e-9))),
                   capped_steps_ours=int(np.sum(np.linalg.norm(o, axis=1) >= cap * (1 - 1e-9)))), f, indent=1)
