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


def _same(recorded, recipe):
    return list(recorded) == list(recipe) if isinstance(recipe, tuple) else recorded == recipe


def _said(v):
    return ", ".join("%.6g" % x for x in np.atleast_1d(v))
