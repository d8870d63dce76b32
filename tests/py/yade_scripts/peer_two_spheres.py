"""Two spheres, normal then tangential loading, driven kinematically: YADE's
Law2_ScGeom_MindlinPhys_Mindlin and our ContactForces evaluated step by step on the same path.
Usage: yade-double -n -x peer_two_spheres.py OUT.json
"""
import json
import os
import sys

# under yade-double __file__ names yade itself; the script path is argv[0]
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))
import numpy as np  # noqa: E402
from yade import O, Vector3  # noqa: E402

from yade_scenes import two_spheres_both  # noqa: E402

out = sys.argv[-1]
r1, r2, delta0 = 1.0e-4, 0.8e-4, 2e-7
box = 2e-3
dt = 1e-8
steps_n, steps_t = 300, 600
vn = 1.5e-6 / (steps_n * dt)      # approach: overlap 2e-7 -> 1.7e-6 m
vt = 2.0e-6 / (steps_t * dt)      # tangential: 2 um, past the Coulomb cap with mu = 0.5

ours, ids, sim = two_spheres_both(r1, r2, delta0, box, dt, 0.5)

rows = []
for k in range(steps_n + steps_t):
    v = [-vn, 0, 0] if k < steps_n else [0, vt, 0]
    O.bodies[ids[1]].state.vel = Vector3(*v)
    O.step()  # YADE: forces at x_k with this velocity, then x_{k+1} = x_k + v dt
    I = O.interactions[ids[0], ids[1]]
    fy = np.array(I.phys.normalForce) + np.array(I.phys.shearForce)
    vel = np.zeros((2, 3))
    vel[1] = v
    ours.velocities = vel
    sim.run(1)       # ours: forces at x_k
    ca = ours.contact_arrays()
    fo = ca["force"][0]
    rows.append(dict(step=k, yade=fy.tolist(), ours=fo.tolist(), yade_ks=I.phys.ks,
                     yade_ratio=I.phys.shearForce.norm() / I.phys.normalForce.norm(),
                     ours_ratio=float(np.linalg.norm(ca["shear_force"][0]) / ca["normal_force"][0]),
                     ours_ks=float(ca["kn"][0]) * 2 * (1 - 0.15) / (2 - 0.15)))
    p = ours.positions
    p[1] += dt * np.array(v)
    ours.positions = p

y = np.array([r["yade"] for r in rows])
o = np.array([r["ours"] for r in rows])
rel = np.linalg.norm(y - o, axis=1) / np.linalg.norm(y, axis=1)
ksr = np.array([abs(r["ours_ks"] / r["yade_ks"] - 1) for r in rows])
with open(out, "w") as f:
    json.dump(dict(max_rel_force=float(rel.max()), max_rel_ks=float(ksr.max()),
                   final_yade=rows[-1]["yade"], final_ours=rows[-1]["ours"],
                   yade_ratio_max=max(r["yade_ratio"] for r in rows),
                   ours_ratio_max=max(r["ours_ratio"] for r in rows),
                   yade_sliding_steps=sum(r["yade_ratio"] > 0.5 * (1 - 1e-9) for r in rows),
                   ours_sliding_steps=sum(r["ours_ratio"] > 0.5 * (1 - 1e-9) for r in rows),
                   steps=len(rows)), f, indent=1)
