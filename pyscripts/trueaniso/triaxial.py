r"""True-triaxial states (paper Table C1) and directional stress probes, composed from the C++
engines TrueTriaxialServo and StressProbe. The servo holds the shear stresses at zero (the cell's
axes are the principal axes, as the paper's frictionless walls make them); probes act on a normal
stress ($E_i$, $\nu_{ij}$) or a shear stress ($G_{ij}$).

A state is (b, sigma_z) at p = 100 kPa; Eq. (9) gives $\sigma_x$, $\sigma_y$. The 39 states of Table C1
lie on eight paths from the isotropic state (b = 0, 0.25, 0.5, 0.75, 1; compression and
extension of z), which the study follows one path at a time, probing each state on the way.
"""
import math
import time

import numpy as np

from . import dem, engines
from .options import ProbeOptions, ServoOptions
from .refusal import InputError

# Table C1, Eqs. 8-9 and the loading paths' mean stress live in stress_states (no engines: the
# readers of result files check rows against them); their names stay importable here.
from .stress_states import PATHS, SIGMA_H, TABLE_C1, b_of, path_mean_stress, table_c1_states  # noqa: F401

__all__ = ["table_c1_states", "b_of", "path_stresses", "reach_state", "stress_as_held", "probe", "two_sides",
           "probe_state", "cross_anisotropic_states", "StateNotReached"]


def paths(states):
    """Group states into paths from the isotropic state: {(b, +1 or -1): [states by distance]}.

    The isotropic state (sigma_z = p) is its own path (b, 0)."""
    groups = {}
    for st in states:
        i, b, sz = st
        side = 0 if abs(sz - 100e3) < 1e-9 else (1 if sz > 100e3 else -1)
        groups.setdefault((b, side), []).append(st)
    for key in groups:
        groups[key].sort(key=lambda s: abs(s[2] - 100e3))
    return groups


class StateNotReached(RuntimeError):
    """The servo or the probe could not bring the specimen to its state; the message says why."""


def validate_state(b, sigma_z, p=100e3):
    """Raises ValueError with the reason for b outside [0, 1] or a principal stress <= 0."""
    return engines.true_triaxial_stresses(b, sigma_z, p)


# What a specimen made as docs/specimens.md describes has (e 0.58, Zm 5.97): the packing the
# overlap estimate assumes when no specimen is known yet (a looser one overlaps more).
DENSE_PACKING = dict(solid_fraction=0.63, coordination=6.0)


def hertz_range_problem(stress, shear_modulus, poisson, solid_fraction=DENSE_PACKING["solid_fraction"],
                        coordination=DENSE_PACKING["coordination"], what="the stress"):
    """Why `stress` (Pa) is beyond Hertz's law for this material, or None: the mean overlap of
    equal spheres at that stress (engines.hertz_overlap_ratio, theory/HertzRange.hpp) beyond
    engines.MAX_OVERLAP_RATIO of a radius. (A stress of 1e9 Pa gave a "specimen" of e 0.08 whose
    contacts overlapped by about 30 % of a radius.)"""
    ratio = engines.hertz_overlap_ratio(shear_modulus, poisson, stress, solid_fraction, coordination)
    if ratio <= engines.MAX_OVERLAP_RATIO:
        return None
    limit = stress * (engines.MAX_OVERLAP_RATIO / ratio) ** 1.5  # the ratio grows as stress^(2/3)
    return ("%s of %.6g Pa would press the contacts into each other by about %.0f %% of a radius; Hertz's law "
            "holds for small overlaps, so stresses above %.0f %% (about %.3g Pa for this material and packing) are "
            "refused" % (what, stress, 100 * ratio, 100 * engines.MAX_OVERLAP_RATIO, limit))


def rolling_problem(stiffness, friction, clumps=False):
    r"""Why rolling resistance (docs/rolling.md) with $\beta$ = stiffness, $\eta_r$ = friction cannot be
    run, or None: both must be finite numbers, > 0 together (one zero gives no resistance, or no
    cap) or both 0 (off, the paper); clumps have none."""
    for name, x in (("stiffness factor beta", stiffness), ("friction eta_r", friction)):
        if not (isinstance(x, (int, float)) and math.isfinite(x) and x >= 0):
            return "the rolling %s must be a finite number >= 0, not %r" % (name, x)
    if (stiffness > 0) != (friction > 0):
        return ("rolling resistance needs both the stiffness factor beta and the rolling friction eta_r > 0 (or both "
                "0: off); got beta = %r, eta_r = %r" % (stiffness, friction))
    if stiffness > 0 and clumps:
        return "rolling resistance is modelled between single spheres only, not for clumps"
    return None


def set_rolling(scene, stiffness, friction):
    """Rolling resistance on the scene, refused before any work (rolling_problem)."""
    problem = rolling_problem(stiffness, friction, scene.num_members != scene.num_bodies)
    if problem:
        raise InputError(problem)
    try:
        scene.rolling_friction = float(friction)
        scene.rolling_stiffness = float(stiffness)
    except ValueError as exc:
        raise InputError(str(exc)) from None


def reach_state(scene, b, sigma_z, p=100e3, servo=None, chunk=5000, progress=None, **settings):
    """Drive the scene to a true-triaxial state at constant mean stress and hold it there (Eqs. 8-9).

    The servo moves its goal along the straight stress path from where the scene is to the state,
    as fast as the specimen follows, and holds until every principal stress is within the servo's
    `tolerance` of Eq. (9), every shear stress within it of `shear` and the unbalanced force is
    below `unbalanced`. The scene is left at rest at the state, its forces evaluated there.

    Args:
        scene: the engines' Scene (a specimen, or a state reached before).
        b: intermediate principal stress coefficient of Eq. (8), in [0, 1].
        sigma_z: the vertical stress of the state, Pa.
        p: the mean stress held along the path, Pa (the paper's 100 kPa).
        servo: `options.ServoOptions`, how the state is reached and held: damping, inertial number,
            tolerances, path rate, when the servo gives up, the loading friction, the shear held,
            rolling resistance, gain, feed-forward and time step rule (each field's meaning and
            default: its class). None: the defaults, the paper's protocol.
        chunk: steps between calls of `progress` (changes no result), an integer >= 1.
        progress: called with the engines' TrueTriaxialServo after every chunk, or None.
        **settings: fields of ServoOptions given as keywords instead, or on top of `servo`
            (``reach_state(scene, b, sz, path_rate=4.0)``).

    Returns:
        dict: ``status`` ("reached"), ``steps``, ``wall_time``, ``stress`` (the six Voigt stresses
        measured last, Pa), ``goal`` (Eq. 9's), ``unbalanced``, ``overshoot``, ``friction`` and the
        stress record (principal values, the largest shear stress).

    Raises:
        trueaniso.refusal.InputError: a setting of the wrong type or out of range
            (``feed_forward="no"``), before any step.
        TypeError: a keyword that is no field of ServoOptions.
        ValueError: b outside [0, 1] or a principal stress <= 0, or bad rolling parameters, before
            any step.
        StateNotReached: the specimen cannot get there: it stops following the path for
            `stall_steps`, is held `hold_steps` without settling, strains beyond `max_strain`, or
            runs `max_steps`.

    Example:
        State 2 of Table C1 (b = 0, sigma_z = 110 kPa) from the 150-sphere specimen:

        >>> from trueaniso import specimen_file, triaxial
        >>> from trueaniso.options import ServoOptions
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> info = triaxial.reach_state(scene, b=0.0, sigma_z=110e3, servo=ServoOptions(tolerance=100.0))
        >>> info["status"], ["%.1f kPa" % (s / 1e3) for s in info["goal"][:3]]
        ('reached', ['95.0 kPa', '95.0 kPa', '110.0 kPa'])
    """
    o = ServoOptions.of(servo, settings, "reach_state")
    chunk = _chunk(chunk, "reach_state")
    validate_state(b, sigma_z, p)
    set_rolling(scene, o.rolling_stiffness, o.rolling_friction)
    servo = engines.TrueTriaxialServo()
    servo.set_goal(b, sigma_z, p)
    servo.control_shear = o.control_shear
    servo.shear_goal = np.asarray(o.shear, dtype=float)
    servo.validate()  # shear goals on a path that holds the shear strains: refused before any work
    servo.path_rate = o.path_rate
    if o.gain is not None:
        servo.gain = o.gain
    servo.feed_forward = o.feed_forward
    servo.stress_tolerance = o.tolerance
    servo.unbalanced_tolerance = o.unbalanced
    servo.max_strain = o.max_strain
    servo.max_steps = o.max_steps
    servo.stall_steps = o.stall_steps
    servo.hold_steps = o.hold_steps
    servo.loading_friction = o.friction  # the servo sets it on the scene (a scene may carry 1e23)
    d50 = 2.0 * float(np.median(scene.radii))
    servo.max_strain_rate = dem.strain_rate_for_inertial_number(o.inertial_number, d50, scene.density, p)
    chain = dem.Chain(scene, damping=o.damping, controllers=[servo], rule=o.time_step)
    servo.start(scene)
    t0 = time.time()
    while servo.status not in ("reached", "failed"):
        chain.run(chunk)
        if progress:
            progress(servo)
    scene.velocity_gradient = np.zeros((3, 3))
    # The integrator moved the bodies after the last force evaluation: forces for the positions
    # held, so that what is measured, saved and probed next is one consistent state.
    dem.refresh(scene)
    info = dict(status=servo.status, steps=int(servo.steps), wall_time=time.time() - t0,
                stress=servo.stress.tolist(), unbalanced=float(servo.unbalanced), message=servo.message,
                overshoot=servo.overshoot.tolist(), goal=servo.final_stress.tolist(),
                friction=float(scene.friction), hold_steps=int(servo.holding), control_shear=o.control_shear,
                waited_steps=int(servo.waited))
    info.update(stress_record(scene, servo.final_stress))
    if servo.status == "failed":
        raise StateNotReached(servo.message)
    return info


def _chunk(chunk, owner):
    if isinstance(chunk, bool) or not isinstance(chunk, (int, np.integer)) or chunk < 1:
        raise InputError("%s: chunk must be an integer >= 1 (steps between progress calls), not %r" % (owner, chunk))
    return int(chunk)


def stress_as_held(scene):
    r"""The scene's stress as the six Voigt components a probe holds, to probe a state as it is.

    $\sigma_{xx}$, $\sigma_{yy}$, $\sigma_{zz}$, $\sigma_{yz}$, $\sigma_{xz}$, $\sigma_{xy}$ in Pa, compression positive, the
    symmetric part. Holding zero shear instead at a state that carries some first moves it to
    another state (54 Pa of shear changed $E_z$ of a clump packing by 5.4e-4, docs/clumps.md).

    Example:
        >>> from trueaniso import specimen_file, triaxial
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> hold = triaxial.stress_as_held(scene)
        >>> print("%.1f %.1f %.1f kPa, shear below 100 Pa: %s" % (*(hold[:3] / 1e3), max(abs(hold[3:])) < 100))
        100.0 100.0 100.0 kPa, shear below 100 Pa: True
    """
    sig = np.asarray(engines.stress(scene))
    sym = 0.5 * (sig + sig.T)
    return np.array([sym[0, 0], sym[1, 1], sym[2, 2], sym[1, 2], sym[0, 2], sym[0, 1]])


def stress_record(scene, goal=None):
    """What a state record reports of the stress (Pa, compression positive): the six components,
    the three principal values (largest first), the largest off-diagonal, and with a goal (six
    Voigt components) the largest principal and shear errors against it (a state is accepted with
    both within 0.5 kPa)."""
    sig = engines.stress(scene)
    sym = 0.5 * (sig + sig.T)
    principal = engines.principal_stresses(sym)
    out = dict(sigma_yz=float(sym[1, 2]), sigma_xz=float(sym[0, 2]), sigma_xy=float(sym[0, 1]),
               sigma_1=float(principal[0]), sigma_2=float(principal[1]), sigma_3=float(principal[2]),
               tau_max=float(max(abs(sym[1, 2]), abs(sym[0, 2]), abs(sym[0, 1]))))
    if goal is not None:
        goal = np.asarray(goal, dtype=float)
        g = np.array([[goal[0], goal[5], goal[4]], [goal[5], goal[1], goal[3]], [goal[4], goal[3], goal[2]]])
        out["principal_error"] = float(np.abs(principal - engines.principal_stresses(g)).max())
        out["shear_error"] = float(np.abs(np.array([sym[1, 2], sym[0, 2], sym[0, 1]]) - goal[3:]).max())
    return out


AXES = ("x", "y", "z", "yz", "xz", "xy")  # Voigt order: normal probes, then shear probes
NORMAL_AXES = AXES[:3]
SHEAR_AXES = AXES[3:]

# The range of gamma (Eq. 12) a study accepts (docs/triaxial.md, "Probe size"): above 1e-5 the
# probe is no longer a tangent (E grows with the increment: +0.5 % at 1e-5, +4.5 % at 1e-4 on 100
# spheres at 100 kPa, as the secant of a modulus growing as sigma^(1/3) over d sigma = E gamma);
# below 1e-8 the increment (E gamma ~ 3 Pa) nears the stress noise of a held state (~5e-5 Pa
# measured, growing with the specimen; a 0.15 Pa drift was reported on larger ones). The library
# itself accepts any gamma > 0 (studies of the probe size need to).
GAMMA_RANGE = (1e-8, 1e-5)


def validate_probe(axis, gamma):
    """The axis as 0-5 (from 0-5 or "x", "y", "z", "yz", "xz", "xy"; "zy", "zx", "yx" name the same
    shears); ValueError for any other axis (True included: a bool is not an axis) and for a gamma
    that is not a finite positive number."""
    if isinstance(axis, str) and axis in AXES + ("zy", "zx", "yx"):
        axis = AXES.index(axis if axis in AXES else axis[::-1])
    elif isinstance(axis, bool) or not isinstance(axis, (int, np.integer)) or axis not in range(6):
        raise ValueError("probe axis must be x, y, z, yz, xz or xy, not %r" % (axis,))
    if not (isinstance(gamma, (int, float, np.floating)) and math.isfinite(gamma) and gamma > 0):
        raise ValueError("probe gamma must be a finite number > 0, not %r" % (gamma,))
    return int(axis)


# How far a scene's stress may lie from what a probe is told to hold (of the largest held stress):
# states are reached within 100 Pa (0.1 % at 100 kPa); 2 % leaves room for a user's rounding, and
# a probe from farther away would first travel to the held state and measure that path instead.
HOLD_MISMATCH = 0.02


def check_held_state(scene, hold):
    """Refuse a probe whose held stresses are not the scene's (ValueError, before any step)."""
    sig = engines.stress(scene)
    hold = np.asarray(hold, dtype=float)
    here = np.array([sig[0, 0], sig[1, 1], sig[2, 2], sig[1, 2], sig[0, 2], sig[0, 1]])[:len(hold)]
    scale = max(np.abs(hold[:3]).max(), 1.0)
    if len(hold) not in (3, 6) or np.abs(here - hold).max() > HOLD_MISMATCH * scale:
        raise ValueError("the scene is at sigma = (%s) kPa, not at the stresses the probe is told to hold (%s) kPa "
                         "(within %g %%): a probe measures the tangent at the state it holds; reach that state "
                         "first (reach_state) or hold the scene's own stresses"
                         % (", ".join("%.2f" % (v / 1e3) for v in here), ", ".join("%.2f" % (v / 1e3) for v in hold),
                            100 * HOLD_MISMATCH))


def probe(scene, hold, axis, sign=1, options=None, chunk=500, progress=None, **settings):
    r"""One directional stress probe at a held state (Eqs. 10-12); the scene is restored afterwards.

    From the held state, sliding is suppressed (friction 1e23), the scene relaxes, and the stress on
    `axis` rises until the strain invariant gamma reaches the options' `gamma` while the other stresses are
    held. A two-sided probe (the options' `sides`; by default on clumps free to rotate) then does the
    same from the relaxed state with the stress lowered, and its increments are the half differences
    of the two sides'.

    Args:
        scene: the engines' Scene at a held state (`reach_state`, or a specimen).
        hold: the state's stresses held on the other components, Pa: three normal stresses (the shear
            stresses then held at zero), or six Voigt components (`stress_as_held`).
        axis: "x", "y", "z" (a normal stress: $E_i$, $\nu_{ij}$) or "yz", "xz", "xy" (a shear stress: $G_{ij}$);
            or 0-5.
        sign: +1 loads, -1 unloads (a two-sided probe: the side run first, whose orientation its
            increments keep).
        options: `options.ProbeOptions`, how the state is probed: gamma (the strain invariant of
            Eq. 12 the probe stops at), a fixed stress increment instead, restrained rotations,
            contact detection, damping, the probe servo's gain and tolerances, its stages' steps,
            held shear stresses or strains, held other strains (each field's meaning and default:
            its class). None: the defaults, the paper's probe.
        chunk: steps between calls of `progress` (changes no result), an integer >= 1.
        progress: called with the engines' StressProbe after every chunk, or None.
        **settings: fields of ProbeOptions given as keywords instead, or on top of `options`
            (``probe(scene, hold, "z", gamma=1e-6)``).

    Returns:
        dict: ``modulus`` and ``E`` (Eq. 10) with ``nu_ij`` (Eq. 11) of a normal probe, or ``G`` of a
        shear probe, in Pa; ``d_stress`` and ``d_strain`` (Voigt increments), ``gamma``, ``steps``,
        ``wall_time`` and how it ran (``rotations``, ``detection``, ``damping``, ``sides``: 1 or 2;
        ``sign`` is 0 for two sides, whose increments are also given one side each,
        ``d_stress_sides`` and ``d_strain_sides``).

    Raises:
        ValueError: an unknown axis, a gamma <= 0, a scene without bodies, or held stresses that are
            not the scene's, before any step.
        trueaniso.refusal.InputError: a setting of the wrong type or out of range
            (``restrain_rotations="no"``), before any step.
        TypeError: a keyword that is no field of ProbeOptions.
        StateNotReached: the probe did not converge within the options' `max_steps`.

    Example:
        >>> from trueaniso import specimen_file, triaxial
        >>> from trueaniso.options import ProbeOptions
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> r = triaxial.probe(scene, [100e3, 100e3, 100e3], "z", options=ProbeOptions(gamma=1e-6))
        >>> print("E_z = %.0f MPa, nu_zx = %.3f" % (r["E"] / 1e6, r["nu_zx"]))
        E_z = 278 MPa, nu_zx = 0.150
    """
    gamma = settings.get("gamma", options.gamma if isinstance(options, ProbeOptions) else ProbeOptions.gamma)
    axis = validate_probe(axis, gamma)  # its own message for an axis or a gamma that is none
    if sign not in (1, -1) or isinstance(sign, bool):
        raise InputError("probe: sign must be 1 or -1, not %r" % (sign,))
    o = ProbeOptions.of(options, settings, "probe")
    chunk = _chunk(chunk, "probe")
    gamma, increment, restrain_rotations, skip_detection = o.gamma, o.increment, o.restrain_rotations, o.skip_detection
    damping, control_shear, hold_other_strains = o.damping, o.control_shear, o.hold_other_strains
    if scene.num_bodies == 0:
        raise ValueError("probe: the scene has no bodies (a stress probe needs a loaded packing)")
    p = engines.StressProbe()
    p.axis, p.sign, p.gamma_target, p.increment = axis, sign, gamma, increment
    p.control_shear = control_shear
    p.hold_other_strains = hold_other_strains
    p.restrain_rotations = restrain_rotations
    p.gain, p.relative_tolerance, p.unbalanced_tolerance = o.gain, o.relative_tolerance, o.unbalanced
    p.two_sided = two_sided = o.two_sided(scene.has_clumps, scene.block_rotations)
    p.settle_steps, p.ramp_steps, p.max_steps = o.settle(two_sided), o.ramp_steps, o.max_steps
    # The cap only matters in the relax stage; probes move strains of ~1e-6.
    p.max_strain_rate = 10.0
    chain = dem.Chain(scene, damping=damping, controllers=[p], rule=o.time_step)
    dem.refresh(scene)
    check_held_state(scene, hold)
    t0 = time.time()
    p.start(scene, np.asarray(hold, dtype=float))
    if skip_detection:
        # Nothing slides and nothing moves beyond ~1e-6 strain: the contact network is that of
        # the start, so the list is kept (it was rebuilt by refresh) and detection is switched off.
        chain.detection.dead = True
    try:
        while p.stage not in ("done", "failed"):
            chain.run(chunk)
            if progress:
                progress(p)
    finally:
        p.restore(scene)
        dem.refresh(scene)
    if p.stage == "failed":
        raise StateNotReached(p.message)
    out = dict(axis=AXES[axis], sign=0 if two_sided else sign, sides=2 if two_sided else 1, modulus=float(p.modulus),
               d_stress=p.d_stress.tolist(), d_strain=p.d_strain.tolist(), gamma=float(p.gamma),
               steps=int(p.steps), relax_steps=int(p.relax_steps), ramp_steps=int(p.ramp_steps_done),
               hold_steps=int(p.hold_steps), wall_time=time.time() - t0,
               # a scene that blocks rotations is restrained whatever was asked
               rotations="restrained" if restrain_rotations or scene.block_rotations else "free",
               detection="off" if skip_detection else "on", damping=damping,
               detection_calls=int(chain.detection.applied), control_shear=bool(control_shear),
               hold_other_strains=bool(hold_other_strains))
    if two_sided:  # each side's increments (the first with `sign`): their half sum is what the state did alone
        out["d_stress_sides"] = [p.d_stress_first.tolist(), p.d_stress_second.tolist()]
        out["d_strain_sides"] = [p.d_strain_first.tolist(), p.d_strain_second.tolist()]
    return _named_moduli(out, axis, p.poisson_ratio)


def _named_moduli(out, axis, poisson):
    """`out` with its modulus named: E and the nu_ij of poisson(j) (Eqs. 10-11) for a normal axis,
    G for a shear axis."""
    if axis < 3:
        out["E"] = out["modulus"]
        for j in range(3):
            if j != axis:
                out["nu_%s%s" % (AXES[axis], AXES[j])] = float(poisson(j))
    else:
        out["G"] = out["modulus"]
    return out


def two_sides(first, second):
    """The two-sided probe of two one-sided ones from the same state, `first` with a sign and
    `second` against it (a host whose engine runs one side at a time: YADE's loop): the increments
    are the half differences, the moduli theirs, the steps and the wall time the sums; the same
    as our engine's two-sided StressProbe computes.

    Example:
        >>> from trueaniso import specimen_file, triaxial
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> up, down = (triaxial.probe(scene, [100e3] * 3, "z", sign=s, sides="one") for s in (1, -1))
        >>> r = triaxial.two_sides(up, down)
        >>> r["sides"], r["sign"], abs(r["E"] / triaxial.probe(scene, [100e3] * 3, "z", sides="two")["E"] - 1) < 1e-3
        (2, 0, True)
    """
    axis = AXES.index(first["axis"])
    ds = 0.5 * (np.asarray(first["d_stress"]) - np.asarray(second["d_stress"]))
    de = 0.5 * (np.asarray(first["d_strain"]) - np.asarray(second["d_strain"]))
    out = dict(first, sign=0, sides=2, d_stress=ds.tolist(), d_strain=de.tolist(), modulus=float(ds[axis] / de[axis]),
               gamma=float(abs(de[axis]) if axis >= 3 else engines.gamma(de[:3])),
               d_stress_sides=[list(first["d_stress"]), list(second["d_stress"])],
               d_strain_sides=[list(first["d_strain"]), list(second["d_strain"])])
    for k in ("steps", "relax_steps", "ramp_steps", "hold_steps", "wall_time"):
        if k in first and k in second:
            out[k] = first[k] + second[k]
    return _named_moduli(out, axis, lambda j: -de[j] / de[axis])


def probe_state(scene, hold, axes=(2, 0, 1), **kw):
    """Probes of one state on several axes, each from the same state (`probe` restores it after each).

    Args:
        scene: the engines' Scene at a held state.
        hold: the state's stresses, as `probe` takes them.
        axes: the axes, z, x, y by default (as the study probes).
        **kw: the other arguments of `probe` (``options``, a ProbeOptions, or its fields).

    Returns:
        list: one `probe` result per axis, in their order.

    Example:
        >>> from trueaniso import specimen_file, triaxial
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> [r["axis"] for r in triaxial.probe_state(scene, [100e3] * 3, axes="xyz")]
        ['x', 'y', 'z']
    """
    return [probe(scene, hold, a, **kw) for a in axes]


# The sigma_v of a cross-anisotropic study when none are given (Pa): stress ratios sigma_v/sigma_h
# from 0.5 to 2.5 on both sides of the isotropic state. The paper does not list the states of
# Fig. 16's source; this choice spans the ratios of Table C1's extreme states (sigma_1/sigma_3 up to 3).
CROSS_ANISOTROPIC_SIGMA_V = (50e3, 60e3, 70e3, 80e3, 90e3, 100e3, 120e3, 140e3, 160e3, 180e3, 200e3, 250e3)


def validate_path_state(path, b, sigma_z):
    """ValueError with the reason for a state that is not on the path (or not a state)."""
    p = path_mean_stress(path, b, sigma_z)
    if path == "cross-anisotropic":
        if b != 0:
            raise ValueError("a cross-anisotropic state is given by sigma_v alone (b = 0 in its definition), "
                             "not b = %r" % (b,))
        if not (isinstance(sigma_z, (int, float)) and math.isfinite(sigma_z) and sigma_z > 0):
            raise ValueError("sigma_v must be a finite stress > 0 Pa, not %r" % (sigma_z,))
    return validate_state(b, sigma_z, p)


def path_stresses(path, b, sigma_z):
    r"""$\sigma_x$, $\sigma_y$, $\sigma_z$ (Pa) of the state (b, sigma_z) on a loading path (Eq. 9).

    Args:
        path: one of `PATHS`: "true-triaxial" (Table C1: p = 100 kPa) or "cross-anisotropic"
            (Fig. 16: $\sigma_x = \sigma_y = 100$ kPa).
        b: b of Eq. (8) (0 on the cross-anisotropic path).
        sigma_z: the vertical stress, Pa.

    Example:
        >>> from trueaniso import triaxial
        >>> [round(s) for s in triaxial.path_stresses("true-triaxial", 0.5, 140e3)]
        [100000, 60000, 140000]
    """
    return engines.true_triaxial_stresses(b, sigma_z, path_mean_stress(path, b, sigma_z))


def cross_anisotropic_states(sigma_v=CROSS_ANISOTROPIC_SIGMA_V):
    r"""The states of a cross-anisotropic study (Fig. 16): $\sigma_x = \sigma_y = 100$ kPa, $\sigma_z = \sigma_v$.

    Args:
        sigma_v: the vertical stresses, Pa (by default from 50 to 250 kPa).

    Returns:
        list: (id, 0, sigma_v) per state, ids 'sv<sigma_v in kPa>' (exact for any multiple of 0.1 Pa).

    Raises:
        ValueError: a stress off the path, or one given twice.

    Example:
        >>> from trueaniso import triaxial
        >>> triaxial.cross_anisotropic_states([60e3, 112.5e3])
        [('sv60', 0.0, 60000.0), ('sv112.5', 0.0, 112500.0)]
    """
    out = []
    for sv in sigma_v:
        sv = float(sv)
        validate_path_state("cross-anisotropic", 0.0, sv)
        out.append(("sv%s" % ("%.4f" % (sv / 1e3)).rstrip("0").rstrip("."), 0.0, sv))
    ids = [i for i, _, _ in out]
    twice = sorted({i for i in ids if ids.count(i) > 1})
    if twice:
        # The values too: two sigma_v 0.01 Pa apart share a name (ids keep 0.1 Pa) and read as one.
        raise ValueError("sigma_v of state %s is given twice (%s Pa; state names keep sigma_v to 0.1 Pa)"
                         % (", ".join(twice), ", ".join("%.12g" % sv for i, _, sv in out if i in twice)))
    return out
