"""Two clumps in contact, driven kinematically on the same path in YADE (members of
O.bodies.appendClumped, Law2_ScGeom_MindlinPhys_Mindlin, avoidGranularRatcheting off) and in ours:
forces and torques on both clumps compared step by step.
Usage: yade-double -n -x peer_two_clumps.py OUT.json

Clump A (three unequal members) is held; clump B (two unequal members) lies across A's two large
members, approaches them, then slides across them while turning, which loads and turns the
tangential forces of two member contacts at once. Both clumps are asymmetric, so YADE's reference point (its members' summed centroid,
overlaps counted twice) is not our centre of mass: torques are compared about YADE's point,
T_Y = T_ours + (c_ours - c_Y) x F, and body B is driven so that every member moves the same in both.
"""
import json
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(sys.argv[0])), "..", "..", "..", "pyscripts"))
import numpy as np  # noqa: E402
from yade import O, Vector3  # noqa: E402

from trueaniso import clump_shapes, engines as E, yade_clumps  # noqa: E402

out = sys.argv[-1]
r = 1.0e-4
box = 4e-3
dt = 1e-8
c = np.full(3, 0.5 * box)

ours = E.Scene()
ours.shear_modulus, ours.poisson, ours.density, ours.friction = 18e9, 0.15, 2500.0, 0.5
ours.cell_size = ours.cell_ref_size = [box] * 3
# Members in the world frame (units of r): A's two large members side by side along x and a third
# below them; B lies across both, one member above each, so that it touches A at two member pairs.
A_centres = np.array([[0, 0, 0], [1.2, 0, 0], [0.5, 0.9, -0.3]]) * r
A_radii = np.array([1.0, 0.9, 0.7]) * r
B_centres = np.array([[0, 0, 0], [1.1, 0, -0.4]]) * r
B_radii = np.array([1.0, 0.7]) * r
A = E.ClumpTemplate(A_centres, A_radii)
B = E.ClumpTemplate(B_centres, B_radii)


def quat(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[math.cos(angle / 2), math.sin(angle / 2) * axis]


def place(scene, t, where):
    """Add template t so that its members sit at where + the centres it was built from."""
    E.add_clumps(scene, t, (where + t.centroid)[None, :], clump_shapes.quaternion_from_matrix(t.axes)[None, :], [1.0])


place(ours, A, c)
# B starts 0.2 um above contact with A's first member (its second pair is 0.31 um further), and the
# approach then closes 1.2 um.
place(ours, B, c + np.array([0.0, 0.0, 2.0 * r + 2e-7]))
ours.dt = dt
ids, members, report = yade_clumps.yade_clump_scene_from(ours, O, damping=0.0, import_contacts=False)
for i in ids:
    O.bodies[i].state.blockedDOFs = "xyzXYZ"
O.dt = dt

sim = E.Simulation(ours)
sim.add(E.ContactDetection())
sim.add(E.ContactForces())

steps_n, steps_t = 400, 800
rows = []
for k in range(steps_n + steps_t):
    if k < steps_n:
        v, w = np.array([0.0, 0.0, -1.2e-6 / (steps_n * dt)]), np.zeros(3)  # approach: 1.2 um
    else:
        v, w = np.array([1.0e-6, 0.5e-6, 0.0]) / (steps_t * dt), np.array([0.005, 0.01, 0.01]) / (steps_t * dt)
    # YADE: clump B moves with (v, w) about its reference point; its members' velocities are set too,
    # since YADE's contact geometry reads the members' (set by the integrator only after the step).
    b = O.bodies[ids[1]]
    cb = np.array(b.state.pos)
    b.state.vel, b.state.angVel = Vector3(*v), Vector3(*w)
    for mid in b.shape.members:
        m = O.bodies[mid]
        m.state.vel = Vector3(*(v + np.cross(w, np.array(m.state.pos) - cb)))
        m.state.angVel = Vector3(*w)
    # ours: the same member motion about our centre of mass
    vo = v + np.cross(w, ours.positions[1] - cb)
    vel, ang = np.zeros((2, 3)), np.zeros((2, 3))
    vel[1], ang[1] = vo, w
    ours.velocities, ours.angular_velocities = vel, ang
    cy = [np.array(O.bodies[i].state.pos) for i in ids]  # YADE's torques are about these
    O.step()
    sim.run(1)  # forces at the same configuration
    F, T = ours.forces, ours.torques
    row = dict(step=k, contacts=int(np.sum(ours.contact_arrays()["normal_force"] > 0)))
    for j, i in enumerate(ids):
        fy, ty = np.array(O.forces.f(i)), np.array(O.forces.t(i))
        t_about_y = T[j] + np.cross(ours.positions[j] - cy[j], F[j])
        row["f%d" % j] = (fy.tolist(), F[j].tolist())
        row["t%d" % j] = (ty.tolist(), t_about_y.tolist())
    rows.append(row)
    # advance ours exactly as YADE did (blocked DOFs: pos += v dt, ori <- rotation(w dt) ori)
    p = ours.positions
    p[1] += dt * vo
    q = ours.orientations
    angle = np.linalg.norm(w) * dt
    if angle > 0:
        dq = quat(w, angle)
        w0, x0, y0, z0 = dq
        w1, x1, y1, z1 = q[1]
        q[1] = [w0 * w1 - x0 * x1 - y0 * y1 - z0 * z1, w0 * x1 + x0 * w1 + y0 * z1 - z0 * y1,
                w0 * y1 - x0 * z1 + y0 * w1 + z0 * x1, w0 * z1 + x0 * y1 - y0 * x1 + z0 * w1]
    ours.positions = p
    ours.orientations = q

ca = ours.contact_arrays()
live = [r_ for r_ in rows if np.linalg.norm(r_["f1"][0]) > 0]


def rel(key):
    """Largest difference over the path relative to the largest YADE value (a relative error of a
    force that vanishes as a contact opens would be meaningless)."""
    scale = max(np.linalg.norm(r_[key][0]) for r_ in live)
    return float(max(np.linalg.norm(np.subtract(*r_[key])) for r_ in live) / scale)


res = dict(steps=len(rows), steps_in_contact=len(live), report=report,
           steps_two_contacts=sum(1 for r_ in rows if r_["contacts"] >= 2),
           contacts_ours=int(np.sum(ca["normal_force"] > 0)), contacts_yade=sum(1 for I in O.interactions if I.isReal),
           max_rel_force=max(rel("f0"), rel("f1")), max_rel_torque=max(rel("t0"), rel("t1")),
           action_reaction=float(max(np.linalg.norm(np.add(r_["f0"][0], r_["f1"][0])) / np.linalg.norm(r_["f1"][0])
                                     for r_ in live)),
           final_force=live[-1]["f1"], final_torque=live[-1]["t1"],
           shear_share=float(np.linalg.norm(ca["shear_force"][ca["normal_force"] > 0], axis=1).sum()
                             / ca["normal_force"][ca["normal_force"] > 0].sum()))
with open(out, "w") as f:
    json.dump(res, f, indent=1)
