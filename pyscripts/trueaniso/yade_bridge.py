"""Bridge between YADE's ``O`` and our Scene (runs only inside yade-double).

The whole periodic cell crosses both ways: hSize (columns = cell vectors, off-diagonal terms of
a sheared cell included), refHSize and the velocity gradient (velGrad, full 3x3), with the
contacts' image shifts (YADE's cellDist is our shift: the image of id2 is pos2 + hSize cellDist).

Conventions that differ and are converted here:
 - YADE's state.vel is the total velocity; ours is the fluctuation about the cell's affine field
   (v_total = v_fluct + velGrad x). A velGrad set in YADE takes effect at its next step (see
   write_to_yade); the bridge reads the scheduled one as our strain rate.
 - YADE's getStress() is tension positive; ours is compression positive.
 - Material: YADE's FrictMat has (young, poisson, frictionAngle); ours (G, nu, mu) with
   G = E/(2(1+nu)), mu = tan(frictionAngle).
 - Contacts: YADE's normal points from id1 to id2 and phys.shearForce is the force on id2, as ours;
   id2's image is pos2 + hSize cellDist, as our shift.
"""
import math

import numpy as np

from . import engines


class BridgeError(ValueError):
    pass


def _yade():
    try:
        import yade  # noqa: F401
        from yade import O
    except ImportError:
        raise BridgeError("the YADE bridge runs inside yade-double (yade-double -n -x script.py)") from None
    return O


def _matrix(m):
    return np.array([[m[i][j] for j in range(3)] for i in range(3)])


def _cell(O):
    """YADE's hSize (3x3, sheared or not), refused if the scene is not periodic."""
    if not O.periodic:
        raise BridgeError("the YADE scene is not periodic (O.periodic = False)")
    return _matrix(O.cell.hSize)


def _yade_matrix(m):
    from yade import Matrix3
    return Matrix3(*[float(v) for v in np.asarray(m, dtype=float).ravel()])


def scene_from_yade(O=None, import_contacts=True):
    """Our Scene from YADE's spheres (or clumps), periodic cell, material and (optionally) contact
    history, with its contacts evaluated by our law at YADE's positions (dem.refresh): before,
    the scene came back unevaluated, and its stress, unbalanced force and stiffness read exactly
    zero until the caller refreshed it (a servo given that stiffness never converged).

    Returns (scene, ids): ids[k] is the YADE body id of our body k.
    """
    O = O or _yade()
    bodies = [b for b in O.bodies if b is not None]
    _check_free(bodies)
    if any(b.isClump or b.isClumpMember for b in bodies):
        from . import yade_clumps
        s, ids = yade_clumps.scene_from_yade_clumps(O, import_contacts)
    else:
        s, ids = _spheres_from_yade(O, bodies, import_contacts)
    from . import dem
    dem.refresh(s)
    _check_apart(s, ids)
    return s, ids


def _check_apart(s, ids):
    """Two bodies at one point (distance 0) have a contact without a normal: the import returned
    and the stress read NaN until specimen_file.save refused 'non-finite values in c_normal' (an
    outside try). Refused here, naming them."""
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
            # Named first: a wall (fixed) was told to be freed, then refused as not a sphere (an outside try).
            raise BridgeError("body #%d is a %s; the bridge imports spheres and clumps of spheres only: erase it "
                              "before the import" % (b.id, type(b.shape).__name__))
        if not b.dynamic or b.state.blockedDOFs:
            raise BridgeError("body #%d is not free (dynamic %s, blockedDOFs %r); trueaniso moves every body: free "
                              "it, or erase it, before the import" % (b.id, b.dynamic, b.state.blockedDOFs))


def _reference_cell(O, h):
    """The cell at zero strain: YADE's motion trsf undone, trsf^-1 hSize. YADE's refHSize is not it
    after a flipCell (hSize changes, refHSize and trsf do not), which read as a shear that never
    happened (gamma_xy 0.997 on a cell only compressed); our Cell remaps the reference on a flip
    so that strains are the motion's alone (core/Cell.hpp), and YADE's strains are trsf's."""
    trsf = _matrix(O.cell.trsf)
    det = np.linalg.det(trsf) if np.all(np.isfinite(trsf)) else float("nan")
    if not det > 1e-6:  # NaN, singular, a reflection or a volume shrunk a millionfold: no motion of a cell
        # Before, strains then counted from now without a word (an outside try set trsf by hand).
        raise BridgeError("YADE's cell.trsf (determinant %g) is no motion of the cell, so its strain is undefined; "
                          "set O.cell.trsf (the identity counts strains from now)" % det)
    return np.linalg.solve(trsf, h)


def _write_cell(O, cell, cell_ref):
    """hSize, and the strain with it: setting hSize resets YADE's refHSize to it (leaving trsf),
    which lost our strain on the way out. refHSize and trsf = hSize refHSize^-1 are set after it."""
    O.cell.hSize = _yade_matrix(cell)
    O.cell.refHSize = _yade_matrix(cell_ref)
    O.cell.trsf = _yade_matrix(np.asarray(cell) @ np.linalg.inv(cell_ref))


def _contact_rows(O, index):
    """(member1, member2, cellDist, normal, |N|, shear force) of YADE's real interactions, indices
    mapped by `index`. Their forces are the history of YADE's Hertz-Mindlin law only: another law's
    (a linear FrictPhys, ViscEl) would be carried on as if they were ours, so those are refused."""
    rows = []
    for I in O.interactions:
        if not I.isReal:
            continue
        kind = type(I.phys).__name__
        if kind not in ("MindlinPhys", "SimplifiedMindlinPhys"):
            raise BridgeError("interaction %d-%d has %s: its forces come from another contact law than Hertz-Mindlin "
                              "(Ip2_FrictMat_FrictMat_MindlinPhys, or ours from the trueaniso YADE plugin: "
                              "Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys); import the positions only "
                              "(import_contacts=False) to evaluate them with ours" % (I.id1, I.id2, kind))
        # MindlinPhys also carries the Mindlin variants the paper's law has not: viscous damping
        # (betan, betas), adhesion (gamma), rolling and twisting moments (krot, ktwist). Their forces
        # passed the class check (adhesion: 4.8 kPa in YADE read 97 kPa here; an outside try).
        extras = [a for a in ("betan", "betas", "adhesionForce", "kr", "ktw") if float(getattr(I.phys, a, 0.0)) != 0.0]
        if extras:
            raise BridgeError("interaction %d-%d has YADE's Mindlin law with %s != 0 (damping, adhesion or moments the "
                              "paper's law has not); import the positions only (import_contacts=False) to evaluate "
                              "them with ours" % (I.id1, I.id2, ", ".join(extras)))
        n = I.geom.normal
        rows.append((index[I.id1], index[I.id2], [I.cellDist[k] for k in range(3)], [n[k] for k in range(3)],
                     I.phys.normalForce.norm(), [I.phys.shearForce[k] for k in range(3)]))
    return rows


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
    if bad.size:  # before: imported, then specimen_file.save refused 'non-finite values in velocities'
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


MATERIAL_FIELDS = ("young", "poisson", "density", "frictionAngle")


def _shared_material(spheres):
    """(young, poisson, density, frictionAngle) common to all spheres, or BridgeError.

    Materials are compared by value, not by identity: YADE hands out a new Python wrapper at
    every access to b.material, and a scene restored by O.load has fresh material objects
    (b.material.id may even be the same for different ones). The law sees only these values."""
    values = set()
    for b in spheres:
        m = b.material
        # FrictMat itself: its subclasses (ViscElMat, CohFrictMat, ...) carry the same fields for
        # other laws, and were converted without a word (ViscEl's 50 kPa read 226 kPa here).
        if type(m).__name__ != "FrictMat":
            raise BridgeError("body %d has a %s material; the bridge converts FrictMat (young, poisson, density, "
                              "frictionAngle) to the paper's Hertz-Mindlin law only" % (b.id, type(m).__name__))
        value = tuple(float(getattr(m, k)) for k in MATERIAL_FIELDS)
        if not all(math.isfinite(v) for v in value):  # NaN != NaN: every sphere counted as its own material
            raise BridgeError("body %d's FrictMat has %s: not finite" % (b.id, ", ".join(
                "%s %g" % (k, v) for k, v in zip(MATERIAL_FIELDS, value) if not math.isfinite(v))))
        values.add(value)
    if len(values) != 1:
        raise BridgeError("all spheres must share one material (young, poisson, density, frictionAngle); "
                          "this scene has %d different ones" % len(values))
    return values.pop()


def _check_homo_deform(O):
    if not O.periodic:  # O.cell is None: an AttributeError traceback before
        raise BridgeError("write_to_yade writes into a periodic scene that holds the bodies (ids) already; "
                          "this O is not periodic: build the scene in YADE with yade_scene_from(scene)")
    if O.cell.homoDeform != 2:
        raise BridgeError("the bridge converts velocities for YADE's default O.cell.homoDeform = 2 "
                          "(total velocities); this scene has %d" % O.cell.homoDeform)


def _current_velocity_gradient(O):
    """The velGrad YADE's bodies move with now (O.cell.velGrad), not a pending one."""
    return np.array([[O.cell.velGrad[i][j] for j in range(3)] for i in range(3)])


def _scheduled_velocity_gradient(O):
    """The velGrad YADE's next step uses (full 3x3): setting O.cell.velGrad only schedules it
    (nextVelGrad) and YADE's NewtonIntegrator adopts it at the next step."""
    return _matrix(O.cell.nextVelGrad if O.cell.velGradChanged else O.cell.velGrad)


def write_to_yade(scene, O=None, ids=None):
    """Positions, velocities, radii, cell and the contacts' shear forces of our scene into YADE's O
    (for viewing, export, or to continue in YADE).

    Each body is written at the image of its position nearest YADE's own: our detection wraps
    bodies into the cell, YADE never does, and a body written one cell vector away made YADE's
    collider miss contacts later (an outside try: 2 of 314 after 1500 steps). Our shear forces go
    onto YADE's interactions of the same pairs: before, YADE went on with its shear history from
    before our run (0.44 % off in stress after 2000 of our steps). A contact YADE does not have yet
    starts at its next step with no shear force.

    YADE adopts a new velGrad only at its next step, and then adds the jump of the affine field,
    (new - current velGrad) x, to every body's velocity (homoDeform = 2). So the velocities
    written carry YADE's current affine field, and the new strain rate is scheduled: after
    YADE's next step the bodies move with ours, v + rate x. YADE's own rule makes its cell start
    moving one step later than its bodies (a lag of rate * dt of strain, ~1e-9 in a probe).
    """
    O = O or _yade()
    from yade import Vector3
    _check_homo_deform(O)
    if scene.has_clumps:
        from . import yade_clumps
        return yade_clumps.write_clumps_to_yade(scene, O, ids)
    ids = ids if ids is not None else list(range(scene.num_bodies))
    if len(ids) != scene.num_bodies:
        raise BridgeError("ids must list one YADE body per scene body")
    missing = [i for i in ids if not 0 <= i < len(O.bodies) or O.bodies[i] is None]
    if missing:  # an IndexError ('Body id out of range') from deep inside before (a second outside try)
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


def nearest_image_shifts(O, ids, positions, cell):
    """The whole cell vectors that bring each of our positions (bodies ids[k] in YADE) nearest
    YADE's own position of that body."""
    yade = np.array([[O.bodies[i].state.pos[k] for k in range(3)] for i in ids])
    n = np.rint(np.linalg.solve(cell, (yade - positions).T)).T
    return n @ np.asarray(cell).T


def write_shear_history(scene, O, yade_of_member, every=False):
    """Our contacts' shear forces onto YADE's real interactions of the same member pairs
    (yade_of_member[m]: YADE id of our member sphere m), signed for YADE's id1 -> id2. With
    `every`, each of our contacts must have one (a scene just built from ours); without, one YADE
    has not made yet is left to its collider's next step."""
    from yade import Vector3
    c = scene.contact_arrays()
    for k in np.nonzero(c["normal_force"] > 0)[0]:
        i1, i2 = int(yade_of_member[c["member1"][k]]), int(yade_of_member[c["member2"][k]])
        I = O.interactions[i1, i2]
        if I is None or not I.isReal:
            if every:
                raise BridgeError("contact of #%d-#%d not found by YADE's collider" % (i1, i2))
            continue
        fs = (1.0 if I.id1 == i1 else -1.0) * c["shear_force"][k]
        I.phys.shearForce = Vector3(*fs)
        if type(I.phys).__name__ == "SimplifiedMindlinPhys":
            # our law in YADE carries the force from the normal it was last evaluated at
            I.phys.prevNormal = Vector3(I.geom.normal)
            I.phys.loaded = True
        else:
            I.phys.shearElastic = Vector3(*fs)


def _interaction_images(O):
    """Every YADE interaction's branch, pos2 + hSize cellDist - pos1, before our state is written."""
    if not O.periodic:
        return []
    h = _cell(O)
    out = []
    for I in O.interactions:
        if O.bodies[I.id1] is None or O.bodies[I.id2] is None:
            continue
        p1, p2 = O.bodies[I.id1].state.pos, O.bodies[I.id2].state.pos
        cd = np.array([I.cellDist[k] for k in range(3)])
        out.append((I, cd, np.array([p2[k] - p1[k] for k in range(3)]) + h @ cd))
    return out


def _keep_interaction_images(O, before):
    """After our positions and cell are written, each YADE interaction gets the cellDist that keeps
    its branch: cellDist = round(hSize^-1 (branch - (pos2 - pos1))). Bodies are written at the
    images nearest YADE's (nearest_image_shifts), so this changes cellDist where our detection
    flipped the cell (hSize M, the same periodic medium, core/Cell.hpp) and where a body crossed
    the cell in our run. Before, bodies were written wrapped and only a flip was remapped: 313
    contacts became 251 on a scene imported and written straight back (an outside try). Our motion
    since (far below half a cell) does not change the rounding."""
    if not before:
        return
    from yade import Vector3i
    inverse = np.linalg.inv(_cell(O))
    for I, cd, branch in before:
        if O.bodies[I.id1] is None or O.bodies[I.id2] is None:
            continue
        p1, p2 = O.bodies[I.id1].state.pos, O.bodies[I.id2].state.pos
        new = np.rint(inverse @ (branch - np.array([p2[k] - p1[k] for k in range(3)]))).astype(int)
        if np.any(new != cd):
            I.cellDist = Vector3i(*[int(v) for v in new])


def yade_scene_from(scene, O=None, damping=0.2, import_contacts=True, mindlin_ratcheting=False, law="yade"):
    """Rebuild YADE's O from our scene, with YADE's own Hertz-Mindlin law (law="yade"): the peer we
    compare to; or, with law="trueaniso", with our law as a YADE class (the plugin of engines/yade,
    loaded through YADE_PREFIX: docs/yade-peer.md).

    YADE's sphere-sphere geometry scales tangential displacements by (r1+r2)/(r1+r2-delta) to
    "avoid granular ratcheting" (its default; the law's own flag of that name is unused in
    2023.02a); our law does not, so it is switched off unless asked (docs/yade-peer.md).
    Returns the YADE ids of our bodies.
    """
    O = O or _yade()
    import yade
    from yade import (Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                      InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_MindlinPhys,
                      Law2_ScGeom_MindlinPhys_Mindlin, NewtonIntegrator, Vector3, utils)
    if law not in ("yade", "trueaniso"):
        raise BridgeError("law must be 'yade' (YADE's Hertz-Mindlin) or 'trueaniso' (ours, from the YADE plugin)")
    if law == "trueaniso":
        try:
            from yade import Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys as Ip2, Law2_ScGeom_SimplifiedMindlinPhys_Mindlin as Law2
        except ImportError:
            raise BridgeError("law='trueaniso' needs the trueaniso YADE plugin: run yade-double with "
                              "YADE_PREFIX=<repository>/build/yade-prefix (./setup.sh builds it)") from None
    else:
        Ip2, Law2 = Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin
    if scene.has_clumps:
        if law != "yade":
            raise BridgeError("the trueaniso YADE plugin's law is for spheres; a clump scene takes law='yade'")
        from . import yade_clumps
        return yade_clumps.yade_clump_scene_from(scene, O, damping, import_contacts, mindlin_ratcheting)[0]
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
    # Our strain rate, scheduled for YADE's next step (as write_to_yade; before, it was dropped). The
    # velocities written are fluctuations, the total ones while YADE's current field is zero.
    O.cell.velGrad = _yade_matrix(scene.velocity_gradient)
    return ids


def contacts_made_at_rest(scene, O, bodies, yade_of_member):
    """YADE's interactions for our contacts, made by its own collider and law in a step at rest,
    then our shear forces on them (write_shear_history) and a second step at rest that puts those
    forces into O.forces (before it, YADE's unbalanced force read 0.086 against our 1.7e-5).
    `bodies`: YADE ids of our bodies (held still meanwhile); `yade_of_member`: of our members.

    At rest: every body's DOFs blocked and its velocity zero, the integrator running. (A step with
    the integrator switched off instead leaves that step's forces unsynced in O.forces, and YADE's
    next step adds them to its own: the first velocity increment came out doubled.)"""
    from yade import Vector3
    if not np.any(scene.contact_arrays()["normal_force"] > 0):
        return
    # Copies: YADE hands out references to the state's vectors, which the zeroing would clear.
    saved = [(Vector3(O.bodies[i].state.vel), Vector3(O.bodies[i].state.angVel), O.bodies[i].state.blockedDOFs)
             for i in bodies]
    for i in bodies:
        st = O.bodies[i].state
        st.vel, st.angVel, st.blockedDOFs = Vector3(0, 0, 0), Vector3(0, 0, 0), "xyzXYZ"
    O.step()
    write_shear_history(scene, O, yade_of_member, every=True)
    O.step()
    for i, (v, w, dofs) in zip(bodies, saved):
        st = O.bodies[i].state
        st.vel, st.angVel, st.blockedDOFs = v, w, dofs
