"""Exact static stiffness of the contact network: Python face of engines/statics.

The C++ engine linearises the dynamic contact law at the scene's state with every contact
sticking, relaxes the bodies (translations, and rotations unless blocked) under the six unit
strains of the periodic cell with a sparse Cholesky solve, and returns the 6x6 tangent of the
Love-Weber stress against the cell's log strain (both compression positive; Voigt order xx, yy,
zz, yz, xz, xy; engineering shear strains). docs/statics.md has the definitions and derivations.
"""

import math
import os

from . import engines as _e

VOIGT = ("xx", "yy", "zz", "yz", "xz", "xy")
__all__ = ["static_stiffness", "rotation_factor", "identity", "state_record"]


def static_stiffness(scene, rotations=True, max_unbalanced=1e-2, max_residual=1e-8, **solver):
    r"""The exact static stiffness of the contact network at the scene's state (module doc).

    Args:
        scene: the engines' Scene at rest at its state, its forces evaluated there.
        rotations: True relaxes the particles' rotations too; False blocks them.
        max_unbalanced: refuse a state out of balance beyond this unbalanced force.
        max_residual: refuse a solve whose relative residual exceeds this.
        **solver: settings of the engine's sparse solver (engines.static_stiffness).

    Returns:
        dict: ``C`` (6x6 stiffness, Pa) and ``S`` (its inverse); ``E`` ($E_x$, $E_y$, $E_z$ of Eq. 40,
        the probe's moduli), ``nu`` (3x3, nu[i, j] = $\nu_{ij}$, i loading, j lateral, NaN on the
        diagonal), ``G`` ($G_{yz}$, $G_{xz}$, $G_{xy}$ of Eq. 39); ``affine`` (the kinematic stiffness, no
        relaxation) with its parts ``affine_normal`` + ``affine_shear`` (Eq. 32) and
        ``affine_geometric`` (initial-force terms); ``stress``; ``residual`` (max of
        norm(K u - f) / norm(f) over the six strains) and ``pinned_reaction``; ``rattlers`` (body
        ids) and ``pinned`` (the bodies whose degrees of freedom were pinned, and why); ``time``
        (s, by phase) and the solver's counts.

    Raises:
        ValueError: a state out of balance beyond `max_unbalanced`.
        RuntimeError: a residual beyond `max_residual`.

    Example:
        >>> from trueaniso import specimen_file, statics
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> r = statics.static_stiffness(scene)
        >>> print("E_z = %.0f MPa, residual below 1e-8: %s" % (r["E"][2] / 1e6, r["residual"] < 1e-8))
        E_z = 278 MPa, residual below 1e-8: True
    """
    from .options import flag
    if not 0 < max_unbalanced:
        raise ValueError("max_unbalanced must be > 0")
    r = _e.static_stiffness(scene, rotations=flag("static_stiffness", "rotations", rotations),
                            max_unbalanced=float(max_unbalanced), **solver)
    if not r["residual"] <= max_residual:
        raise RuntimeError("static stiffness: residual %.3g > %.3g; pinned DOFs %s"
                           % (r["residual"], max_residual, [(p["body"], p["reason"]) for p in r["pinned"]]))
    return r


def rotation_factor(scene, free=None, blocked=None, **kw):
    """zeta of Eq. (37) derived from static solves (docs/statics.md, "Rotation factor").

    zeta is the value for which the kinematic prediction of Eq. (37) gives the modulus of the static
    solve with rotations free, between zeta = 1 (rotations blocked, the kinematic stiffness) and 0.

    Args:
        scene: the engines' Scene at its state.
        free: a `static_stiffness` result with rotations free (None: solved here).
        blocked: the same with rotations blocked (None: solved here).
        **kw: the arguments of `static_stiffness`.

    Returns:
        dict: ``zeta`` (per axis), ``zeta_h`` (of $(E_x + E_y)/2$), ``zeta_v`` (of $E_z$),
        ``zeta_rotation``, ``zeta_rotation_h``, ``zeta_rotation_v``, ``E_free``, ``E_blocked`` and
        ``E_kinematic`` (zeta = 1). A zeta no value in ``engines.ZETA_RANGE`` reproduces is NaN.

    Example:
        >>> from trueaniso import specimen_file, statics
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> z = statics.rotation_factor(scene)
        >>> print("zeta_h = %.2f, zeta_v = %.2f" % (z["zeta_h"], z["zeta_v"]))
        zeta_h = 0.33, zeta_v = 0.25
    """
    free = free if free is not None else static_stiffness(scene, rotations=True, **kw)
    blocked = blocked if blocked is not None else static_stiffness(scene, rotations=False, **kw)
    z = _e.rotation_factor(free["affine_normal"], free["affine_shear"], free["E"], blocked["E"])
    z.update(E_free=free["E"], E_blocked=blocked["E"],
             E_kinematic=_e.kinematic_moduli(free["affine_normal"], free["affine_shear"], 1.0))
    return z


def summary(result):
    """One line per modulus, for logs."""
    E, nu, G = result["E"], result["nu"], result["G"]
    lines = ["E_%s = %.4g MPa" % (a, E[i] / 1e6) for i, a in enumerate("xyz")]
    lines += ["nu_%s%s = %.4f" % (a, b, nu[i, j]) for i, a in enumerate("xyz") for j, b in enumerate("xyz") if i != j]
    lines += ["G_%s = %.4g MPa" % (VOIGT[3 + i], G[i] / 1e6) for i in range(3)]
    lines.append("residual %.2e, %d rattlers, %d pinned, %.2f s" % (
        result["residual"], len(result["rattlers"]), len(result["pinned"]), result["time"]["total"]))
    return "\n".join(lines)


def identity(meta, n, state=None):
    """What a statics record is of, which a reader checks it against (analysis.b1_checks).

    A record keeps it as ``study``: the report refuses a record in a study directory, or borrowed
    with --b1-data, whose specimen, material or state is not the study's.

    Args:
        meta: the specimen file's metadata of the scene solved (`specimen_file.load`); a study's
            checkpoint names its study's specimen in its parameters.
        n: the number of particles.
        state: the state's id of a study's checkpoint, or None for the specimen itself (its
            isotropic state).

    Returns:
        dict: ``specimen`` (the study's specimen checksum), ``n``, ``material`` (``shear_modulus``,
        ``poisson``, ``density``) and ``state`` (``id``, with ``b``, ``sigma_z`` and ``path`` of a
        checkpoint's state).

    Example:
        >>> from trueaniso import specimen_file, statics
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> who = statics.identity(meta, scene.num_bodies)
        >>> who["specimen"] == meta["sha256"], who["n"], who["material"]["shear_modulus"]
        (True, 150, 18000000000.0)
    """
    p = meta.get("parameters") or {}
    m = meta["material"]
    out = dict(specimen=p["specimen"] if state is not None else meta["sha256"], n=int(n),
               material=dict(shear_modulus=float(m["shear_modulus"]), poisson=float(m["poisson"]),
                             density=float(m["density"])))
    if state is None:
        out["state"] = dict(id="isotropic")
    else:
        out["state"] = dict(id=str(state), b=float(p["b"]), sigma_z=float(p["sigma_z"]),
                            path=p.get("path", "true-triaxial"))
    return out


def state_record(scene, identity=None):
    """What a study keeps of a state's static solve (Appendix B, Table B1), as plain numbers (JSON).

    Args:
        scene: the engines' Scene at rest at its state (a study's checkpoint, or a specimen).
        identity: what the record is of (`identity`: the study's specimen, material, particle count
            and state), stored as ``study`` so that a reader can refuse a record of another study;
            None leaves it out.

    Returns:
        dict: ``E_free`` and ``E_blocked`` (rotations free and blocked), ``E_kinematic`` (zeta = 1),
        ``nu_free``, ``zeta_h``, ``zeta_v`` (`rotation_factor`), ``sigma`` (the state's normal
        stresses), ``residual``, ``rattlers`` (their count), ``time`` (s), and ``study`` when
        `identity` is given.

    Example:
        >>> from trueaniso import specimen_file, statics
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> rec = statics.state_record(scene, statics.identity(meta, scene.num_bodies))
        >>> print("E_blocked / E_kinematic = %.2f" % (rec["E_blocked"][2] / rec["E_kinematic"][2]))
        E_blocked / E_kinematic = 0.97
        >>> rec["study"]["n"], rec["study"]["state"]
        (150, {'id': 'isotropic'})
    """
    free = static_stiffness(scene, rotations=True)
    blocked = static_stiffness(scene, rotations=False)
    zeta = rotation_factor(scene, free=free, blocked=blocked)
    s = _e.stress(scene)
    return dict(E_free=[float(x) for x in free["E"]], E_blocked=[float(x) for x in blocked["E"]],
                E_kinematic=[float(x) for x in zeta["E_kinematic"]],
                nu_free=[[None if x != x else float(x) for x in row] for row in free["nu"]],
                zeta_h=float(zeta["zeta_h"]), zeta_v=float(zeta["zeta_v"]), residual=float(free["residual"]),
                sigma=[float(s[i, i]) for i in range(3)], rattlers=len(free["rattlers"]),
                time=free["time"]["total"] + blocked["time"]["total"],
                **({} if identity is None else dict(study=identity)))


def said_zeta(z):
    """A record's magnitude zeta for a log line: None (null in the record, NaN from the solve) is
    a modulus no zeta in engines.ZETA_RANGE reproduces, as at clump2's isotropic state."""
    if z is not None and math.isfinite(z):
        return "%.3f" % z
    return "none in [%g, %g] reproduces E" % tuple(_e.ZETA_RANGE)


def state_file(out, state):
    """Where a study directory keeps a state's record: statics_isotropic.json for the specimen
    (run_study's name), statics_state-ID.json for the checkpoint of state ID."""
    return os.path.join(out, "statics_isotropic.json" if state is None else "statics_state-%s.json" % state)


def cached_record(out, state=None, scene=None, log=print, meta=None):
    """The record of `state` (None: the specimen, given as `scene` with its file's metadata `meta`)
    from its file in `out`, or solved from the scene (for a state: its checkpoint states/ID.npz)
    and written atomically, with its identity."""
    from . import atomic, run_cost, specimen_file, study_dir
    path = state_file(out, state)
    if not os.path.exists(path):
        if scene is None:
            try:
                scene, meta = specimen_file.load(study_dir.checkpoint_path(out, state))
            except specimen_file.SpecimenFileError as exc:
                # A study's checkpoint, not a specimen: run_study reaches a missing one again.
                raise specimen_file.SpecimenFileError(study_dir.checkpoint_problem(exc, state)) from None
        log("statics (%s): solving the contact network's stiffness, rotations free and blocked ..."
            % ("isotropic state" if state is None else "state %s" % state))
        meter = run_cost.Meter()
        record = state_record(scene, None if meta is None else identity(meta, scene.num_bodies, state))
        record["cost"] = meter.spent()  # the solves' peak memory is a paper-size study's largest
        atomic.write_json(path, record)
    from . import validate
    return validate.load_json(path, "statics_record")
