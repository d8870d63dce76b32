"""Local non-viscous damping side by side with YADE's NewtonIntegrator(damping=0.4): two free
spheres thrown against each other obliquely (normal and tangential force, torques), integrated
by both codes from the same state with the same time step; positions and velocities compared
step by step.
Usage: yade-double -n -x peer_damping.py OUT.json
"""
import json
import os
import sys

# under yade-double __file__ names yade itself; the script path is argv[0]
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
import numpy as np  # noqa: E402
from yade import O  # noqa: E402

from trueaniso import dem, engines as E, yade_bridge  # noqa: E402

out = sys.argv[-1]
damping, dt, steps = 0.4, 2e-9, 3000
r1, r2 = 1.0e-4, 0.8e-4
box = 2e-3

ours = E.Scene()
ours.shear_modulus, ours.poisson, ours.density, ours.friction = 18e9, 0.15, 2500.0, 0.5
ours.cell_size = ours.cell_ref_size = [box] * 3
c = np.full(3, 0.5 * box)
ours.add_spheres(np.array([c, c + [r1 + r2 - 1e-6, 0.3e-6, 0]]), np.array([r1, r2]))
ours.velocities = np.array([[0.02, -0.01, 0.005], [-0.03, 0.015, 0.0]])
ours.dt = dt
dem.refresh(ours)
ids = yade_bridge.yade_scene_from(ours, O, damping=damping)
O.dt = dt

undamped = ours.copy()  # the same throw without damping: shows the damping matters here
chain = dem.Chain(ours, damping=damping)
chain.timestep.dead = True  # the same fixed dt in both codes
ours.dt = dt

scale_x, scale_v, scale_w = r1, 0.03, 0.0
dx = dv = dw = 0.0
in_contact = 0
for k in range(steps):
    O.step()
    chain.run(1)
    yp = np.array([list(O.bodies[i].state.pos) for i in ids])
    yv = np.array([list(O.bodies[i].state.vel) for i in ids])
    yw = np.array([list(O.bodies[i].state.angVel) for i in ids])
    dx = max(dx, float(np.abs(yp - ours.positions).max()))
    dv = max(dv, float(np.abs(yv - ours.velocities).max()))
    dw = max(dw, float(np.abs(yw - ours.angular_velocities).max()))
    scale_w = max(scale_w, float(np.abs(yw).max()))
    in_contact += sum(1 for I in O.interactions if I.isReal)
plain = dem.Chain(undamped, damping=0.0)
plain.timestep.dead = True
undamped.dt = dt
plain.run(steps)
final_v = float(np.abs(ours.velocities).max())
with open(out, "w") as f:
    json.dump(dict(steps=steps, max_position_diff=dx, max_velocity_diff=dv, max_angular_velocity_diff=dw,
                   radius=r1, velocity_scale=scale_v, angular_velocity_scale=scale_w,
                   final_speed=final_v, undamped_final_speed=float(np.abs(undamped.velocities).max()),
                   steps_in_contact=in_contact), f, indent=1)
