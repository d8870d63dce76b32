"""The recipes of the clump assemblies clump1 and clump2 (clump_specimen.py says how each is
prepared): their template shape, size distribution, orientation weights, layers and stage
settings; and the named variants of every assembly's recipe, the spheres' too. Data only, so that
the checks of a specimen file (derived.py) can read them without the preparation's imports.
"""

RECIPES = {
    "clump1": dict(shape="pentamer-2.0", d50=0.195e-3, cu=1.25, orientation_weights=(1.0, 1.0, 10.0), layers=1,
                   stage1_rotations="blocked", stage1_pressure=10e3, mu_prep=0.01, mu_free=None, mu_final=0.5,
                   phi_cell=0.62, switch_fraction=0.05),
    "clump2": dict(shape="dimer-1.5", d50=0.216e-3, cu=1.43, orientation_weights=(1.0, 1.0, 0.3), layers=4,
                   stage1_rotations="blocked", stage1_pressure=5e3, mu_prep=0.01, mu_free=0.25, mu_final=0.5,
                   phi_cell=0.55, switch_fraction=1.0),
}


def recipe(assembly, **overrides):
    if assembly not in RECIPES:
        raise ValueError("unknown clump assembly %r (available: %s)" % (assembly, ", ".join(RECIPES)))
    r = dict(RECIPES[assembly])
    for k, v in overrides.items():
        if k not in r:
            raise ValueError("%s: unknown recipe parameter %r (parameters: %s)" % (assembly, k, ", ".join(r)))
        if v is not None:
            r[k] = v
    if r["stage1_rotations"] not in ("blocked", "free"):
        raise ValueError("stage1_rotations must be 'blocked' or 'free'")
    if not r["stage1_pressure"] > 0:
        raise ValueError("stage1_pressure must be > 0")
    return r


# Named variants of a recipe: settings of prepare_spheres or prepare_clumps (recipe parameters or
# their own keywords) that differ from the assembly's defaults (docs/specimens.md; docs/clumps.md,
# section 5b, has the clumps' measurements).
VARIANTS = {
    # spheres: the friction switched to 0.5 at the final pressure, the radii grown there at 0.015
    # (without the unloading the packing loses 0.34 of Zm along the Table C1 paths); the radii grown at
    # 0.015 to 5 kPa only, without the unloading (700,000 steps at 1000 and 4000 spheres, its creep
    # to 5 kPa); and the default unloaded to 5 kPa instead of 20 (denser: e 0.572, Zm 5.89 at 1000
    # spheres) (docs/studies/specimens.md, "Spheres: old and new recipes").
    "sphere": {"grown-to-target": dict(switch_fraction=1.0), "grown-to-switch": dict(unload=False, switch_fraction=0.05),
               "unloaded-to-5kPa": dict(switch_fraction=0.05)},
    # clump2 without the free expansion at 0.25: rotations blocked and friction 0.01 up to
    # the target, long axes weighted 0.5, the friction switched to 0.5 at the target (e 0.629 at 4000
    # clumps, compacting along the Table C1 paths); and that recipe grown frictionless (mu_prep 0):
    # fewer rattlers and a higher Zm at 1000 clumps, e 0.01 below the paper's 0.636 instead of above.
    "clump2": {"grown-to-target": dict(orientation_weights=(1.0, 1.0, 0.5), stage1_pressure=100e3),
               "frictionless": dict(orientation_weights=(1.0, 1.0, 0.5), stage1_pressure=100e3, mu_prep=0.0)},
    # clump1 with the cell holding the normal stresses at their mean while the radii grow
    # (RadiusExpansion.hold_deviator, gain 0.05): the same recipe otherwise. It takes the normal
    # deviator from 7-9 % of p to under 1 % but does not shorten the preparation (docs/clumps.md, 5c).
    # clump1 with its radii grown by a servo of gain 0.1 instead of 0.002 (the consolidation servo's
    # too): p is reached 5 times sooner, and the packing's densification at friction 0.002, which
    # the stage waits out, then sets the steps. With --time-step per-axis, 2.1-4.0 times fewer steps
    # at 300 clumps, e and E_z/E_x within the recipe's scatter between seeds (docs/clumps.md, 5c).
    # clump1 without the unloading, of three balls (trimer-2.0, e 0.470 at 4000 clumps,
    # where the smoother pentamer-2.0 packs to 0.439 at 300), grown at friction 0.002, the friction
    # switched at the target.
    # clump1 grown (and unloaded) at friction 0.002 instead of 0.01, the pentamer recipe otherwise:
    # e 0.430 at 1000 clumps, 0.015 below the paper's 0.445 (docs/studies/clumps.md, 5g).
    "clump1": {"hold-deviator": dict(hold_deviator=0.05), "fast-growth": dict(gain=0.1),
               "grown-to-target": dict(shape="trimer-2.0", switch_fraction=1.0, mu_prep=0.002),
               "grown-at-0.002": dict(mu_prep=0.002)},
}


def variant(assembly, name):
    """The settings of the named variant of an assembly's recipe (a dict of prepare_spheres or
    prepare_clumps keywords)."""
    if assembly not in RECIPES and assembly != "sphere":
        raise ValueError("unknown assembly %r (available: sphere, %s)" % (assembly, ", ".join(RECIPES)))
    own = VARIANTS.get(assembly, {})
    if name not in own:
        raise ValueError("%s has no recipe variant %r (variants: %s)" % (assembly, name, ", ".join(own) or "none"))
    return dict(own[name])
