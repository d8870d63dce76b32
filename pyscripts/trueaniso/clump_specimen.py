"""Clump specimens clump1 and clump2: a loose random packing of clumps with a preferred orientation,
compacted by radius expansion and consolidated isotropically (docs/specimens.md, "Clump specimens").

The paper only cites its two preparation methods; our readings of them:

- clump1, "two-stage isotropic consolidation" (after Zhao & Guo 2015): clumps generated with
  their long axes favouring the vertical, stage 1 compacts them with particle rotation blocked
  until the network carries 10 kPa (the orientation fabric is kept while the contact network
  forms), stage 2 releases rotation, compacts to the isotropic 100 kPa and consolidates there with
  the final friction;
- clump2, "multi-layer rotational replication" (after Zhou et al. 2026b, c): one horizontal layer
  of clumps lying near the horizontal is generated, and the specimen is built from copies of it
  stacked along z, copy k turned by k x 90 degrees about z (which maps the square periodic cell
  onto itself), so the two horizontal directions are equivalent by construction; stage 1 (rotation
  blocked) goes to 100 kPa, stage 2 consolidates there with the final friction.

Recipe parameters live in RECIPES (clump_recipes); every one can be overridden by a keyword of prepare_clumps.
"""
import math
import time

import numpy as np

from . import clump_shapes, dem, engines, prep_checkpoint as _checkpointed, psd as _psd, specimen
# The recipes are data that the checks of a specimen file read too (derived.py); kept importable here.
from .clump_recipes import RECIPES, recipe  # noqa: F401


__all__ = ["prepare_clumps", "check_count", "least_layered_count", "PreparationError"]


class PreparationError(RuntimeError):
    """A stage of a clump preparation did not converge within its steps."""


def random_sequential_clumps(template, scales, quats, box, rng, periodic_z=True, max_attempts=100000):
    """Centres of clumps (template scaled by `scales`, turned by `quats`) placed one by one at
    random in `box` without any member overlapping a member of another clump, largest first.
    The box is periodic in x and y, and in z if periodic_z; otherwise every member must lie inside
    0 <= z <= box_z (a layer that can be stacked). Returns the centres (n, 3)."""
    n = len(scales)
    off, rad = template.offsets, template.radii
    rmax = float(scales.max() * rad.max())
    ncell = np.maximum(1, np.floor(box / (2.0 * rmax)).astype(int))
    cell = box / ncell
    wrap = np.array([True, True, periodic_z])
    around = np.array([(dx, dy, dz) for dx in (-1, 0, 1) for dy in (-1, 0, 1) for dz in (-1, 0, 1)])
    grid = {}
    mpos = np.empty((n * len(rad), 3))
    mrad = np.empty(n * len(rad))
    used = 0
    centres = np.empty((n, 3))

    def cells_of(points):
        c = np.floor(points / cell).astype(int)
        c[:, wrap] %= ncell[wrap]
        return c

    for k in np.argsort(-scales, kind="stable"):
        local = scales[k] * clump_shapes.rotated(off, clump_shapes.rotation_matrix(quats[k]))
        r = scales[k] * rad
        lo_z, hi_z = (r - local[:, 2]).max(), (box[2] - r - local[:, 2]).min()
        if not periodic_z and hi_z <= lo_z:
            raise ValueError("the layer is thinner than a clump: use fewer layers or more particles")
        for _ in range(max_attempts):
            c = rng.random(3) * box
            if not periodic_z:
                c[2] = lo_z + rng.random() * (hi_z - lo_z)
            p = c + local
            keys = (cells_of(p)[:, None, :] + around[None, :, :]).reshape(-1, 3)
            keys[:, wrap] %= ncell[wrap]
            idx = [i for key in set(map(tuple, keys)) for i in grid.get(key, ())]
            if idx:
                d = mpos[idx][None, :, :] - p[:, None, :]
                d[..., wrap] -= box[wrap] * np.round(d[..., wrap] / box[wrap])
                squared = d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1] + d[..., 2] * d[..., 2]
                if np.any(squared < (r[:, None] + mrad[idx][None, :]) ** 2):
                    continue
            break
        else:
            raise ValueError("the size distribution cannot fit the box: random placement failed")
        centres[k] = c
        cp = cells_of(p)
        cp[:, 2] = np.clip(cp[:, 2], 0, ncell[2] - 1)
        for q, rq, key in zip(p, r, map(tuple, cp)):
            grid.setdefault(key, []).append(used)
            mpos[used], mrad[used] = q, rq
            used += 1
    return centres


def _layer(n, template, size_distribution, seed, orientation_weights, phi_cell, layers, phi_start):
    """The random draws of one layer and its box: (rng, equivalent diameters, orientations, cell
    side, start factor, layer box). The template has d_eq = 1."""
    rng = np.random.default_rng(seed)
    per_layer = n // layers
    d = size_distribution.sample(per_layer, rng)
    quats = clump_shapes.orientations(per_layer, rng, orientation_weights)
    side = math.cbrt(layers * template.volume * np.sum(d * d * d) / phi_cell)  # no pow: psd.sample says why
    start = math.cbrt(phi_start / phi_cell)
    return rng, d, quats, side, start, np.array([side, side, side / layers])


def _thin_layer(n, template, d, quats, start, box, layers):
    """(why a layer of stacked copies cannot hold its clumps: one is taller than the layer as
    drawn, a first-order estimate of the count that would) or None. Depends on the draws, so on n
    and the seed: a small clump2 (4 layers) fails at some seeds only, and is refused here, before
    the estimate line, not with an internal message after it."""
    if layers == 1:
        return None

    def height(k):  # what random_sequential_clumps needs: lo_z < hi_z
        z = start * d[k] * clump_shapes.rotated(template.offsets, clump_shapes.rotation_matrix(quats[k]))[:, 2]
        r = start * d[k] * np.asarray(template.radii)
        return float((z + r).max() + (r - z).max())

    tallest = max(height(k) for k in range(len(d)))
    if tallest < box[2]:
        return None
    need = layers * int(np.ceil(n / layers * (tallest / box[2]) ** 3 * 1.2))  # thickness grows as n^(1/3)
    return ("%d clumps in %d stacked layers make each layer %.3g mm thick, less than its tallest clump as drawn "
            "(%.3g mm)" % (n, layers, 1e3 * box[2], 1e3 * tallest), need)


def layers_problem(assembly, n, seed, phi_start=0.20, **overrides):
    """Why the assembly's stacked layers (its recipe with `overrides`: d50, cu, phi_cell) cannot
    hold n clumps drawn with this seed, or None (prepare_specimen.py and run_study.py ask before
    any work). The message names the least count that fits (least_layered_count)."""
    thin = _layers_check(assembly, seed, phi_start, overrides)(n)
    if thin is None:
        return None
    # The estimate ignores that more clumps draw a taller one: followed, it leads from 28 to 60 to
    # 116. The draws are cheap at these counts, so the least count that fits with
    # this seed is searched and named instead; the estimate only where none is found.
    why = thin[0]
    least = least_layered_count(assembly, n + recipe(assembly)["layers"], seed, phi_start, **overrides)
    if least is None:
        return _with_estimate(thin)
    return "%s: --n %d is the least that fits with this seed (or give another --seed)" % (why, least)


def _with_estimate(thin):
    return "%s: give --n of about %d or more (or another --seed)" % thin


def least_layered_count(assembly, start, seed, phi_start=0.20, **overrides):
    """The least count >= `start` that the recipe builds and whose layers hold their clumps with this seed.

    A count the recipe builds is a multiple of its layers; a layer too thin for its clumps is refused
    by the preparation (`layers_problem`).

    Args:
        assembly: "clump1" or "clump2".
        start: the least count wanted.
        seed: the seed of the preparation.
        phi_start: the solid fraction of the placement.
        **overrides: any parameter of the recipe.

    Returns:
        int or None: None if no count within 20 x `start` fits.

    Example:
        >>> from trueaniso import clump_specimen
        >>> clump_specimen.least_layered_count("clump2", 10, seed=1)
        52
    """
    layers = recipe(assembly, **overrides)["layers"]
    fits = _layers_check(assembly, seed, phi_start, overrides)
    first = -(-start // layers) * layers
    return next((m for m in range(first, 20 * first + 100 * layers, layers) if fits(m) is None), None)


def _layers_check(assembly, seed, phi_start, overrides):
    r = recipe(assembly, **overrides)
    t = clump_shapes.template(r["shape"])
    dist = _psd.SizeDistribution.from_d50_cu(r["d50"], r["cu"])

    def problem(m):
        _, d, quats, _, start, box = _layer(m, t, dist, seed, r["orientation_weights"], r["phi_cell"], r["layers"],
                                            phi_start)
        return _thin_layer(m, t, d, quats, start, box, r["layers"])
    return problem


def random_loose_clumps(n, template, size_distribution, seed, orientation_weights, phi_cell, layers=1,
                        phi_start=0.20):
    """n clumps at random, orientations from clump_shapes.orientations(weights), sized by the
    equivalent diameter drawn from the size distribution; the cell fits them at phi_cell (union
    volumes). With layers > 1, n / layers clumps fill one layer of height side / layers and the
    cell is its copies turned by k x 90 degrees about z (rotational replication).

    Returns (positions, quaternions, final scales, start factor, cell size): clumps are placed at
    start factor x their final size (solid fraction phi_start). Random sequential placement of
    elongated clumps slows down steeply above 0.2 (1000 dimers: 1.2 s at 0.2, 4.7 s at 0.25,
    15 s at 0.3), and radius expansion makes up the difference in a few thousand steps."""
    if n < 1:
        raise ValueError("number of clumps must be >= 1")
    if layers < 1 or n % layers:
        raise ValueError("the number of clumps (%d) must be a multiple of the number of layers (%d)" % (n, layers))
    if not 0.05 <= phi_start < phi_cell < 0.75:
        raise ValueError("solid fractions must satisfy 0.05 <= phi_start < phi_cell < 0.75")
    rng, d, quats, side, start, box = _layer(n, template, size_distribution, seed, orientation_weights, phi_cell,
                                            layers, phi_start)
    thin = _thin_layer(n, template, d, quats, start, box, layers)
    if thin:
        raise ValueError(_with_estimate(thin))
    centres = random_sequential_clumps(template, start * d, quats, box, rng, periodic_z=(layers == 1))
    pos, qs = [centres], [quats]
    for k in range(1, layers):
        c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][k % 4]
        turned = np.column_stack([c * centres[:, 0] - s * centres[:, 1], s * centres[:, 0] + c * centres[:, 1],
                                  centres[:, 2] + k * box[2]])
        turned[:, :2] %= side
        half = 0.5 * math.pi * (k % 4)
        rz = np.array([math.cos(0.5 * half), 0.0, 0.0, math.sin(0.5 * half)])
        pos.append(turned)
        qs.append(np.array([clump_shapes.quaternion_product(rz, q) for q in quats]))
    pos, quats, d = np.vstack(pos), np.vstack(qs), np.tile(d, layers)
    ncell = max(1, int(side // (2.0 * template.bounding_radius * d.max())))
    along = specimen.grid_rows(pos, side / ncell)
    return pos[along], quats[along], d[along], start, np.full(3, side)


def particles(n, assembly):
    """'1000 spheres', '53004 clump1 clumps': a count of particles in the log's words."""
    return "%d %s" % (n, "spheres" if assembly == "sphere" else "%s clumps" % assembly)


def bounding_diameter(assembly):
    """Largest length of an assembly's clump over its equivalent diameter."""
    return 2.0 * clump_shapes.template(recipe(assembly)["shape"]).bounding_radius


def members_per_clump(assembly):
    """Member spheres of one clump of the assembly's shape."""
    return len(clump_shapes.template(recipe(assembly)["shape"]).radii)


def check_count(assembly, n):
    """Refuse a count of clumps the assembly's recipe cannot build (its layers must divide it).

    Raises:
        ValueError: with the reason.

    Example:
        >>> from trueaniso import clump_specimen
        >>> clump_specimen.check_count("clump2", 1000)
        >>> clump_specimen.check_count("clump2", 1001)
        Traceback (most recent call last):
        ...
        ValueError: clump2 is built from 4 identical layers: --n must be a multiple of 4
    """
    layers = recipe(assembly)["layers"]
    if n < layers or n % layers:
        raise ValueError("%s is built from %d identical layers: --n must be a multiple of %d" % (assembly, layers, layers))


def prepare_clumps(assembly, n, seed=1, pressure=100e3, damping=0.4, inertial_number=1e-2, prep_unbalanced=1e-2,
                   unbalanced=1e-3, stress_tolerance=100.0, gain=0.002, max_steps=5_000_000, progress=None,
                   checkpoints=None, hold_deviator=None, switch_pressure=None, **overrides):
    """A clump specimen consolidated isotropically to `pressure` (module doc; docs/specimens.md).

    The final state is in force and moment balance below `unbalanced`, so a probe or a static solve
    with rotations free starts from it.

    Args:
        assembly: "clump1" or "clump2".
        n: number of clumps (a multiple of the recipe's layers: `check_count`).
        seed: seed of the random placement and orientations.
        pressure: isotropic stress of the specimen, Pa.
        damping: YADE's local non-viscous damping.
        inertial_number: caps the rate of growth and of the cell.
        prep_unbalanced: unbalanced force at which a stage of growth stops.
        unbalanced: unbalanced force at which the consolidation stops.
        stress_tolerance: every stress within this of `pressure` (Pa) at the end.
        gain: gain of the cell servo.
        max_steps: each stage gives up after this many steps (`PreparationError`).
        progress: a `progress.Progress` for progress lines, or None.
        checkpoints: as in `specimen.prepare_spheres`: an interrupted preparation resumes.
        hold_deviator: a gain in (0, 1]: while the radii grow, the cell holds the normal stresses at
            their mean at constant volume with that gain; None: the growth is at a fixed cell.
        switch_pressure: the mean stress to which the packing grown to `pressure` is unloaded (rotations
            as the growth left them, its friction), where the friction becomes mu_final and the cell
            servo compresses it to `pressure`. None: the recipe's ``switch_fraction`` of `pressure`
            (`specimen.default_switch_pressure`); `pressure`: no unloading (every recipe before it).
        **overrides: any parameter of the recipe (`clump_recipes.RECIPES`), e.g. ``mu_prep``.

    Returns:
        (scene, log): the engines' Scene at rest at the state, and a dict of the recipe and the
        steps and wall time of each stage.

    Raises:
        ValueError: an unknown assembly or parameter, a count the layers cannot hold, a pressure
            <= 0, a negative friction, a switch pressure out of range.
        PreparationError: a stage did not converge within `max_steps`.

    Example:
        >>> from trueaniso import clump_specimen, specimen
        >>> scene, log = clump_specimen.prepare_clumps("clump1", 20, seed=1)
        >>> s = specimen.state(scene)
        >>> print("%d clumps of %d spheres, p = %.0f kPa" % (scene.num_bodies, scene.num_members // scene.num_bodies,
        ...                                                   s["p"] / 1e3))
        20 clumps of 5 spheres, p = 100 kPa
    """
    if hold_deviator is not None and not 0 < hold_deviator <= 1:
        raise ValueError("hold_deviator %r: the deviator hold's gain must lie in (0, 1]" % (hold_deviator,))
    if pressure <= 0:
        raise ValueError("pressure must be > 0")
    r = recipe(assembly, **overrides)
    if r["mu_prep"] < 0 or r["mu_final"] < 0 or (r["mu_free"] or 0.0) < 0:
        raise ValueError("friction coefficients must be >= 0")
    switch = switch_pressure
    if switch is None:
        switch = specimen.default_switch_pressure(pressure, r["switch_fraction"], stress_tolerance)
    problem = switch != pressure and specimen.switch_pressure_problem(switch, pressure, stress_tolerance)
    if problem:
        raise ValueError(problem)
    t0 = time.time()
    tmpl = clump_shapes.template(r["shape"])
    resumed = checkpoints.resume() if checkpoints is not None else None
    if resumed:
        scene, place = resumed
    else:
        dist = _psd.SizeDistribution.from_d50_cu(r["d50"], r["cu"])
        pos, quats, d, start, side = random_loose_clumps(n, tmpl, dist, seed, r["orientation_weights"],
                                                         r["phi_cell"], layers=r["layers"])

        def scene_at(factor):
            s = engines.Scene()
            s.shear_modulus, s.poisson, s.density, s.friction = 18e9, 0.15, 2500.0, r["mu_prep"]
            s.cell_size = s.cell_ref_size = side
            engines.add_clumps(s, tmpl, pos, quats, factor * d)
            return s

        scene = scene_at(start)
        # Stage 1: compaction by radius expansion, rotations blocked or free.
        scene.block_rotations = r["stage1_rotations"] == "blocked"
        # The growth scale so far multiplies the controllers' own (one per run between checkpoints).
        final = scene_at(1.0)
        place = dict(stage="gas", steps={}, start_scale=start, grown_scale=1.0, generation_time=time.time() - t0,
                     max_dt=dem.reference_time_step(final, pressure))
        if switch < pressure:  # the unloaded packing's cap, as the spheres' (specimen.prepare_spheres)
            place["unloading_max_dt"] = dem.reference_time_step(final, switch)
        place["elapsed"] = time.time() - t0
    rate = dem.strain_rate_for_inertial_number(inertial_number, r["d50"], scene.density, pressure)
    expanding = ("gas", "stage 1", "expansion")

    def build(st):
        if st.at("unloading"):
            st.controller = specimen.expansion(switch, gain, rate, stress_tolerance, prep_unbalanced)
            st.chain = dem.Chain(st.scene, damping=damping, controllers=[st.controller],
                                 max_dt=st.place["unloading_max_dt"])
        elif st.place["stage"] in expanding:
            # The loose start (solid fraction 0.2) carries no stress: grow 10 times faster until the
            # contact network takes 1 % of the target pressure (the rate cap only matters under load).
            st.controller = specimen.expansion(pressure, gain, 10.0 * rate if st.at("gas") else rate,
                                               stress_tolerance, prep_unbalanced)
            if hold_deviator is not None:
                st.controller.hold_deviator = True
                st.controller.deviator_gain = hold_deviator
            st.chain = dem.Chain(st.scene, damping=damping, controllers=[st.controller], max_dt=st.place["max_dt"])
        else:
            st.controller = specimen.consolidation(pressure, gain, rate, stress_tolerance, unbalanced)
            st.chain = dem.Chain(st.scene, damping=damping, controllers=[st.controller])

    def fold(st):
        if st.place["stage"] in expanding + ("unloading",):
            st.place["grown_scale"] *= st.controller.scale

    st = _checkpointed.Stages(scene, place, checkpoints, build, fold)
    first = _checkpointed.FIRST_STAGES_CHUNK
    if not st.run("gas", first, lambda: st.controller.pressure >= 0.01 * pressure, max_steps, progress,
                  "expansion (gas)", check_first=True):  # long specimens spend minutes here: say so
        raise PreparationError("the loose packing did not take 1 %% of the pressure within %d steps" % max_steps)
    if st.at("gas"):
        st.controller.max_growth_rate = rate
        st.advance("stage 1" if r["stage1_pressure"] < pressure else "expansion", new_engines=False)
    # Stage 1 ends when the network first carries stage1_pressure: below the target, rotations are
    # then released and the expansion goes on to the target (the network formed with the stage-1
    # fabric densifies). Waiting for balance at stage1_pressure with rotations blocked only let the
    # blocked packing creep (470,000 steps at 300 clumps for e 0.78 -> 0.71), and the creep is
    # undone by the free stage anyway.
    if not st.run("stage 1", first, lambda: st.controller.pressure >= r["stage1_pressure"],
                  max_steps - st.steps("gas"), progress, "stage 1 (rotations %s)" % r["stage1_rotations"],
                  check_first=True):
        raise PreparationError("stage 1 did not reach %.4g Pa within %d steps" % (r["stage1_pressure"], max_steps))
    if st.at("stage 1"):
        st.scene.block_rotations = False
        if r["mu_free"] is not None:  # the friction of the free expansion and the unloading
            st.scene.friction = r["mu_free"]
        st.advance("expansion", new_engines=False)
    if st.at("expansion"):
        label = "expansion (free)" if r["stage1_pressure"] < pressure else "expansion"
        if not st.run("expansion", _checkpointed.CHUNK, lambda: st.controller.reached, max_steps, progress,
                      label):
            raise PreparationError("%s did not converge within %d steps (p or unbalanced force off target)"
                                   % (label, max_steps))
        fold(st)
        st.advance("unloading" if switch < pressure else "switch")
    if st.at("unloading"):
        # Rotations as the expansion left them, its friction: the radii shrink until the switch pressure
        # is held.
        if not st.run("unloading", _checkpointed.CHUNK, lambda: st.controller.reached, max_steps, progress):
            raise PreparationError("unloading did not converge within %d steps (p or unbalanced force off the "
                                   "switch pressure)" % max_steps)
        fold(st)
        st.advance("switch")
    if st.at("switch"):
        st.scene.rescale(1.0 / (st.place["start_scale"] * st.place["grown_scale"]))
        st.scene.cell_ref_size = st.scene.cell_size
        # Stage 2: rotations free, final friction, the cell servoed from the switch pressure to the
        # isotropic stress until the forces and the moments are balanced.
        st.scene.block_rotations = False
        st.scene.friction = r["mu_final"]
        st.advance("consolidation")
    if not st.run("consolidation", _checkpointed.CHUNK,
                  lambda: st.controller.reached and engines.unbalanced_torque(st.scene) < unbalanced,
                  max_steps, progress):
        raise PreparationError("consolidation did not converge within %d steps (p or unbalanced force off target)"
                               % max_steps)
    scene = st.scene
    scene.strain_rate = np.zeros(3)
    scene.velocities = np.zeros((scene.num_bodies, 3))
    scene.angular_velocities = np.zeros((scene.num_bodies, 3))
    log = dict(assembly=assembly, n=n, seed=seed, pressure=pressure, damping=damping,
               inertial_number=inertial_number, prep_unbalanced=prep_unbalanced, unbalanced=unbalanced,
               stress_tolerance=stress_tolerance, gain=gain,
               size_scale=1.0 / (st.place["start_scale"] * st.place["grown_scale"]),
               steps_expansion=sum(st.steps(k) for k in expanding), steps_consolidation=st.steps("consolidation"),
               generation_time=st.place["generation_time"], wall_time=st.elapsed(),
               aspect_ratio=clump_shapes.aspect_ratio(tmpl), template_volume_error=tmpl.volume_error_estimate,
               **{k: (list(v) if isinstance(v, tuple) else v) for k, v in r.items()})
    if r["stage1_pressure"] >= pressure:  # no free expansion, so no friction of one (as every such file records)
        log["mu_free"] = None
    if switch < pressure:  # absent, as in every file before the unloading: the switch at the final pressure
        log.update(switch_pressure=switch, unloaded_from=pressure, steps_unloading=st.steps("unloading"))
    if hold_deviator is not None:  # the default's log records none
        log["hold_deviator"] = hold_deviator
    if checkpoints is not None:
        log["checkpoint_every"] = checkpoints.every
    log.update(st.cost())  # CPU time, peak memory, load, runs (prep_checkpoint.Stages.cost)
    return scene, log
