"""The settings of the protocols, one object per concern, each checked once when it is made:

- ServoOptions: how a state is reached and held (triaxial.reach_state, the TrueTriaxialServo);
- ProbeOptions: how a state is probed (triaxial.probe, the StressProbe);
- PathOptions: what a study walks (study.run_states): the loading path and the probe axes.

The functions take the objects (``reach_state(scene, b, sz, servo=ServoOptions(path_rate=20))``)
and, as before, their fields as keywords (``reach_state(scene, b, sz, path_rate=20)``); either way
every value is checked for its type and range before any work, so that
``reach_state(feed_forward="no")`` is refused instead of running with the feed-forward on
(``bool("no")`` is True). A study's fingerprint (metadata.json) is made from the objects' fields
(fingerprint()), the same keys and values as before they existed.
"""
import dataclasses
import math
import numbers

from .refusal import InputError

__all__ = ["ServoOptions", "ProbeOptions", "PathOptions"]

TIME_STEP_RULES = ("smallest-inertia", "per-axis")  # dem.TIME_STEP_RULES's keys (dem loads the engines)
# The rule of the states and the probes: per-axis, the same states and moduli as smallest-inertia
# in 1.6 (spheres) to 3.2 (clump1) times fewer steps (docs/time-step.md).
DEFAULT_TIME_STEP = "per-axis"
# The rule of a study or a specimen that records none: every one made before the rule was recorded.
UNRECORDED_TIME_STEP = "smallest-inertia"
PATHS = ("true-triaxial", "cross-anisotropic")  # stress_states.PATHS
PROBE_SIDES = ("auto", "one", "two")  # ProbeOptions.sides
# What a study that records no probe sides (fingerprint probe.sides) was probed with.
UNRECORDED_PROBE_SIDES = "one"
# A probe's settle steps (ProbeOptions.settle_steps None): the speed/error scan's 100 on spheres
# (docs/speed-vs-error.md); 300 for a two-sided probe, whose sides' Holds on clump2 packings ended
# before their slow modes had followed (reciprocity 0.54 % at the worst of 39 states at 100, 0.33 % at
# 300, 2000 clumps; docs/studies/clumps.md 5j).
SETTLE_STEPS = 100
TWO_SIDED_SETTLE_STEPS = 300
AXES = ("x", "y", "z", "yz", "xz", "xy")  # triaxial.AXES


def _refuse(owner, name, value, what):
    raise InputError("%s: %s must be %s, not %r" % (owner, name, what, value))


def flag(owner, name, value):
    """`value` as a flag: True or False (or numpy's bool_), else InputError naming owner and name."""
    # numpy's bool_ too (a value read from an array); 0 and 1 and 'no' are not flags
    if not (isinstance(value, bool) or type(value).__name__ == "bool_"):
        _refuse(owner, name, value, "True or False")
    return bool(value)


def _real(owner, name, value, low=-math.inf, high=math.inf, low_open=False, high_open=False, inf=False):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        _refuse(owner, name, value, "a number")
    x = float(value)
    if math.isnan(x) or (math.isinf(x) and not (inf and x > 0)):
        _refuse(owner, name, value, "a finite number" + (" (or inf)" if inf else ""))
    ok = (x > low if low_open else x >= low) and (x < high if high_open else x <= high)
    if not ok:
        _refuse(owner, name, value, "in %s%g, %g%s" % ("(" if low_open else "[", low, high, ")" if high_open else "]"))
    return x


def _integer(owner, name, value, low):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        _refuse(owner, name, value, "an integer")
    if value < low:
        _refuse(owner, name, value, "an integer >= %d" % low)
    return int(value)


class _Options:
    """Common to the option objects: made from an object and/or keywords, fingerprinted."""
    OWNER = "options"
    NOT_FINGERPRINTED = ()  # fields that change no result (or that the fingerprint names elsewhere)

    @classmethod
    def of(cls, options=None, keywords=None, owner=None):
        """`options` (an object of this class, or None: the defaults) with `keywords` (its fields)
        replaced; a keyword that is no field is refused as Python refuses an unknown keyword."""
        keywords = dict(keywords or {})
        if options is not None and not isinstance(options, cls):
            raise TypeError("%s: expected %s, not %s" % (owner or cls.OWNER, cls.__name__, type(options).__name__))
        names = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(keywords) - names)
        if unknown:
            raise TypeError("%s() got an unexpected keyword argument %r" % (owner or cls.OWNER, unknown[0]))
        return dataclasses.replace(options or cls(), **keywords)

    def keywords(self):
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}

    @classmethod
    def defaults(cls):
        return cls().keywords()


@dataclasses.dataclass(frozen=True)
class ServoOptions(_Options):
    r"""How `triaxial.reach_state` reaches and holds a state (the TrueTriaxialServo's settings).

    Every value is checked for its type and range when the object is made; the defaults are the
    paper's protocol, every study's. The rates and step counts are per step of the reference time
    step rule (smallest-inertia), so that a rule with a longer step (per-axis, the default) loads at
    the same rate in time (docs/time-step.md). Frozen: ``dataclasses.replace(servo, path_rate=4.0)`` makes another.

    Args:
        damping: YADE's local non-viscous damping, in [0, 1).
        inertial_number: caps the cell's strain rate (quasi-static below 1e-3).
        tolerance: Pa within which each stress is held at the state.
        unbalanced: the unbalanced force of a settled state.
        path_rate: Pa per step along the path (inf: the whole load at once; docs/state-speed.md).
        max_strain: the specimen fails beyond this cell strain (StateNotReached).
        max_steps: the servo gives up after this many steps.
        stall_steps: ... or after this many steps in a row without following the path.
        hold_steps: ... or after this many steps held at the state without settling.
        friction: mu while loading (the paper's 0.5).
        control_shear: True holds the shear stresses at `shear`; False the cell's shear strains.
        shear: the shear stresses held ($\sigma_{yz}$, $\sigma_{xz}$, $\sigma_{xy}$), Pa.
        rolling_stiffness: beta of the rolling resistance (docs/rolling.md; 0 with
            `rolling_friction` 0: the paper's law).
        rolling_friction: $\eta_r$ of the rolling resistance.
        gain: the fraction of the stress error closed a step (None: the engine's 0.01).
        feed_forward: True feeds the path's rate forward through the measured tangent stiffness.
        time_step: the time step rule, "per-axis" or "smallest-inertia".

    Raises:
        trueaniso.refusal.InputError: a value of the wrong type or out of range, in one line.

    Example:
        >>> from trueaniso.options import ServoOptions
        >>> ServoOptions(path_rate=20.0).path_rate
        20.0
        >>> ServoOptions(feed_forward="no")
        Traceback (most recent call last):
        ...
        trueaniso.refusal.InputError: reach_state: feed_forward must be True or False, not 'no'
    """
    OWNER = "reach_state"
    NOT_FINGERPRINTED = ("damping", "gain")  # damping: named beside it; gain: only when set (fingerprint)

    damping: float = 0.4
    inertial_number: float = 1e-3
    tolerance: float = 100.0
    unbalanced: float = 1e-4
    path_rate: float = 2.0
    max_strain: float = 0.05
    max_steps: int = 3_000_000
    stall_steps: int = 100_000
    hold_steps: int = 200_000
    friction: float = 0.5
    control_shear: bool = True
    shear: tuple = (0.0, 0.0, 0.0)
    rolling_stiffness: float = 0.0
    rolling_friction: float = 0.0
    gain: float = None
    feed_forward: bool = False
    time_step: str = DEFAULT_TIME_STEP

    def __post_init__(self):
        o = self.OWNER
        put = object.__setattr__
        put(self, "damping", _real(o, "damping", self.damping, 0.0, 1.0, high_open=True))
        for name in ("inertial_number", "tolerance", "unbalanced", "max_strain"):
            put(self, name, _real(o, name, getattr(self, name), 0.0, low_open=True))
        put(self, "path_rate", _real(o, "path_rate", self.path_rate, 0.0, low_open=True, inf=True))
        for name in ("max_steps", "stall_steps", "hold_steps"):
            put(self, name, _integer(o, name, getattr(self, name), 1))
        put(self, "friction", _real(o, "friction", self.friction, 0.0, low_open=True))
        put(self, "control_shear", flag(o, "control_shear", self.control_shear))
        shear = self.shear
        try:
            shear = tuple(shear)
        except TypeError:
            _refuse(o, "shear", self.shear, "three shear stresses (Pa)")
        if len(shear) != 3:
            _refuse(o, "shear", self.shear, "three shear stresses (Pa)")
        put(self, "shear", tuple(_real(o, "shear", s) for s in shear))
        for name in ("rolling_stiffness", "rolling_friction"):
            put(self, name, _real(o, name, getattr(self, name), 0.0))
        if self.gain is not None:
            put(self, "gain", _real(o, "gain", self.gain, 0.0, 1.0, low_open=True))
        put(self, "feed_forward", flag(o, "feed_forward", self.feed_forward))
        if self.time_step not in TIME_STEP_RULES:
            _refuse(o, "time_step", self.time_step, "one of %s" % ", ".join(TIME_STEP_RULES))

    def fingerprint(self, p=100e3):
        """What a study's metadata.json records of it (fingerprint.state, beside damping): every
        field but the gain, which is named only when set (every study takes the engine's), and
        the mean stress p of the reach_state signature it replaced (recorded, not used)."""
        out = {k: v for k, v in self.keywords().items() if k not in self.NOT_FINGERPRINTED}
        out["shear"] = list(self.shear)
        if self.gain is not None:
            out["gain"] = self.gain
        out["p"] = p
        return out


@dataclasses.dataclass(frozen=True)
class ProbeOptions(_Options):
    """How `triaxial.probe` probes a state (the StressProbe's settings), checked when made.

    The defaults are the paper's probe, every study's.

    Args:
        gamma: the strain invariant of Eq. (12) the probe stops at.
        increment: > 0 probes by this fixed stress increment (Pa) instead of by `gamma`.
        restrain_rotations: True blocks particle rotations during the probe.
        skip_detection: True keeps the contact list of the start (nothing slides).
        damping: YADE's local non-viscous damping, in [0, 1).
        gain: gain of the probe's servo.
        relative_tolerance: stress error allowed on the held components, relative to the increment.
        unbalanced: unbalanced force at which the relaxation ends.
        settle_steps: steps in a row within tolerance that end a stage (None: 100, or 300 for a
            two-sided probe, whose Hold otherwise ends before a clump packing's slow modes have
            followed the increment: docs/triaxial.md, "Two-sided probes").
        ramp_steps: steps of the ramp of the stress increment.
        max_steps: the probe gives up after this many steps.
        control_shear: True holds the shear stresses; False the cell's shear strains (normal axes
            only).
        hold_other_strains: True holds the five other strains at zero: the modulus is then the
            stiffness $C_{kk}$, not $1/S_{kk}$ (docs/cell.md).
        time_step: the time step rule, "per-axis" or "smallest-inertia". The gain and the step
            counts are per step of smallest-inertia, so either rule probes over the same time.
        sides: "two" probes each axis from the relaxed state once with the sign and once against
            it and takes the half difference (a central difference: what the held state does by
            itself during the probe cancels); "one" is the paper's one-sided probe; "auto" (the
            default) is "two" where the scene has clumps and their rotations are free, where a
            one-sided probe's Poisson's ratios are 1-2 % off the exact static compliance, and
            "one" elsewhere (docs/triaxial.md, "Two-sided probes").

    Raises:
        trueaniso.refusal.InputError: a value of the wrong type or out of range, in one line.

    Example:
        >>> from trueaniso.options import ProbeOptions
        >>> o = ProbeOptions(restrain_rotations=True)
        >>> o.gamma, o.restrain_rotations
        (1e-06, True)
    """
    OWNER = "probe"
    # sides and settle_steps: recorded as they resolve on the study's specimen (fingerprint).
    NOT_FINGERPRINTED = ("gamma", "restrain_rotations", "skip_detection", "damping", "gain", "sides", "settle_steps")

    gamma: float = 1e-6
    increment: float = 0.0
    restrain_rotations: bool = False
    skip_detection: bool = False
    damping: float = 0.4
    gain: float = 0.03
    relative_tolerance: float = 2e-3
    unbalanced: float = 1e-5
    settle_steps: object = None
    ramp_steps: int = 300
    max_steps: int = 2_000_000
    control_shear: bool = True
    hold_other_strains: bool = False
    time_step: str = DEFAULT_TIME_STEP
    sides: str = "auto"

    def __post_init__(self):
        o = self.OWNER
        put = object.__setattr__
        put(self, "gamma", _real(o, "gamma", self.gamma, 0.0, low_open=True))
        put(self, "increment", _real(o, "increment", self.increment, 0.0))
        for name in ("restrain_rotations", "skip_detection", "control_shear", "hold_other_strains"):
            put(self, name, flag(o, name, getattr(self, name)))
        put(self, "damping", _real(o, "damping", self.damping, 0.0, 1.0, high_open=True))
        put(self, "gain", _real(o, "gain", self.gain, 0.0, 1.0, low_open=True))
        for name in ("relative_tolerance", "unbalanced"):
            put(self, name, _real(o, name, getattr(self, name), 0.0, low_open=True))
        if self.settle_steps is not None:
            put(self, "settle_steps", _integer(o, "settle_steps", self.settle_steps, 0))
        put(self, "ramp_steps", _integer(o, "ramp_steps", self.ramp_steps, 0))
        put(self, "max_steps", _integer(o, "max_steps", self.max_steps, 1))
        if self.time_step not in TIME_STEP_RULES:
            _refuse(o, "time_step", self.time_step, "one of %s" % ", ".join(TIME_STEP_RULES))
        if not (isinstance(self.sides, str) and self.sides in PROBE_SIDES):
            _refuse(o, "sides", self.sides, "one of %s" % ", ".join(PROBE_SIDES))

    def two_sided(self, clumps, rotations_blocked=False):
        """Whether a probe with these options is two-sided on a scene with (`clumps`) or without
        clumps whose rotations are or are not blocked scene-wide: "auto" makes it two-sided where
        the bodies are clumps free to rotate."""
        if self.sides == "auto":
            return bool(clumps) and not (self.restrain_rotations or rotations_blocked)
        return self.sides == "two"

    def settle(self, two_sided):
        """The steps in a row within tolerance that end a stage: `settle_steps`, or when that is None
        SETTLE_STEPS, TWO_SIDED_SETTLE_STEPS for a two-sided probe."""
        if self.settle_steps is not None:
            return self.settle_steps
        return TWO_SIDED_SETTLE_STEPS if two_sided else SETTLE_STEPS

    def fingerprint(self, clumps=False, rotations_blocked=False):
        """What a study's metadata.json records of it (fingerprint.probe): gamma, rotations,
        detection and damping by their names there, then every other field but the gain, the sides
        and the settle steps as they resolve on a specimen with or without `clumps` (an "auto" or a
        None is no answer: a study asked for two sides and one left at "auto" on clumps are one)."""
        out = dict(gamma=self.gamma, rotations="restrained" if self.restrain_rotations else "free",
                   detection="off" if self.skip_detection else "on", damping=self.damping)
        out.update({k: v for k, v in self.keywords().items() if k not in self.NOT_FINGERPRINTED})
        two = self.two_sided(clumps, rotations_blocked)
        out.update(sides="two" if two else "one", settle_steps=self.settle(two))
        return out


@dataclasses.dataclass(frozen=True)
class PathOptions(_Options):
    r"""What `study.run_states` walks: the loading path and the probe axes of each state.

    Args:
        path: "true-triaxial" (Table C1's paths, p = 100 kPa) or "cross-anisotropic" (Fig. 16:
            $\sigma_x = \sigma_y = 100$ kPa).
        probes: the probe axes, each at most once: "x", "y", "z", "yz", "xz", "xy" (or 0-5, or
            "zy", "zx", "yx"), kept as their names.

    Raises:
        trueaniso.refusal.InputError: an unknown path or axis, an axis given twice, no axis.

    Example:
        >>> from trueaniso.options import PathOptions
        >>> PathOptions(probes=(2, "yz")).probes
        ('z', 'yz')
    """
    OWNER = "run_states"

    path: str = "true-triaxial"
    probes: tuple = ("z", "x", "y")

    def __post_init__(self):
        if self.path not in PATHS:
            raise InputError("unknown path %r: the paths are %s" % (self.path, ", ".join(PATHS)))
        probes = self.probes
        if isinstance(probes, str) or not hasattr(probes, "__iter__"):
            _refuse(self.OWNER, "probes", probes, "a sequence of probe axes (e.g. ('z', 'x', 'y'))")
        names = []
        for a in probes:
            if isinstance(a, str) and a in AXES + ("zy", "zx", "yx"):
                names.append(a if a in AXES else a[::-1])
            elif isinstance(a, numbers.Integral) and not isinstance(a, bool) and 0 <= a < 6:
                names.append(AXES[int(a)])
            else:
                _refuse(self.OWNER, "probes", self.probes, "probe axes among %s (or 0-5)" % ", ".join(AXES))
        if not names:
            _refuse(self.OWNER, "probes", self.probes, "at least one probe axis")
        if len(set(names)) != len(names):
            raise InputError("each probe axis may be given once")
        object.__setattr__(self, "probes", tuple(names))
