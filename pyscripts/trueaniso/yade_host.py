"""The study's states, probes and fabric stepped by YADE's own loop (run_states.py --host yade).

The same protocol as our stepper's (triaxial.reach_state, triaxial.probe, fabric.fabric_row), with
YADE doing the stepping: each piece of work takes our scene (the specimen or a state's checkpoint),
builds YADE's O from it with the plugin's law (yade_bridge.yade_scene_from(..., law="trueaniso"):
YADE's collider, InteractionLoop and NewtonIntegrator), puts the plugin's TrueTriaxialServo,
StressProbe or FabricRecorder into O.engines before NewtonIntegrator, runs YADE until the engine is
done, and reads the answer from the engine's attributes. A reached state comes back as our scene
(yade_bridge.scene_from_yade) and is saved as its checkpoint, so a study on this host resumes,
reports and is checked as any other; every state and probe starts from a file here too.

YADE's time step is fixed for each piece of work: the step of the study's rule (dem.TIME_STEP_RULES)
on the scene as it starts (TimeStepper's bound, the one our stepper takes at its first step; a
state's strains of ~1e-3 change it by a few per cent, inside the rule's safety factor). The servo's
per-step settings are per step of the reference rule, so a longer rule passes its ratio as the
servo's stepScale, as our stepper does. The plugin's StressProbe takes no step scale: the probe's
gain and step counts are given to it already scaled, as our StressProbe scales them
(CellServoLaw::perStep, stepsFor), which for a fixed step is the same probe.

Runs only inside yade-double with the plugin loaded (YADE_PREFIX=<repository>/build/yade-prefix);
`problem()` says in one line why not.
"""
import math
import time

import numpy as np

from . import dem, engines, fabric, triaxial
from .options import ProbeOptions
from .triaxial import StateNotReached

# What the YADE engines of the plugin do not offer of the stepper's protocol options: a study that
# asks for them on this host is refused before any work (run_states.py).
UNSUPPORTED_STATE = dict(control_shear=True, shear=(0.0, 0.0, 0.0), feed_forward=False, gain=None)
UNSUPPORTED_PROBE = dict(control_shear=True, hold_other_strains=False)


def problem():
    """None if this process can step the study in YADE, else why not (one line)."""
    from . import cli
    if not cli.in_yade():
        return ("--host yade runs inside YADE: start the script with yade-double -n -x (and "
                "YADE_PREFIX=<repository>/build/yade-prefix, where ./setup.sh installs the trueaniso plugin)")
    import yade.wrapper
    if not all(hasattr(yade.wrapper, c) for c in ("TrueTriaxialServo", "StressProbe", "FabricRecorder")):
        return ("--host yade needs the trueaniso YADE plugin: run yade-double with YADE_PREFIX=<repository>/build/"
                "yade-prefix (./setup.sh builds it when the YADE source can be had; docs/yade-peer.md)")
    return None


def threads():
    """YADE's thread count (yade-double -jN): part of a study's fingerprint on this host."""
    from yade import O
    return int(O.numThreads)


def _time_step(scene, rule):
    """(dt, step scale) of a time step rule on the scene: TimeStepper's bound at the rule's factor,
    capped as a Chain caps it, and its ratio to the reference rule's step (the unit of the servo's
    per-step settings)."""
    per_axis, safety = dem.TIME_STEP_RULES[rule]
    ref_safety = dem.TIME_STEP_RULES[dem.REFERENCE_TIME_STEP][1]
    dem.refresh(scene)
    reference = engines.TimeStepper.stiffness_bound(scene)
    bound = engines.TimeStepper.per_axis_bound(scene) if per_axis else reference
    dt = min(dem.reference_time_step(scene, safety=safety), safety * bound if math.isfinite(bound) else math.inf)
    ref_dt = min(dem.reference_time_step(scene, safety=ref_safety),
                 ref_safety * reference if math.isfinite(reference) else math.inf)
    return dt, dt / ref_dt


def _into_yade(scene, damping, dt, detection=True):
    """O built from our scene with the plugin's law; returns O."""
    from yade import O
    from . import yade_bridge
    yade_bridge.yade_scene_from(scene, damping=damping, law="trueaniso")
    O.dt = dt
    return O


def _insert(O, engine):
    """An engine of ours after InteractionLoop, before NewtonIntegrator (where it reads this step's forces)."""
    engines_ = list(O.engines)
    k = [i for i, e in enumerate(engines_) if type(e).__name__ == "NewtonIntegrator"][0]
    O.engines = engines_[:k] + [engine] + engines_[k:]


def check_options(state_options=None, probe_options=None):
    """ValueError for an option of our stepper's protocol the plugin's engines do not offer."""
    _check_options(state_options or {}, UNSUPPORTED_STATE, "TrueTriaxialServo")
    _check_options(probe_options or {}, UNSUPPORTED_PROBE, "StressProbe")


STAGES = ("idle", "relax", "ramp", "hold", "done", "failed")  # StressProbe.stage


def _check_options(given, unsupported, what):
    for key, default in unsupported.items():
        if key in given and given[key] != default and not (default is None and given[key] is None):
            raise ValueError("--host yade: the plugin's %s does not offer %s = %r (our stepper's option)"
                             % (what, key, given[key]))


def _d50(scene):
    return 2.0 * float(np.median(scene.radii))


def reach_state(scene, b, sigma_z, p=100e3, damping=0.4, inertial_number=1e-3, tolerance=100.0, unbalanced=1e-4,
                path_rate=2.0, max_strain=0.05, max_steps=3_000_000, stall_steps=100_000, hold_steps=200_000,
                friction=0.5, chunk=5000, progress=None, rolling_stiffness=0.0, rolling_friction=0.0,
                time_step=dem.REFERENCE_TIME_STEP, **others):
    """triaxial.reach_state in YADE: returns (the scene at the state, the same info dict). Raises
    StateNotReached as it does."""
    from yade.wrapper import TrueTriaxialServo
    _check_options(others, UNSUPPORTED_STATE, "TrueTriaxialServo")
    triaxial.validate_state(b, sigma_z, p)
    triaxial.set_rolling(scene, rolling_stiffness, rolling_friction)
    scene.friction = friction  # the loading friction on the material too (new contacts, the checkpoint)
    dt, scale = _time_step(scene, time_step)
    O = _into_yade(scene, damping, dt)
    servo = TrueTriaxialServo(b=b, sigmaZ=sigma_z, meanStress=p, pathRate=path_rate, stressTolerance=tolerance,
                              unbalancedTolerance=unbalanced, maxStrain=max_strain, maxSteps=max_steps,
                              stallSteps=stall_steps, holdSteps=hold_steps, loadingFriction=friction,
                              maxStrainRate=dem.strain_rate_for_inertial_number(inertial_number, _d50(scene),
                                                                                scene.density, p),
                              stepScale=scale, label="trueanisoServo")
    _insert(O, servo)
    t0 = time.time()
    while not (servo.reached or servo.failed):
        O.run(int(chunk), True)
        if progress:
            progress.line(int(servo.steps), float(servo.stressError), float(servo.unbalanced),
                          "  [%s, YADE]" % ("holding" if servo.status == 2 else "loading"))
    wall = time.time() - t0
    O.cell.velGrad = O.cell.velGrad * 0  # our checkpoint holds the state at rest (as reach_state)
    if servo.failed:
        raise StateNotReached(servo.message)
    from . import yade_bridge
    held, _ = yade_bridge.scene_from_yade(O)
    held.velocity_gradient = np.zeros((3, 3))
    # the checkpoint's step is the rule's, its unit the reference rule's step (as our stepper's Chain
    # keeps them): a study under another rule than the reference checks its checkpoints against both
    held.reference_dt = dt / scale
    dem.refresh(held)
    info = dict(status="reached", steps=int(servo.steps), wall_time=wall, stress=list(servo.stress),
                unbalanced=float(servo.unbalanced), message=servo.message, overshoot=list(servo.overshoot),
                goal=list(servo.finalStress()), friction=float(held.friction), hold_steps=int(servo.holding),
                control_shear=True, waited_steps=int(servo.waited), host="yade", dt=dt)
    info.update(triaxial.stress_record(held, servo.finalStress()))
    return held, info


def steps_for(reference_steps, scale):
    """A count of reference steps in steps `scale` reference steps long (engines' stepsFor: the
    same time, at least one step; C's lround, halves away from zero)."""
    return reference_steps if scale == 1.0 else max(1, int(math.floor(reference_steps / scale + 0.5)))


def probe(scene, hold, axis, sign=1, gamma=1e-6, increment=0.0, restrain_rotations=False, skip_detection=False,
          damping=0.4, gain=0.03, relative_tolerance=2e-3, unbalanced=1e-5, settle_steps=None, ramp_steps=300,
          max_steps=2_000_000, chunk=500, progress=None, time_step=dem.REFERENCE_TIME_STEP, **others):
    """triaxial.probe in YADE's loop (StressProbe): the same result dict. The scene is not changed.
    A two-sided probe (`sides`, ProbeOptions.two_sided) is two probes from the imported scene, one
    with `sign` and one against it: their Relax stages are the same steps, as in our stepper's
    engine, which runs its Relax once."""
    from yade.wrapper import StressProbe
    sides = others.pop("sides", ProbeOptions.sides)
    _check_options(others, UNSUPPORTED_PROBE, "StressProbe")
    axis = triaxial.validate_probe(axis, gamma)
    o = ProbeOptions(sides=sides, restrain_rotations=bool(restrain_rotations), settle_steps=settle_steps)
    two_sided = o.two_sided(scene.has_clumps, scene.block_rotations)
    settle_steps = o.settle(two_sided)
    if two_sided:
        kw = dict(gamma=gamma, increment=increment, restrain_rotations=restrain_rotations,
                  skip_detection=skip_detection, damping=damping, gain=gain, relative_tolerance=relative_tolerance, unbalanced=unbalanced,
                  settle_steps=settle_steps, ramp_steps=ramp_steps, max_steps=max_steps, chunk=chunk,
                  progress=progress, time_step=time_step, sides="one", **others)
        return triaxial.two_sides(probe(scene, hold, axis, sign, **kw), probe(scene, hold, axis, -sign, **kw))
    dem.refresh(scene)
    triaxial.check_held_state(scene, hold)
    hold6 = np.zeros(6)
    hold = np.asarray(hold, dtype=float)
    hold6[:len(hold)] = hold
    dt, scale = _time_step(scene, time_step)
    O = _into_yade(scene, damping, dt)
    p = StressProbe(axis=triaxial.AXES[axis], sign=sign, gammaTarget=gamma, increment=increment,
                    restrainRotations=bool(restrain_rotations), holdStress=list(hold6),
                    gain=gain if scale == 1.0 else min(1.0, gain * scale),
                    relativeTolerance=relative_tolerance, unbalancedTolerance=unbalanced,
                    settleSteps=steps_for(settle_steps, scale), rampSteps=steps_for(ramp_steps, scale),
                    maxSteps=steps_for(max_steps, scale), restoreState=False, label="trueanisoProbe")
    _insert(O, p)
    collider = [e for e in O.engines if type(e).__name__ == "InsertionSortCollider"][0]
    collider.dead = bool(skip_detection)
    t0 = time.time()
    while not p.finished:
        O.run(int(chunk), True)
        if progress:
            progress.line(int(p.steps), float(p.stressError), float(p.unbalanced), "  [%s, YADE]" % STAGES[p.stage])
    if p.stage != 4:
        raise StateNotReached(p.message)
    out = dict(axis=triaxial.AXES[axis], sign=sign, modulus=float(p.G if axis >= 3 else p.E),
               d_stress=list(p.dStress), d_strain=list(p.dStrain), gamma=float(p.gamma), steps=int(p.steps),
               wall_time=time.time() - t0,
               rotations="restrained" if restrain_rotations or scene.block_rotations else "free",
               detection="off" if skip_detection else "on", damping=damping, control_shear=True,
               hold_other_strains=False, host="yade", dt=dt)
    if axis < 3:
        out["E"] = out["modulus"]
        for j in range(3):
            if j != axis:
                out["nu_%s%s" % (triaxial.AXES[axis], triaxial.AXES[j])] = float(p.nu[j])
    else:
        out["G"] = out["modulus"]
    return out


def fabric_row(scene, zeta=1.0, density="eq36"):
    """fabric.fabric_row with the fabric read by the plugin's FabricRecorder on the scene in YADE
    (Zm, R, H, B, M, Nc/V, e, mean N, counts); the micromechanical prediction from its B and M and
    the near-contact count (Zm_gap) are computed from them and the scene as our stepper's row does."""
    from yade.wrapper import FabricRecorder
    dem.refresh(scene)
    dt, _ = _time_step(scene, dem.REFERENCE_TIME_STEP)
    O = _into_yade(scene, 0.4, dt)
    rec = FabricRecorder()
    _insert(O, rec)
    rec()  # its action once, on the forces of the scene as imported (no step)
    if rec.contacts == 0:
        raise fabric.NoContacts(rec.message)
    def matrix(m):
        return np.array([[m[i][j] for j in range(3)] for i in range(3)])
    f = dict(Zm=rec.Zm, Nc=rec.contacts, Np=rec.particles, Np0=rec.rattlers, Np1=rec.oneContact, R=matrix(rec.R),
             H=matrix(rec.H), B=matrix(rec.B), M=np.array(rec.M).reshape(3, 3, 3, 3), NcV_eq36=rec.NcOverVEq36,
             NcV_count=rec.NcOverV, e=rec.voidRatio, mean_N=rec.meanNormalForce)
    p = fabric.prediction_from(f, scene.shear_modulus, scene.poisson, zeta, density)
    out = fabric.row(f, p, zeta, density)
    out.update(fabric.gap_columns(scene))
    return out
