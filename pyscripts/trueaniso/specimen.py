"""Sphere specimens: random loose packing, radius expansion to the target pressure, an unloading to
a low pressure, and the consolidation back to the target at the consolidation friction.

Recipe (choices and reasons are in docs/specimens.md):

1. random sequential addition at solid fraction 0.30 in a cubic periodic cell sized so that the
   final radii would fill it to ``phi_cell``; particles ordered along the cell grid for locality;
2. radius expansion at fixed cell with friction ``mu_prep``, the growth servoed on the mean
   stress, until p = the target and the unbalanced force is below ``prep_unbalanced``: a dense
   packing, nearly isostatic;
3. the radii shrink, still at ``mu_prep``, until p = ``switch_pressure`` (20 % of the target) is held
   with the unbalanced force below ``prep_unbalanced``;
4. a similarity rescale back to the exact size distribution (Hertz stresses do not change);
5. friction set to ``mu_final`` (0.5, the paper's consolidation friction), the cell servoed from
   the switch pressure to the isotropic target stress (its shear stresses to zero: the cell
   shears a little) until every principal stress and every shear stress is within
   ``stress_tolerance`` and the unbalanced force below ``unbalanced``.

A switch pressure at the target skips step 3 (the named variant ``grown-to-target``, whose packings
lose contacts along the Table C1 paths: docs/path-fidelity.md); ``grown-to-switch`` grows the radii
to the switch pressure only (clump_recipes.VARIANTS).
"""
import math
import time

import numpy as np

from . import dem, engines, prep_checkpoint as _checkpointed, psd as _psd


__all__ = ["prepare_spheres", "state", "d50_cu", "PreparationError"]


class PreparationError(RuntimeError):
    """A stage of a preparation did not converge within its steps."""


def random_loose_packing(n, size_distribution, seed, phi_cell=0.60, phi_start=0.30):
    """Positions and final radii of n spheres; the cell fits them at phi_cell.

    Returns (positions, final_radii, start_scale, cell_size): the spheres are placed without
    overlap with radii start_scale * final_radii.
    """
    if n < 1:
        raise ValueError("number of spheres must be >= 1")
    if not 0.05 <= phi_start < phi_cell < 0.74:
        raise ValueError("solid fractions must satisfy 0.05 <= phi_start < phi_cell < 0.74")
    rng = np.random.default_rng(seed)
    radii = 0.5 * size_distribution.sample(n, rng)
    # cube roots and products, not powers: the same bits on every processor (psd.sample says why)
    volume = 4.0 / 3.0 * math.pi * np.sum(radii * radii * radii)
    side = math.cbrt(volume / phi_cell)
    scale = math.cbrt(phi_start / phi_cell)
    r = scale * radii
    # Random sequential addition, largest first, with a hash grid of cells >= the largest diameter.
    order = np.argsort(-r, kind="stable")
    ncell = max(1, int(side // (2.0 * r.max())))
    cell = side / ncell
    grid = {}
    pos = np.empty((n, 3))
    for k, i in enumerate(order):
        for attempt in range(100000):
            p = rng.random(3) * side
            c = np.floor(p / cell).astype(int) % ncell
            ok = True
            for dx in (-1, 0, 1):
                for dy in (-1, 0, 1):
                    for dz in (-1, 0, 1):
                        key = ((c[0] + dx) % ncell, (c[1] + dy) % ncell, (c[2] + dz) % ncell)
                        for j in grid.get(key, ()):
                            d = pos[j] - p
                            d -= side * np.round(d / side)
                            reach = r[i] + r[j]  # products, not dot or **: no BLAS or libm pow here
                            if d[0] * d[0] + d[1] * d[1] + d[2] * d[2] < reach * reach:
                                ok = False
                                break
                        if not ok:
                            break
                    if not ok:
                        break
                if not ok:
                    break
            if ok:
                break
        else:
            raise ValueError("the size distribution cannot fit the box: random placement failed")
        pos[i] = p
        grid.setdefault(tuple(c), []).append(i)
    along = grid_rows(pos, cell)
    return pos[along], radii[along], scale, np.full(3, side)


def grid_rows(positions, width):
    """The memory order of a new specimen: positions sorted by the cell of a grid (cells `width`
    wide, a scalar or one per axis) they fall in, x fastest, then y, then z (rows of the grid), so
    that neighbours in space are neighbours in the arrays. Measured against a Morton order
    (Scene.order_in_space) and a random one: rows were the fastest (docs/benchmarks.md, "Stepper
    changes"). Sphere and clump placement and the benchmarks' tiled scenes use it."""
    key = np.floor(np.asarray(positions) / width).astype(int)
    return np.lexsort((key[:, 0], key[:, 1], key[:, 2]))


def new_scene(positions, radii, cell_size, shear_modulus=18e9, poisson=0.15, density=2500.0, friction=0.5):
    s = engines.Scene()
    s.shear_modulus = shear_modulus
    s.poisson = poisson
    s.density = density
    s.friction = friction
    s.cell_size = cell_size
    s.cell_ref_size = cell_size
    s.add_spheres(positions, radii)
    return s


def expansion(pressure, gain, rate, stress_tolerance, unbalanced):
    """The radius expansion of step 2 (the clumps' first stages too): growth servoed on the mean
    stress, at most `rate` (d ln r / dt)."""
    grow = engines.RadiusExpansion()
    grow.target_pressure = pressure
    grow.gain = gain
    grow.max_growth_rate = rate
    grow.stress_tolerance = stress_tolerance
    grow.unbalanced_tolerance = unbalanced
    return grow


def consolidation(pressure, gain, rate, stress_tolerance, unbalanced):
    """The cell servo of step 4 (the clumps' stage 2 too): all six components, so the shear
    stresses go to zero too."""
    servo = engines.StressServo()
    servo.target = np.full(3, pressure)
    servo.gain = gain
    servo.max_strain_rate = rate
    servo.stress_tolerance = stress_tolerance
    servo.unbalanced_tolerance = unbalanced
    return servo


# The mean stress at which the friction becomes mu_final and the cell servo takes the packing to the
# target, as a fraction of the target: 20 kPa at 100 kPa (docs/specimens.md, "Why unload, and to
# 20 kPa": at 5 kPa the packing leaves the unloading denser, e 0.572 and Zm 5.89 at 1000 spheres).
SWITCH_FRACTION = 0.2


def default_switch_pressure(pressure, fraction=SWITCH_FRACTION, stress_tolerance=100.0):
    """The switch pressure of a preparation to `pressure` that names none: `fraction` of it, but not
    below the least switch_pressure_problem accepts (10 stress tolerances); at the final pressure
    itself (no unloading) when that is above it."""
    if fraction >= 1.0:
        return pressure
    return min(pressure, max(fraction * pressure, 10.0 * stress_tolerance))


def switch_pressure_problem(switch_pressure, pressure, stress_tolerance=100.0, name="switch pressure"):
    """Why the friction cannot be switched at `switch_pressure` (None if it can): above `pressure`
    the servo would have to unload; below 10 stress tolerances the stop of the stage that reaches
    it (p within one tolerance of its goal) is met more than 10 % off, or by a packing not jammed."""
    least = 10.0 * stress_tolerance
    if not least <= switch_pressure <= pressure:
        return ("%s %g Pa must lie in [%g, %g] Pa (at least 10 times the stress tolerance %g Pa, "
                "at most the final pressure)" % (name, switch_pressure, least, pressure, stress_tolerance))
    return None


def prepare_spheres(n, seed=1, size_distribution=_psd.PAPER_SPHERES, pressure=100e3,
                    mu_prep=0.015, mu_final=0.5, phi_cell=0.60, damping=0.4, inertial_number=1e-2,
                    prep_unbalanced=1e-2, unbalanced=1e-3, stress_tolerance=100.0, gain=0.002,
                    max_steps=5_000_000, progress=None, checkpoints=None, switch_pressure=None,
                    switch_fraction=SWITCH_FRACTION, unload=True):
    """A sphere specimen consolidated isotropically to `pressure` (the recipe of the module doc).

    Args:
        n: number of spheres.
        seed: seed of the random placement; the same seed gives the same specimen, bit for bit.
        size_distribution: a `psd.SizeDistribution`; the paper's (D50 0.195 mm, Cu 1.25) by default.
        pressure: isotropic stress of the specimen, Pa.
        mu_prep: friction while the radii grow (lower: a denser specimen).
        mu_final: friction at the end (the paper's 0.5).
        phi_cell: solid fraction the final radii would fill the first cell to.
        damping: YADE's local non-viscous damping.
        inertial_number: caps the rate of growth and of the cell (quasi-static below 1e-3).
        prep_unbalanced: unbalanced force at which the growth stops.
        unbalanced: unbalanced force at which the consolidation stops.
        stress_tolerance: every stress within this of `pressure` (Pa) at the end.
        gain: gain of the cell servo.
        max_steps: each stage gives up after this many steps (`PreparationError`).
        progress: a `progress.Progress` for progress lines, or None.
        checkpoints: a `prep_checkpoint.Checkpoints`: the preparation writes its place every so many
            steps and starts from the checkpoint on disk if there is one, so an interrupted preparation
            resumes. None: nothing is written (the specimen is the same bits as with checkpoints
            never due).
        switch_pressure: the mean stress to which the packing grown to `pressure` is unloaded (at
            `mu_prep`, in balance), where the friction becomes `mu_final` and the cell servo
            compresses it to `pressure`. None: `switch_fraction` of `pressure`
            (default_switch_pressure); `pressure`: no unloading, the friction switched at the target
            (the variant grown-to-target).
        switch_fraction: the default switch pressure's share of `pressure` (20 %).
        unload: False grows the radii to `switch_pressure` only, without the unloading (the variant
            grown-to-switch). The time step and rate caps are those of `pressure`, the unloading's
            cap that of `switch_pressure`.

    Returns:
        (scene, log): the engines' Scene at rest at the state, and a dict of the recipe's parameters,
        the steps of each stage and the wall time.

    Raises:
        ValueError: a pressure <= 0, a negative friction, a switch pressure the recipe cannot use.
        PreparationError: a stage did not converge within `max_steps`.

    Example:
        >>> from trueaniso import specimen
        >>> scene, log = specimen.prepare_spheres(40, seed=1)
        >>> s = specimen.state(scene)
        >>> print("%d spheres, p = %.0f kPa" % (s["n"], s["p"] / 1e3))
        40 spheres, p = 100 kPa
    """
    if pressure <= 0:
        raise ValueError("pressure must be > 0")
    if switch_pressure is None:
        switch_pressure = default_switch_pressure(pressure, switch_fraction, stress_tolerance)
    # The switch at the final pressure is the recipe itself, at any pressure the recipe accepts.
    problem = switch_pressure != pressure and switch_pressure_problem(switch_pressure, pressure, stress_tolerance)
    if problem:
        raise ValueError(problem)
    expansion_pressure = pressure if unload else switch_pressure
    if mu_prep < 0 or mu_final < 0:
        raise ValueError("friction coefficients must be >= 0")
    t0 = time.time()
    resumed = checkpoints.resume() if checkpoints is not None else None
    if resumed:
        scene, place = resumed
    else:
        pos, radii, start, side = random_loose_packing(n, size_distribution, seed, phi_cell)
        scene = new_scene(pos, start * radii, side, friction=mu_prep)
        # The growth scale so far multiplies the controllers' own (one per run between checkpoints).
        final = new_scene(pos, radii, side)
        place = dict(stage="expansion", steps={}, start_scale=start, grown_scale=1.0,
                     max_dt=dem.reference_time_step(final, pressure))
        if switch_pressure < expansion_pressure:
            # The unloaded packing's contacts are softer (k_n ~ N^(1/3)): its cap is that of the
            # switch pressure (1.6 times the target's at 5 kPa); the steps of the unloading are spent
            # relaxing the packing there, a time, not a number of steps.
            place["unloading_max_dt"] = dem.reference_time_step(final, switch_pressure)
        place["elapsed"] = time.time() - t0
    rate = dem.strain_rate_for_inertial_number(inertial_number, size_distribution.d50, scene.density, pressure)
    sizing = ("expansion", "unloading")  # the stages whose controller changes the radii

    def build(st):
        if st.place["stage"] in sizing:
            goal, cap = (expansion_pressure, "max_dt") if st.at("expansion") else (switch_pressure, "unloading_max_dt")
            st.controller = expansion(goal, gain, rate, stress_tolerance, prep_unbalanced)
            st.chain = dem.Chain(st.scene, damping=damping, controllers=[st.controller], max_dt=st.place[cap])
        else:
            st.controller = consolidation(pressure, gain, rate, stress_tolerance, unbalanced)
            st.chain = dem.Chain(st.scene, damping=damping, controllers=[st.controller])

    def fold(st):
        if st.place["stage"] in sizing:
            st.place["grown_scale"] *= st.controller.scale

    st = _checkpointed.Stages(scene, place, checkpoints, build, fold)
    if st.at("expansion"):
        if not st.run("expansion", _checkpointed.CHUNK, lambda: st.controller.reached, max_steps, progress):
            raise PreparationError("expansion did not converge within %d steps (p or unbalanced force off target)"
                                   % max_steps)
        fold(st)
        st.advance("unloading" if switch_pressure < expansion_pressure else "switch")
    if st.at("unloading"):
        if not st.run("unloading", _checkpointed.CHUNK, lambda: st.controller.reached, max_steps, progress):
            raise PreparationError("unloading did not converge within %d steps (p or unbalanced force off the "
                                   "switch pressure)" % max_steps)
        fold(st)
        st.advance("switch")
    if st.at("switch"):
        # Back to the sampled radii exactly: they were placed at start_scale and grew since.
        st.scene.rescale(1.0 / (st.place["start_scale"] * st.place["grown_scale"]))
        st.scene.cell_ref = st.scene.cell
        st.scene.friction = mu_final
        st.advance("consolidation")
    if not st.run("consolidation", _checkpointed.CHUNK, lambda: st.controller.reached, max_steps, progress):
        raise PreparationError("consolidation did not converge within %d steps (p or unbalanced force off target)"
                               % max_steps)
    scene = st.scene
    scene.velocity_gradient = np.zeros((3, 3))
    scene.velocities = np.zeros((scene.num_bodies, 3))
    scene.angular_velocities = np.zeros((scene.num_bodies, 3))
    dem.refresh(scene)  # forces of the positions kept (the integrator moved them last)

    log = dict(n=n, seed=seed, pressure=pressure, mu_prep=mu_prep, mu_final=mu_final,
               phi_cell=phi_cell, damping=damping, inertial_number=inertial_number,
               prep_unbalanced=prep_unbalanced, unbalanced=unbalanced,
               stress_tolerance=stress_tolerance, gain=gain,
               radius_scale=st.place["start_scale"] * st.place["grown_scale"],
               steps_expansion=st.steps("expansion"), steps_consolidation=st.steps("consolidation"),
               wall_time=st.elapsed(), d50=size_distribution.d50, cu=size_distribution.cu)
    # Keys absent: the switch at the final pressure (every file before the option), and the radii
    # grown to the switch pressure (every file before the unloading).
    if switch_pressure != pressure:
        log["switch_pressure"] = switch_pressure
    if expansion_pressure != switch_pressure:
        log["unloaded_from"] = expansion_pressure
        log["steps_unloading"] = st.steps("unloading")
    if checkpoints is not None:
        log["checkpoint_every"] = checkpoints.every
    log.update(st.cost())  # CPU time, peak memory, load, runs (prep_checkpoint.Stages.cost)
    return scene, log


def d50_cu(scene):
    """D50 and Cu of the scene's particles by mass, as the paper gives them for its assemblies (section 2.1).

    Each particle counts by the diameter of its equal-volume sphere (a clump's by its union volume).

    Returns:
        (D50 in m, Cu).

    Example:
        >>> from trueaniso import specimen, specimen_file
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> d50, cu = specimen.d50_cu(scene)
        >>> print("D50 = %.2f mm, Cu = %.1f" % (d50 * 1e3, cu))
        D50 = 0.19 mm, Cu = 1.3
    """
    d = np.cbrt(6.0 * np.asarray(scene.volumes, dtype=float) / np.pi)
    return _psd.mass_d50_cu(d)


def state(scene):
    """The numbers a researcher checks on a specimen.

    Returns:
        dict: ``n``, ``void_ratio``, ``Zm``, ``Z``, ``Nc``, ``Np0``, ``Np1`` (the fabric counts);
        ``sigma_x``, ``sigma_y``, ``sigma_z``, ``sigma_yz``, ``sigma_xz``, ``sigma_xy`` and ``p`` (Pa,
        compression positive); ``sigma_1`` >= ``sigma_2`` >= ``sigma_3``, the largest shear stress
        ``tau_max`` and the deviatoric ``q`` of the principal values; ``unbalanced``, ``friction``,
        ``cell`` (hSize, columns are the cell vectors), ``d50`` and ``cu`` (`d50_cu`).

    Raises:
        ValueError: a scene whose contacts carry forces but were never evaluated at these positions
            (a scene just imported from YADE: call `dem.refresh` first).

    Example:
        >>> from trueaniso import specimen, specimen_file
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> s = specimen.state(scene)
        >>> print("e = %.3f, Zm = %.2f, p = %.1f kPa" % (s["void_ratio"], s["Zm"], s["p"] / 1e3))
        e = 0.581, Zm = 5.84, p = 100.0 kPa
    """
    from .triaxial import stress_record
    sig = engines.stress(scene)
    z = engines.coordination(scene)
    out = dict(n=scene.num_bodies, void_ratio=engines.void_ratio(scene), Zm=z["Zm"], Z=z["Z"],
               Nc=z["Nc"], Np0=z["Np0"], Np1=z["Np1"],
               sigma_x=sig[0, 0], sigma_y=sig[1, 1], sigma_z=sig[2, 2],
               p=np.trace(sig) / 3.0, unbalanced=engines.unbalanced_force(scene),
               friction=scene.friction, cell=scene.cell.tolist())
    out.update(stress_record(scene))
    out["d50"], out["cu"] = d50_cu(scene)
    s1, s2, s3 = out["sigma_1"], out["sigma_2"], out["sigma_3"]
    out["q"] = float(np.sqrt(0.5 * ((s1 - s2) ** 2 + (s2 - s3) ** 2 + (s3 - s1) ** 2)))
    return out
