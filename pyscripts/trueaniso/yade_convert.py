"""Conversion between YADE's ``O`` and our Scene that the sphere bridge (yade_bridge) and the
clump bridge (yade_clumps) share (runs only inside yade-double): the periodic cell both ways, the
material rule, velocity gradients, YADE's contact rows, our shear history onto YADE's interactions
and the images of YADE's interactions kept when our state is written. The conventions converted
are listed in yade_bridge.
"""
import math

import numpy as np


class BridgeError(ValueError):
    """A YADE scene, body, material or interaction the bridge cannot convert; the message names it."""


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


def _reference_cell(O, h):
    """The cell at zero strain: YADE's motion trsf undone, trsf^-1 hSize. YADE's refHSize is not it
    after a flipCell (hSize changes, refHSize and trsf do not), which read as a shear that never
    happened (gamma_xy 0.997 on a cell only compressed); our Cell remaps the reference on a flip
    so that strains are the motion's alone (core/Cell.hpp), and YADE's strains are trsf's."""
    trsf = _matrix(O.cell.trsf)
    det = np.linalg.det(trsf) if np.all(np.isfinite(trsf)) else float("nan")
    if not det > 1e-6:  # NaN, singular, a reflection or a volume shrunk a millionfold: no motion of a cell
        # Refused, not taken as strains counted from now without a word (a trsf set by hand).
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
        # pass the class check (adhesion: 4.8 kPa in YADE would read 97 kPa here).
        extras = [a for a in ("betan", "betas", "adhesionForce", "kr", "ktw") if float(getattr(I.phys, a, 0.0)) != 0.0]
        if extras:
            raise BridgeError("interaction %d-%d has YADE's Mindlin law with %s != 0 (damping, adhesion or moments the "
                              "paper's law has not); import the positions only (import_contacts=False) to evaluate "
                              "them with ours" % (I.id1, I.id2, ", ".join(extras)))
        n = I.geom.normal
        rows.append((index[I.id1], index[I.id2], [I.cellDist[k] for k in range(3)], [n[k] for k in range(3)],
                     I.phys.normalForce.norm(), [I.phys.shearForce[k] for k in range(3)]))
    return rows


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
        # other laws, and would be converted without a word (ViscEl's 50 kPa would read 226 kPa here).
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
    the cell in our run (bodies written wrapped, with only a flip remapped, turned 313 contacts into
    251 on a scene imported and written straight back). Our motion
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


def contacts_made_at_rest(scene, O, bodies, yade_of_member):
    """YADE's interactions for our contacts, made by its own collider and law in a step at rest,
    then our shear forces on them (write_shear_history) and a second step at rest that puts those
    forces into O.forces (without it, YADE's unbalanced force reads 0.086 against our 1.7e-5).
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


def contact_law(law):
    """(Ip2, Law2) classes of a law: "yade" (YADE's Hertz-Mindlin) or "trueaniso" (ours, from the plugin)."""
    if law == "trueaniso":
        try:
            from yade import Ip2_FrictMat_FrictMat_SimplifiedMindlinPhys as Ip2, Law2_ScGeom_SimplifiedMindlinPhys_Mindlin as Law2
        except ImportError:
            raise BridgeError("law='trueaniso' needs the trueaniso YADE plugin: run yade-double with "
                              "YADE_PREFIX=<repository>/build/yade-prefix (./setup.sh builds it)") from None
        return Ip2, Law2
    if law == "yade":
        from yade import Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin
        return Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin
    raise BridgeError("law must be 'yade' (YADE's Hertz-Mindlin) or 'trueaniso' (ours, from the YADE plugin)")
