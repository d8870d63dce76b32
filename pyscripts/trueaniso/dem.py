"""Composition of the standard engine chain, and the unit conversions its parameters need."""
import math

from . import engines as _e

__all__ = ["Chain", "refresh", "strain_rate_for_inertial_number"]


# Time step rules of TimeStepper: name -> (per_axis, safety). "smallest-inertia" is the rule every
# committed result was made with; "per-axis" is the per-axis bound at the largest factor at which
# undamped packings of spheres, clump1 and clump2 keep their energy over 100,000 steps
# (docs/time-step.md; the runs' local damping is the margin).
TIME_STEP_RULES = {"smallest-inertia": (False, 0.5), "per-axis": (True, 0.8)}
# The rule whose step is the unit of time of the servos' per-step settings (path rate, gain, step
# counts; scene.reference_dt): under any other rule they load at the same rate in time.
REFERENCE_TIME_STEP = "smallest-inertia"
# The rule a Chain takes when not told (scripts set it from --time-step, cli.resolve_time_step).
time_step_rule = "smallest-inertia"


class Chain:
    """A simulation in the usual order: detection, forces, [controllers], time step, integrator.

    The attributes name the engines, so that a protocol can switch them (``chain.detection.dead =
    True`` during a probe, where nothing slides and the contact network cannot change):
    ``detection``, ``forces``, ``controllers``, ``timestep``, ``integrator``, and ``sim``, the
    engines' Simulation. ``run(n)`` runs n steps and returns n.

    Args:
        scene: the engines' Scene.
        damping: YADE's local non-viscous damping of the integrator.
        skin_factor: the Verlet list's skin, as a fraction of the mean radius.
        safety: the time step's safety factor (None: the rule's).
        max_dt: the cap of the time step (None: `reference_time_step` at 100 kPa).
        controllers: engines run after the forces (a servo, a probe, a `fabric.recorder`).
        rule: a key of `TIME_STEP_RULES` (None: the module's `time_step_rule`, "smallest-inertia").

    Raises:
        ValueError: an unknown time step rule.

    Example:
        >>> from trueaniso import specimen_file, dem
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> chain = dem.Chain(scene, damping=0.4)
        >>> chain.run(100), scene.step
        (100, 108100)
    """

    def __init__(self, scene, damping=0.2, skin_factor=0.2, safety=None, max_dt=None, controllers=(), rule=None):
        self.scene = scene
        rule = time_step_rule if rule is None else rule
        if rule not in TIME_STEP_RULES:
            raise ValueError("unknown time step rule %r (rules: %s)" % (rule, ", ".join(TIME_STEP_RULES)))
        per_axis, rule_safety = TIME_STEP_RULES[rule]
        safety = rule_safety if safety is None else safety
        self.detection = _e.ContactDetection()
        self.detection.skin_factor = skin_factor
        self.forces = _e.ContactForces()
        self.timestep = _e.TimeStepper()
        self.timestep.safety = safety
        self.timestep.per_axis = per_axis
        self.timestep.max_dt = max_dt if max_dt is not None else reference_time_step(scene, safety=safety)
        # The reference rule's cap, the one its own chain would take (scene.reference_dt: the unit of
        # the servos' per-step settings; under the reference rule itself it is max_dt, to the bit).
        reference_safety = TIME_STEP_RULES[REFERENCE_TIME_STEP][1]
        self.timestep.reference_safety = reference_safety
        if max_dt is None:
            self.timestep.reference_max_dt = reference_time_step(scene, safety=reference_safety)
        self.integrator = _e.NewtonIntegrator()
        self.integrator.damping = damping
        self.controllers = list(controllers)
        self.sim = _e.Simulation(scene)
        for e in [self.detection, self.forces] + self.controllers + [self.timestep, self.integrator]:
            self.sim.add(e)
        if scene.dt <= 0:
            scene.dt = self.timestep.max_dt

    def run(self, n):
        """Run n steps; returns n."""
        return self.sim.run(int(n))


def refresh(scene):
    """Recompute every contact quantity (forces, normals, branches) for the current positions.

    No tangential increment is made: what a loaded or edited scene needs before it is measured.
    The C++ engines/dynamics/ContactRefresh is the one home of this.

    Example:
        >>> from trueaniso import specimen_file, dem, engines
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> scene.positions = scene.positions * 1.0  # an edit
        >>> dem.refresh(scene)
        >>> print("p = %.1f kPa" % (engines.stress(scene).trace() / 3e3))
        p = 100.0 kPa
    """
    _e.refresh_contacts(scene)


def reference_contact_force(scene, pressure):
    r"""Mean contact force expected at a pressure: $p = N_c \langle N l \rangle / V$ with $N_c l \sim 3 V_s Z/(2\pi r^2 \dots)$.

    A bound is enough here (it only caps the time step before contacts exist): for spheres of
    mean diameter $d$ at solid fraction ~0.6 and $Z \sim 6$,
    $\langle N \rangle \sim \pi d^2 p/(0.6 Z) \sim 0.9\,d^2 p$; we use $4 d^2 p$ so the cap is safe
    for the stiffest contacts of a well-formed network.
    """
    radii = scene.radii
    d = 2.0 * float(radii.mean())
    return 4.0 * d * d * pressure


def reference_time_step(scene, pressure=100e3, safety=None, coordination=12):
    r"""Time step for contacts carrying the reference force at `pressure` ($k_n$ of Eq. 5): the cap of
    the time stepper's step. $\sqrt{m/(Z k_n)}$ at the stiffest expected contact is below either
    bound of a packing at that pressure, so it takes the factor of the rule (default: the factor of
    the module's time_step_rule)."""
    if safety is None:
        safety = TIME_STEP_RULES[time_step_rule][1]
    radii = scene.radii
    mmin = float(scene.masses.min())
    force = reference_contact_force(scene, pressure)
    kn = scene.Cn * math.cbrt(float(radii.max()) * force)  # rbar <= r_max: an upper bound
    return safety * math.sqrt(mmin / (coordination * kn))


def strain_rate_for_inertial_number(inertial_number, d50, density, pressure):
    r"""The strain rate $\dot\varepsilon$ of an inertial number, $I = \dot\varepsilon\, d \sqrt{\rho/p}$ (I < 1e-3: quasi-static).

    The engines' control/InertialNumber.hpp, which the YADE plugin's TrueTriaxialServo takes too.

    Args:
        inertial_number: $I$.
        d50: the particles' diameter $d$, m.
        density: the particles' density $\rho$, $\mathrm{kg/m^3}$.
        pressure: the mean stress, Pa.

    Example:
        >>> from trueaniso import dem
        >>> print("%.3g /s" % dem.strain_rate_for_inertial_number(1e-3, 0.2e-3, 2500.0, 100e3))
        31.6 /s
    """
    return _e.strain_rate_for_inertial_number(float(inertial_number), float(d50), float(density), float(pressure))
