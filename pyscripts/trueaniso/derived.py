"""Derived quantities of a specimen file checked against what they derive from.

A clump of a named assembly (clump1, clump2) is its assembly's template (clump_shapes, the shape
its parameters record, else its recipe's) scaled to its size: its members' offsets and radii are
the template's times one factor, its mass is the density times the template's volume times the
factor cubed, its principal moments the density times the template's moments times the factor to
the fifth. A file whose members are another template (clump1 labelled clump2) or whose mass or
inertia were changed is refused naming the body: the checksum only proves the file is the one
written. A clump packing without an assembly (YADE's, through the bridge) keeps YADE's own mass
properties (summed over members), and is not checked here.
"""
import math

import numpy as np

# Members as placed from the template: the factor is recovered from one radius, so offsets and
# radii agree to rounding (1e-16); masses and moments go through the union's volume and moments
# computed once per shape, 1e-12 apart at most. An edited value is off by far more.
MEMBERS_RTOL = 1e-9
MASS_RTOL = 1e-6


def clump_problem(arrays, meta):
    """What in a clump specimen disagrees with its template and density, or None."""
    mb = np.asarray(arrays["member_begin"])
    counts = np.diff(mb)
    if counts.size == 0 or np.all(counts == 1):
        return None
    params = meta.get("parameters") or {}
    assembly = params.get("assembly")
    if assembly not in ("clump1", "clump2"):
        return None
    from . import clump_recipes, clump_shapes
    for other, r in clump_recipes.RECIPES.items():  # a prepared file records its recipe: another's is a relabel
        if other != assembly and all(k in params and _same(params[k], r[k]) for k in RECIPE_KEYS):
            return ("parameters.assembly: %s, but its parameters record the %s recipe (%s): the assembly label does "
                    "not match the members" % (assembly, other, ", ".join(RECIPE_KEYS)))
    shape = params.get("shape") or clump_recipes.recipe(assembly)["shape"]
    try:
        t = clump_shapes.template(shape)
    except ValueError as exc:
        return "parameters.shape: %s" % exc
    k = len(t.radii)
    bad = np.flatnonzero(counts != k)
    if bad.size:
        b = int(bad[0])
        return ("body %d has %d member spheres, but a clump of %s (shape %s) has %d: the assembly label does not "
                "match the members" % (b, counts[b], assembly, shape, k))
    nb = counts.size
    radii = np.asarray(arrays["radii"], dtype=float).reshape(nb, k)
    offsets = np.asarray(arrays["member_offsets"], dtype=float).reshape(nb, k, 3)
    f = radii[:, 0] / t.radii[0]
    size = f[:, None] * np.max(t.radii)
    off_error = np.max(np.abs(offsets - f[:, None, None] * t.offsets[None]), axis=2)
    rad_error = np.abs(radii - f[:, None] * t.radii[None])
    wrong = np.flatnonzero(np.any((off_error > MEMBERS_RTOL * size) | (rad_error > MEMBERS_RTOL * size), axis=1))
    if wrong.size:
        return ("body %d: its members are not the %s template (shape %s) at any size: the assembly label does not "
                "match the members" % (wrong[0], assembly, shape))
    density = float(meta["material"]["density"])
    checks = (("mass", np.asarray(arrays["masses"], dtype=float)[:, None], (density * t.volume * f ** 3)[:, None]),
              ("principal moments of inertia", np.asarray(arrays["inertia"], dtype=float),
               density * np.asarray(t.inertia)[None] * (f ** 5)[:, None]))
    for what, stored, expected in checks:
        off = np.abs(stored / expected - 1)
        if np.any(off > MASS_RTOL):
            b = int(np.argmax(np.max(off, axis=1)))
            return ("body %d: its %s %s disagree with its members and the density (%s: the %s template's, scaled)"
                    % (b, what, _said(stored[b]), _said(expected[b]), assembly))
    return None


RECIPE_KEYS = ("shape", "orientation_weights", "layers")  # what makes one assembly's clumps another's


def recipe_problem(meta):
    """Why a specimen file's recipe name and the settings it records disagree, or None: a file that
    names a variant of its assembly's recipe (clump_recipes.VARIANTS: parameters.recipe) records
    each of the variant's settings as the variant has it (frictionless is mu_prep 0; a file of
    'frictionless' with mu_prep 0.3 is not that recipe, whatever made it)."""
    params = meta.get("parameters") or {}
    name = params.get("recipe")
    if name is None:
        return None
    from . import clump_recipes
    assembly = params.get("assembly", "sphere")
    try:
        settings = clump_recipes.variant(assembly, name)
    except ValueError as exc:
        return "parameters.recipe: %s" % exc
    for key, value in settings.items():
        if key in params and not _same(params[key], value):
            return ("parameters.recipe: %s sets %s = %r, but parameters.%s is %r: the recipe's name and its settings "
                    "disagree" % (name, key, value, key, params[key]))
    return None


def _same(recorded, recipe):
    return list(recorded) == list(recipe) if isinstance(recipe, tuple) else recorded == recipe


def _said(v):
    return ", ".join("%.6g" % x for x in np.atleast_1d(v))


# A stored time step against the one derived again on load: the bounds move with the positions
# within a step (8e-7 of the step measured on the committed clump specimen, 0 on the spheres,
# whose step is the cap of their radii and masses); an edited one is off by far more.
TIME_STEP_RTOL = 1e-3


# A packing whose contacts carry this many times the stress its summary records is not the packing
# its steps were derived on (an edited or exploded one): its contacts' stiffness bound says nothing
# of its stored step, and the study refuses it for its stress (study.EXPLODED) with that reason.
NOT_AS_RECORDED = 10.0


def _packing_not_as_recorded(scene, meta):
    summary = meta.get("summary") or {}
    recorded = [abs(summary[k]) for k in ("sigma_x", "sigma_y", "sigma_z") if isinstance(summary.get(k), (int, float))]
    if not recorded or max(recorded) <= 0:
        return False
    from . import engines
    try:
        largest = float(np.max(np.abs(np.linalg.eigvalsh(np.asarray(engines.stress(scene))))))
    except (ValueError, RuntimeError):
        return False
    return not math.isfinite(largest) or largest > NOT_AS_RECORDED * max(recorded)


def time_step_problem(scene, meta):
    """Why the time steps a specimen file stores are not those its time step rules derive from its
    material, radii and masses (dem.Chain: the cap reference_time_step at the rule's factor, and
    the rule's stiffness bound on the contacts), or None: reference_dt (dt where the file stores
    none) the reference rule's, dt between the shortest and the longest step of the rules. The
    stored step starts the next run: the servos scale their per-step settings by dt / reference_dt
    on its first step, so an edited one moves the whole path that follows. Checked
    where a file records that trueaniso made it (a preparation's or a study's parameters); a scene
    saved from YADE keeps YADE's dt, which the first step replaces, and a preparation's checkpoint
    is mid-way (its cap is of the radii it grows to), so neither is held to a rule."""
    params = meta.get("parameters") or {}
    made_here = "state" in params or ("n" in params and "seed" in params)
    if "checkpoint" in params or not (made_here or "reference_dt" in meta):
        return None
    from . import dem, engines
    if _packing_not_as_recorded(scene, meta):
        return None
    derived = {}
    for rule, (per_axis, safety) in dem.TIME_STEP_RULES.items():
        bound = (engines.TimeStepper.per_axis_bound if per_axis else engines.TimeStepper.stiffness_bound)(scene)
        cap = dem.reference_time_step(scene, safety=safety)
        derived[rule] = min(cap, safety * bound) if math.isfinite(bound) else cap

    def near(x, y):
        return abs(x - y) <= TIME_STEP_RTOL * y
    reference = meta.get("reference_dt", meta["dt"])
    want = derived[dem.REFERENCE_TIME_STEP]
    if not near(reference, want):
        field = "reference_dt" if "reference_dt" in meta else "dt"
        return ("%s: %.6g s, but its %s time step rule gives %.6g s from its material, radii and masses (%.4g times "
                "it): the stored step was edited" % (field, reference, dem.REFERENCE_TIME_STEP, want, reference / want))
    # The step itself: within the rules' range (a rule's factor may change between versions; a step
    # shorter or longer than every rule's is none of them).
    lo, hi = min(derived.values()), max(derived.values())
    if made_here and not (1 - TIME_STEP_RTOL) * lo <= meta["dt"] <= (1 + TIME_STEP_RTOL) * hi:
        return ("dt: %.6g s, but its time step rules give %s from its material, radii and masses: the stored step was "
                "edited" % (meta["dt"], ", ".join("%.6g s (%s)" % (d, r) for r, d in derived.items())))
    return None
