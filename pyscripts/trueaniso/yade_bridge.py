r"""Bridge between YADE's ``O`` and our Scene (runs only inside yade-double).

The whole periodic cell crosses both ways: hSize (columns = cell vectors, off-diagonal terms of
a sheared cell included), refHSize and the velocity gradient (velGrad, full 3x3), with the
contacts' image shifts (YADE's cellDist is our shift: the image of id2 is pos2 + hSize cellDist).

Conventions that differ and are converted here:

- YADE's state.vel is the total velocity; ours is the fluctuation about the cell's affine field
  (v_total = v_fluct + velGrad x). A velGrad set in YADE takes effect at its next step (see
  write_to_yade); the bridge reads the scheduled one as our strain rate.
- YADE's getStress() is tension positive; ours is compression positive.
- Material: YADE's FrictMat has (young, poisson, frictionAngle); ours (G, nu, mu) with
  $G = E/(2(1+\nu))$, $\mu = \tan(\text{frictionAngle})$.
- Contacts: YADE's normal points from id1 to id2 and phys.shearForce is the force on id2, as ours;
  id2's image is pos2 + hSize cellDist, as our shift.
"""
import math

import numpy as np

from . import engines, yade_clumps
from .yade_convert import (MATERIAL_FIELDS, BridgeError, _cell, _check_homo_deform, _contact_rows,  # noqa: F401
                           _current_velocity_gradient, _interaction_images, _keep_interaction_images,
                           _reference_cell, _scheduled_velocity_gradient, _shared_material, _write_cell, _yade,
                           _yade_matrix, contact_law, contacts_made_at_rest, nearest_image_shifts, write_shear_history)

__all__ = ["yade_scene_from", "scene_from_yade", "write_to_yade"]


def scene_from_yade(O=None, import_contacts=True):
    """Our Scene from YADE's O: its spheres (or clumps), periodic cell, material and contact history.

    The scene's contacts are evaluated by our law at YADE's positions (`dem.refresh`), so that its
    stress, unbalanced force and stiffness read what they are.

    Args:
        O: YADE's Omega (None: ``yade.O``).
        import_contacts: take YADE's contacts and their shear forces (the contact history).

    Returns:
        (scene, ids): the engines' Scene, and ids[k] the YADE body id of our body k.

    Raises:
        BridgeError: bodies that are not free spheres or clumps, a cell or material the scene cannot
            hold, in one line.

    Example:
        Inside yade-double:

        >>> from yade import O
        >>> from trueaniso import specimen_file, yade_bridge, specimen
        >>> ours, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> _ = yade_bridge.yade_scene_from(ours, O)
        >>> scene, ids = yade_bridge.scene_from_yade(O)
        >>> print("%d spheres, p = %.1f kPa" % (scene.num_bodies, specimen.state(scene)["p"] / 1e3))
        150 spheres, p = 100.0 kPa
    """
    O = O or _yade()
    bodies = [b for b in O.bodies if b is not None]
    _check_free(bodies)
    if any(b.isClump or b.isClumpMember for b in bodies):
        s, ids = yade_clumps.scene_from_yade_clumps(O, import_contacts)
    else:
        s, ids = _spheres_from_yade(O, bodies, import_contacts)
    from . import dem
    dem.refresh(s)
    _check_apart(s, ids)
    return s, ids


def _check_apart(s, ids):
    """Two bodies at one point (distance 0) have a contact without a normal: imported, the stress
    would read NaN until specimen_file.save refused 'non-finite values in c_normal'. Refused here,
    naming them."""
    c = s.contact_arrays()
    apart = ~np.isfinite(c["normal"]).all(axis=1)
    if not s.has_clumps:  # a sphere on another's image (a cell vector away) has a round-off branch, not NaN
        touching = c["normal_force"] > 0
        apart |= touching & (np.linalg.norm(c["branch"], axis=1) < 1e-9 * float(np.max(s.radii)))
    bad = np.flatnonzero(apart)
    if bad.size:
        k = int(bad[0])
        raise BridgeError("bodies #%d and #%d sit at one point (their spheres' centres coincide): a contact "
                          "between them has no direction; move or erase one (%d such contact%s)"
                          % (ids[int(c["body1"][k])], ids[int(c["body2"][k])], bad.size, "" if bad.size == 1 else "s"))


def _check_free(bodies):
    """Our stepper moves every body: a YADE body with blocked DOFs, or not dynamic (a fixed
    sphere), would silently become free. Refused instead."""
    from yade import Sphere
    for b in bodies:
        if b.isClumpMember:
            continue  # its clump carries its state
        if not b.isClump and not isinstance(b.shape, Sphere):
            # Named first: a wall (fixed) is no sphere, and telling it to be freed would be no help.
            raise BridgeError("body #%d is a %s; the bridge imports spheres and clumps of spheres only: erase it "
                              "before the import" % (b.id, type(b.shape).__name__))
        if not b.dynamic or b.state.blockedDOFs:
            raise BridgeError("body #%d is not free (dynamic %s, blockedDOFs %r); trueaniso moves every body: free "
                              "it, or erase it, before the import" % (b.id, b.dynamic, b.state.blockedDOFs))


def _spheres_from_yade(O, bodies, import_contacts):
    from yade import Sphere
    h = _cell(O)
    spheres = [b for b in bodies if isinstance(b.shape, Sphere) and not b.isClumpMember and not b.isClump]
    if len(spheres) != len(bodies):
        raise BridgeError("the bridge imports free spheres only; this scene has %d other bodies"
                          % (len(bodies) - len(spheres)))
    if not spheres:
        raise BridgeError("the YADE scene has no spheres")
    young, poisson, density, friction_angle = _shared_material(spheres)
    s = engines.Scene()
    try:
        s.shear_modulus = young / (2.0 * (1.0 + poisson))
        s.poisson = poisson
        s.density = density
        s.friction = math.tan(friction_angle)
    except (ValueError, ZeroDivisionError) as exc:  # said in our terms ("shear modulus must be > 0") before
        raise BridgeError("the spheres' FrictMat (young %g, poisson %g, density %g, frictionAngle %g) cannot be "
                          "converted: %s" % (young, poisson, density, friction_angle, exc)) from None
    try:
        s.cell = h  # a singular or inverted hSize is refused here, with the engines' message
    except ValueError as exc:
        raise BridgeError("the YADE cell cannot be imported: %s" % exc) from None
    ref = _reference_cell(O, h)  # a refusal of YADE's trsf stays one (BridgeError is a ValueError)
    try:
        s.cell_ref = ref
    except ValueError:
        s.cell_ref = h  # no usable reference: strains count from now
    pos = np.array([[b.state.pos[k] for k in range(3)] for b in spheres])
    radii = np.array([b.shape.radius for b in spheres])
    bad = np.flatnonzero(~np.isfinite(pos).all(axis=1) | ~(np.isfinite(radii) & (radii > 0)))
    if bad.size:  # the engines said 'sphere position must be finite', naming no body
        b = spheres[int(bad[0])]
        raise BridgeError("body #%d has position %s and radius %g: not finite, or not > 0 (%d such bodies)"
                          % (b.id, tuple(b.state.pos), b.shape.radius, bad.size))
    s.add_spheres(pos, radii)
    motion = np.array([[*b.state.vel, *b.state.angVel] for b in spheres])
    bad = np.flatnonzero(~np.isfinite(motion).all(axis=1))
    if bad.size:  # here, naming the body, not at specimen_file.save ('non-finite values in velocities')
        b = spheres[int(bad[0])]
        raise BridgeError("body #%d has velocity %s and angular velocity %s: not finite (%d such bodies)"
                          % (b.id, tuple(b.state.vel), tuple(b.state.angVel), bad.size))
    _check_homo_deform(O)
    grad = _current_velocity_gradient(O)
    vel = np.array([[b.state.vel[k] for k in range(3)] for b in spheres])
    s.velocities = vel - pos @ grad.T  # fluctuations about the field the bodies move with now
    s.velocity_gradient = _scheduled_velocity_gradient(O)  # the one YADE's next step would use
    s.angular_velocities = np.array([[b.state.angVel[k] for k in range(3)] for b in spheres])
    s.dt = O.dt
    ids = [b.id for b in spheres]
    if import_contacts:
        rows = _contact_rows(O, {i: k for k, i in enumerate(ids)})
        if rows:
            m1, m2, sh, nrm, fn, fs = zip(*rows)
            s.set_contact_history(np.array(m1), np.array(m2), np.array(sh, dtype=np.int32),
                                  np.array(nrm), np.array(fn), np.array(fs))
    return s, ids


def write_to_yade(scene, O=None, ids=None):
    """Our scene's positions, velocities, radii, cell and contact shear forces into YADE's O.

    For viewing, export, or to go on in YADE. Each body is written at the image of its position
    nearest YADE's own (our detection wraps bodies into the cell, YADE never does, and a body written
    one cell vector away made YADE's collider miss contacts), and our shear forces go onto YADE's
    interactions of the same pairs (else YADE goes on with its shear history from before our run:
    0.44 % off in stress after 2000 of our steps); a contact YADE does not have yet starts at its
    next step with no shear force.

    YADE adopts a new velGrad only at its next step, adding the jump of the affine field to every
    body's velocity: the velocities written carry YADE's current affine field and the new strain rate
    is scheduled, so that after YADE's next step the bodies move with ours (YADE's cell starts moving
    one step after its bodies: a lag of about 1e-9 of strain in a probe).

    Args:
        scene: the engines' Scene.
        O: YADE's Omega (None: ``yade.O``).
        ids: the YADE body id of each of our bodies (None: 0, 1, ...), as `scene_from_yade` or
            `yade_scene_from` give them.

    Raises:
        BridgeError: ids that do not match O's bodies, or a cell not deformed as YADE's homoDeform 2.

    Example:
        Inside yade-double: our engines load the YADE scene to state 2, then YADE goes on from it.

        >>> from yade import O, utils
        >>> from trueaniso import specimen_file, triaxial, yade_bridge
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> ids = yade_bridge.yade_scene_from(scene, O)
        >>> _ = triaxial.reach_state(scene, b=0.0, sigma_z=110e3)
        >>> yade_bridge.write_to_yade(scene, O, ids)
        >>> O.run(1, True)
        >>> print("YADE's sigma_z = %.0f kPa" % (-utils.getStress()[2, 2] / 1e3))
        YADE's sigma_z = 110 kPa
    """
    O = O or _yade()
    from yade import Vector3
    _check_homo_deform(O)
    if scene.has_clumps:
        return yade_clumps.write_clumps_to_yade(scene, O, ids)
    ids = ids if ids is not None else list(range(scene.num_bodies))
    if len(ids) != scene.num_bodies:
        raise BridgeError("ids must list one YADE body per scene body")
    missing = [i for i in ids if not 0 <= i < len(O.bodies) or O.bodies[i] is None]
    if missing:  # said here, not as an IndexError ('Body id out of range') from deep inside
        raise BridgeError("write_to_yade writes into the YADE bodies the scene came from; O has no body #%d (%d of "
                          "the %d missing): build the scene in YADE with yade_scene_from(scene)"
                          % (missing[0], len(missing), len(ids)))
    current = _current_velocity_gradient(O)
    before = _interaction_images(O)
    shift = nearest_image_shifts(O, ids, scene.positions, scene.cell)
    _write_cell(O, scene.cell, scene.cell_ref)
    O.cell.velGrad = _yade_matrix(scene.velocity_gradient)
    pos, vel, ang, rad = scene.positions + shift, scene.velocities, scene.angular_velocities, scene.radii
    total = vel + pos @ current.T  # YADE's affine field at the position written
    for k, i in enumerate(ids):
        b = O.bodies[i]
        b.state.pos = Vector3(*pos[k])
        b.state.vel = Vector3(*total[k])
        b.state.angVel = Vector3(*ang[k])
        b.shape.radius = float(rad[k])
    _keep_interaction_images(O, before)
    write_shear_history(scene, O, ids)


def yade_scene_from(scene, O=None, damping=0.2, import_contacts=True, mindlin_ratcheting=False, law="yade"):
    r"""Rebuild YADE's O from our scene: bodies, periodic cell, material, contacts and an engine list.

    With YADE's own Hertz-Mindlin law (law="yade"), the peer we compare to; or with our law as a
    YADE class (law="trueaniso": the plugin of engines/yade, loaded with YADE_PREFIX, docs/yade-peer.md).
    YADE's sphere-sphere geometry scales tangential displacements by $(r_1+r_2)/(r_1+r_2-\delta)$ to "avoid
    granular ratcheting" (its default); our law does not, so it is switched off unless asked.

    Args:
        scene: the engines' Scene.
        O: YADE's Omega (None: ``yade.O``); reset first.
        damping: the local damping of YADE's NewtonIntegrator.
        import_contacts: make YADE's interactions of our contacts, with their shear forces.
        mindlin_ratcheting: keep YADE's tangential scaling.
        law: "yade" or "trueaniso".

    Returns:
        list: the YADE ids of our bodies.

    Raises:
        BridgeError: an unknown law, or law="trueaniso" without the plugin.

    Example:
        Inside yade-double:

        >>> from yade import O
        >>> from trueaniso import specimen_file, yade_bridge
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> ids = yade_bridge.yade_scene_from(scene, O, damping=0.4)
        >>> len(O.bodies), O.periodic, type(O.engines[-1]).__name__
        (150, True, 'NewtonIntegrator')
    """
    O = O or _yade()
    from yade import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                      InsertionSortCollider, InteractionLoop, NewtonIntegrator, Vector3, utils)
    Ip2, Law2 = contact_law(law)
    if scene.has_clumps:
        return yade_clumps.yade_clump_scene_from(scene, O, damping, import_contacts, mindlin_ratcheting, law)[0]
    O.reset()
    O.periodic = True
    _write_cell(O, scene.cell, scene.cell_ref)
    G, nu = scene.shear_modulus, scene.poisson
    mat = O.materials.append(FrictMat(young=2.0 * G * (1.0 + nu), poisson=nu, density=scene.density,
                                      frictionAngle=math.atan(scene.friction)))
    ids = []
    pos, vel, ang, rad = scene.positions, scene.velocities, scene.angular_velocities, scene.radii
    for k in range(scene.num_bodies):
        b = utils.sphere(Vector3(*pos[k]), float(rad[k]), material=mat)
        b.state.vel = Vector3(*vel[k])
        b.state.angVel = Vector3(*ang[k])
        ids.append(O.bodies.append(b))
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
        contacts_made_at_rest(scene, O, ids, ids)  # steps YADE at rest: before the strain rate is set
    # Our strain rate, scheduled for YADE's next step (as write_to_yade). The
    # velocities written are fluctuations, the total ones while YADE's current field is zero.
    O.cell.velGrad = _yade_matrix(scene.velocity_gradient)
    return ids
