"""The YADE bridge for scenes with clumps (runs only inside yade-double); yade_bridge dispatches
here when a scene has clumps. Conventions as in yade_bridge (total against fluctuation velocities,
compression positive, FrictMat against (G, nu, mu), contacts id1 -> id2 with id2's image shift).

YADE's clumps and ours:
 - YADE's clump is a body with a Clump shape whose member spheres are bodies of their own; the
   clump's state holds its position (reference point), orientation, mass and principal inertia, and
   members sit at relPos in its frame (Clump.members: {member id: (relPos, relOri)}).
 - O.bodies.appendClumped puts the reference point at the members' mass centroid and the frame on
   the principal axes of the members' summed inertia, overlaps counted twice unless discretization
   > 0 (then on a grid). Ours are the union's, from CGAL (engines/clump). On export we write our
   mass and inertia into YADE's clump state; the reference points coincide when the summed and the
   union centroids do (any clump of equal members placed symmetrically, like the dimers and rows
   of docs/specimens.md), the frames when the principal axes do. What differs is reported.
 - On import YADE's clump state is taken as it is (reference point, orientation, mass, inertia:
   the dynamics YADE ran); the solid volume of each clump is the union's (CGAL, cached per shape),
   so the void ratio counts overlaps once.
"""
import math

import numpy as np

from . import clump_shapes, engines
from .yade_convert import (BridgeError, _cell, _check_homo_deform, _contact_rows, _current_velocity_gradient,
                           _interaction_images, _keep_interaction_images, _reference_cell,
                           _scheduled_velocity_gradient, _shared_material, _write_cell, _yade_matrix,
                           contact_law, contacts_made_at_rest, nearest_image_shifts, write_shear_history)


def _quat_wxyz(q):
    axis, angle = q.toAxisAngle()
    s = math.sin(0.5 * angle)
    return [math.cos(0.5 * angle), axis[0] * s, axis[1] * s, axis[2] * s]


def _material(bodies):
    """(G, nu, density, mu) shared by all spheres: yade_convert._shared_material (FrictMat, compared by value)."""
    young, nu, rho, phi = _shared_material(bodies)
    return young / (2.0 * (1.0 + nu)), nu, rho, math.tan(phi)


def check_clumps(O):
    """Everything an import needs from YADE's clumps, or one BridgeError naming the first problem:
    a member listed by a clump that is not in O.bodies (erased) or is not a sphere of that clump,
    a clump member whose clump is gone, a clump heavier than its members (members erased after
    clumping: YADE removes them from the clump but keeps its mass), other shapes.
    Returns (clumps, spheres): YADE bodies in id order."""
    from yade import Sphere
    bodies = [b for b in O.bodies if b is not None]
    clumps = [b for b in bodies if b.isClump]
    spheres = [b for b in bodies if not b.isClump and not b.isClumpMember]
    clump_ids = {b.id for b in clumps}
    for b in bodies:
        if not b.isClump and not isinstance(b.shape, Sphere):
            raise BridgeError("body #%d is a %s; the bridge imports spheres and clumps of spheres"
                                % (b.id, type(b.shape).__name__))
        if b.isClumpMember and b.clumpId not in clump_ids:
            raise BridgeError("body #%d is a member of clump #%d, which is missing" % (b.id, b.clumpId))
    for c in clumps:
        members = c.shape.members
        if not members:
            raise BridgeError("clump #%d has no members" % c.id)
        total = 0.0
        for mid in members:
            m = O.bodies[mid] if 0 <= mid < len(O.bodies) else None
            if m is None or not isinstance(m.shape, Sphere) or m.clumpId != c.id:
                raise BridgeError("clump #%d: member #%d is missing (erased, or not a sphere of this clump)"
                                    % (c.id, mid))
            total += m.state.mass
        if c.state.mass > total * (1 + 1e-9):
            raise BridgeError("clump #%d has mass %.6g but its %d members only %.6g: members are missing "
                                "(erased after clumping?)" % (c.id, c.state.mass, len(members), total))
    return clumps, spheres


def scene_from_yade_clumps(O, import_contacts=True):
    """Our Scene from YADE's clumps and free spheres, periodic cell, material and contact history.
    Returns (scene, ids): ids[k] is the YADE id of our body k (a clump's id for a clump)."""
    h = _cell(O)  # the full cell matrix, sheared or not (yade_bridge.scene_from_yade)
    clumps, spheres = check_clumps(O)
    member_bodies = [O.bodies[mid] for c in clumps for mid in c.shape.members]
    G, nu, rho, mu = _material(member_bodies + spheres)
    s = engines.Scene()
    s.shear_modulus, s.poisson, s.density, s.friction = G, nu, rho, mu
    try:
        s.cell = h
    except ValueError as exc:
        raise BridgeError("the YADE cell cannot be imported: %s" % exc) from None
    ref = _reference_cell(O, h)  # a refusal of YADE's trsf stays one (BridgeError is a ValueError)
    try:
        s.cell_ref = ref
    except ValueError:
        s.cell_ref = h  # no usable reference: strains count from now
    _check_homo_deform(O)
    grad = _current_velocity_gradient(O)
    ids, member_index, vel, ang = [], {}, [], []
    for b in sorted(clumps + spheres, key=lambda b: b.id):
        pos = np.array(b.state.pos)
        if b.isClump:
            mids = sorted(b.shape.members)
            offsets = np.array([list(b.shape.members[i][0]) for i in mids])
            radii = np.array([O.bodies[i].shape.radius for i in mids])
            k = s.add_clump(pos, _quat_wxyz(b.state.ori), offsets, radii, b.state.mass, np.array(b.state.inertia))
        else:
            mids = [b.id]
            k = s.add_sphere(pos, b.shape.radius)
        first = int(s.member_begin[k])
        for j, mid in enumerate(mids):
            member_index[mid] = first + j
        ids.append(b.id)
        vel.append(np.array(b.state.vel) - grad @ pos)
        ang.append(np.array(b.state.angVel))
    s.velocities = np.array(vel)
    s.angular_velocities = np.array(ang)
    s.velocity_gradient = _scheduled_velocity_gradient(O)
    s.dt = O.dt
    if import_contacts:
        rows = _contact_rows(O, member_index)
        if rows:
            m1, m2, sh, nrm, fn, fs = zip(*rows)
            s.set_contact_history(np.array(m1), np.array(m2), np.array(sh, dtype=np.int32), np.array(nrm),
                                  np.array(fn), np.array(fs))
    return s, ids


def yade_clump_scene_from(scene, O, damping=0.2, import_contacts=True, mindlin_ratcheting=False, law="yade"):
    """Rebuild YADE's O from our scene with clumps (O.bodies.appendClumped), with YADE's Hertz-
    Mindlin law or ours (`law`) as in yade_bridge.yade_scene_from. Our mass and inertia are written into YADE's
    clump states. Returns (ids, members, report): ids[k] the YADE id of our body k, members[m] the
    YADE id of our member m, report = dict(max_centre_offset, max_inertia_offdiagonal): the
    distance between YADE's reference point and our centre of mass over our largest member radius,
    and our inertia tensor's largest off-diagonal term in YADE's frame over its largest term
    (0 when YADE's clump frame is ours)."""
    from yade import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                      InteractionLoop, NewtonIntegrator, Vector3, utils)
    Ip2, Law2 = contact_law(law)
    O.reset()
    O.periodic = True
    _write_cell(O, scene.cell, scene.cell_ref)
    G, nu = scene.shear_modulus, scene.poisson
    mat = O.materials.append(FrictMat(young=2.0 * G * (1.0 + nu), poisson=nu, density=scene.density,
                                      frictionAngle=math.atan(scene.friction)))
    begin, mpos, rad = scene.member_begin, scene.member_positions, scene.radii
    pos, q, mass, inertia = scene.positions, scene.orientations, scene.masses, scene.inertia
    vel, ang = scene.velocities, scene.angular_velocities
    ids, members = [], []
    offset, offdiag = 0.0, 0.0
    for k in range(scene.num_bodies):
        spheres = [utils.sphere(Vector3(*mpos[m]), float(rad[m]), material=mat) for m in range(begin[k], begin[k + 1])]
        if len(spheres) == 1:
            i = O.bodies.append(spheres[0])
            members.append(i)
        else:
            i, mids = O.bodies.appendClumped(spheres)
            members.extend(mids)
            st = O.bodies[i].state
            offset = max(offset, np.linalg.norm(np.array(st.pos) - pos[k]) / rad[begin[k]:begin[k + 1]].max())
            # our inertia tensor in YADE's clump frame: its diagonal becomes YADE's inertia
            Ry, Ro = clump_shapes.rotation_matrix(_quat_wxyz(st.ori)), clump_shapes.rotation_matrix(q[k])
            I = Ry.T @ Ro @ np.diag(inertia[k]) @ Ro.T @ Ry
            offdiag = max(offdiag, np.abs(I - np.diag(np.diag(I))).max() / np.abs(I).max())
            st.mass = float(mass[k])
            st.inertia = Vector3(*np.diag(I))
        b = O.bodies[i]
        b.state.vel = Vector3(*vel[k])
        b.state.angVel = Vector3(*ang[k])
        ids.append(i)
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()], label="collider"),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=mindlin_ratcheting)],
                        [Ip2()],
                        [Law2(label="mindlin")]),
        NewtonIntegrator(damping=damping, label="newton"),
    ]
    O.dt = scene.dt if scene.dt > 0 else 1e-8
    if import_contacts:
        contacts_made_at_rest(scene, O, ids, members)  # steps at rest: before the strain rate is set
    O.cell.velGrad = _yade_matrix(scene.velocity_gradient)
    return ids, members, dict(max_centre_offset=offset, max_inertia_offdiagonal=offdiag)


def write_clumps_to_yade(scene, O, ids):
    """Our clump scene's cell, positions, orientations and velocities into YADE's O, bodies matched
    by `ids` (YADE ids of our bodies, as yade_clump_scene_from returned them); members placed at our
    member positions, so O shows the state before YADE's next step moves them. Velocities and
    strain rate follow yade_bridge.write_to_yade's rule."""
    from yade import Quaternion, Vector3
    if ids is None or len(ids) != scene.num_bodies:
        raise BridgeError("ids must list one YADE body per scene body")
    current = _current_velocity_gradient(O)
    before = _interaction_images(O)
    shift = nearest_image_shifts(O, ids, scene.positions, scene.cell)  # as yade_bridge.write_to_yade, a clump's
    _write_cell(O, scene.cell, scene.cell_ref)                          # members with it
    O.cell.velGrad = _yade_matrix(scene.velocity_gradient)
    pos, q, vel, ang = scene.positions + shift, scene.orientations, scene.velocities, scene.angular_velocities
    begin = scene.member_begin
    mpos = scene.member_positions + np.repeat(shift, np.diff(begin), axis=0)
    total = vel + pos @ current.T
    for k, i in enumerate(ids):
        b = O.bodies[i]
        mids = sorted(b.shape.members) if b.isClump else [i]
        if len(mids) != begin[k + 1] - begin[k]:
            raise BridgeError("YADE body #%d has %d members, ours %d" % (i, len(mids), begin[k + 1] - begin[k]))
        b.state.vel = Vector3(*total[k])
        b.state.angVel = Vector3(*ang[k])
        if b.isClump:
            w, x, y, z = q[k]
            b.state.pos = Vector3(*pos[k])
            b.state.ori = Quaternion(w, x, y, z)
            for j, mid in enumerate(mids):
                m = O.bodies[mid]
                m.state.pos = Vector3(*mpos[begin[k] + j])
                m.state.ori = b.state.ori * b.shape.members[mid][1]
        else:
            b.state.pos = Vector3(*pos[k])
    _keep_interaction_images(O, before)  # the members' interactions keep their branches (yade_convert)
    yade_of_member = np.empty(int(begin[-1]), dtype=int)
    for k, i in enumerate(ids):
        b = O.bodies[i]
        yade_of_member[begin[k]:begin[k + 1]] = sorted(b.shape.members) if b.isClump else [i]
    write_shear_history(scene, O, yade_of_member)
