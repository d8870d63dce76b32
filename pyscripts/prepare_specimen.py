"""Prepare a specimen consolidated isotropically to 100 kPa and save it (versioned .npz + .json).

    yade-double -n -x pyscripts/prepare_specimen.py --n 4000 --seed 1 --out specimens/spheres-4000.npz
    /usr/bin/python3 pyscripts/prepare_specimen.py --n 1000 --out specimens/spheres-1000.npz
    /usr/bin/python3 pyscripts/prepare_specimen.py --assembly clump1 --n 4000 --out specimens/clump1-4000.npz

The recipe and the reasons for its parameters are in docs/specimens.md. An existing valid output
is kept and reported; use --force to prepare it again. An interrupted preparation resumes from its
last checkpoint (written every --checkpoint-every steps beside --out as .NAME.checkpoint) when run
again with the same options, to the same specimen an uninterrupted run writes. Memory and time are
estimated before any work, and a specimen that cannot fit in this machine's memory is refused.
Inside yade-double the result is also written into O (cell and spheres) for viewing or export.
"""
import json
import math
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__)))
from trueaniso import start_guard  # noqa: E402  (first: Ctrl-C while numpy and the engines load is one line)
start_guard.install()
try:
    from trueaniso import (clump_recipes, clump_specimen, cli, engines, lock, prep_checkpoint, progress, provenance,
                           psd, resources, specimen, specimen_file, study_dir, triaxial)
except ImportError as exc:  # the compiled module not built (or a Debian package missing): one line, not a traceback
    sys.stderr.write("error: %s\n" % exc)
    os._exit(2)

# Defaults of the options that depend on the assembly (the clumps' are their recipes').
SPHERE_DEFAULTS = dict(d50=0.195e-3, cu=1.25, mu_prep=0.015, phi_cell=0.60)


def assembly_defaults(assembly, variant=None):
    if assembly == "sphere":
        return dict(SPHERE_DEFAULTS)
    # A variant's recipe parameters replace the defaults; its other settings (keywords of
    # prepare_clumps, such as the servo's gain) go to the preparation as they are (prepare).
    named = clump_recipes.variant(assembly, variant) if variant else {}
    r = clump_specimen.recipe(assembly, **{k: v for k, v in named.items() if k in clump_recipes.RECIPES[assembly]})
    return dict(d50=r["d50"], cu=r["cu"], mu_prep=r["mu_prep"], phi_cell=r["phi_cell"])


def options(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--assembly", type=cli.assembly, default="sphere",
                   help="particle type: %s (docs/specimens.md)" % ", ".join(cli.ASSEMBLIES))
    p.add_argument("--n", type=cli.at_least(1, "an empty cell cannot be consolidated"), default=1000,
                   help="number of particles")
    p.add_argument("--seed", type=cli.count, default=1, help="seed of the random packing (>= 0)")
    p.add_argument("--pressure", type=cli.finite, default=100e3, help="isotropic stress (Pa)")
    p.add_argument("--d50", type=cli.finite, help="median diameter by mass (m; clumps: of the equal-volume sphere); "
                   "default 0.195e-3, clump2 0.216e-3")
    p.add_argument("--cu", type=cli.finite, help="uniformity coefficient D60/D10; default 1.25, clump2 1.43")
    p.add_argument("--mu-prep", type=cli.finite, help="friction while radii grow; default per assembly")
    p.add_argument("--mu", type=cli.finite, default=0.5, help="friction of the consolidated state")
    p.add_argument("--switch-pressure", type=cli.finite, default=None,
                   help="spheres: mean stress (Pa) to which the packing grown at --mu-prep is unloaded, where the "
                        "friction becomes --mu and the cell servo compresses it to --pressure (a specimen "
                        "consolidated at the final friction; docs/specimens.md). Default: %g of --pressure (20 kPa "
                        "at 100 kPa)" % specimen.SWITCH_FRACTION)
    p.add_argument("--recipe", help="a named variant of an assembly's recipe, whose settings replace the defaults "
                                    "that depend on the assembly (docs/specimens.md; docs/clumps.md, section 5b): %s"
                                    % "; ".join("%s: %s" % (a, ", ".join(v))
                                                for a, v in clump_recipes.VARIANTS.items()))
    p.add_argument("--phi-cell", type=cli.finite,
                   help="solid fraction at which the final sizes would fill the cell; default per assembly")
    p.add_argument("--inertial-number", type=cli.finite, default=1e-2,
                   help="cap of the expansion/compression rate as an inertial number")
    p.add_argument("--unbalanced", type=cli.finite, default=1e-3, help="unbalanced force of the final state")
    cli.add_time_step_option(p)
    cli.add_threads_option(p, study=True, continues="the interrupted preparation of --out (its checkpoint; "
                                                    "the packing's last bits depend on the count)")
    p.add_argument("--checkpoint-every", type=cli.count, default=None,
                   help="steps between checkpoints of the preparation, from which an interrupted run resumes; "
                        "default %d, or an interrupted preparation's own (0: none; the specimen is then bit for "
                        "bit what versions before checkpoints made). An interrupted preparation resumes only at "
                        "its own interval, which is part of its recipe (the engines restart from each checkpoint), "
                        "so another is refused. A checkpoint is written between the stages' "
                        "chunks of %d steps (%d in a clump preparation's first stages), at the first chunk's end "
                        "at least this many steps after the last" % (prep_checkpoint.EVERY, prep_checkpoint.CHUNK,
                                                                     prep_checkpoint.FIRST_STAGES_CHUNK))
    p.add_argument("--out", required=True, help="specimen file (.npz); a .json summary is written beside it")
    p.add_argument("--force", action="store_true",
                   help="prepare again even if --out is a valid specimen (an interrupted preparation with these "
                        "settings still resumes; one with other settings is discarded)")
    p.add_argument("--wait", action="store_true",
                   help="if another run is preparing --out, wait for it instead of refusing")
    p.add_argument("--progress-every", type=cli.non_negative, default=progress.EVERY,
                   help="seconds between progress lines (0: after every chunk of 2,000 steps)")
    p.add_argument("--quiet", action="store_true", help="no progress lines, only the final summary")
    return cli.parse(p, argv)


def validate(o):
    if o.recipe is not None:
        try:
            named = clump_recipes.variant(o.assembly, o.recipe)
        except ValueError as exc:
            raise cli.InputError("--recipe: %s" % exc) from None
        # An option that contradicts the recipe named: the file would record the name with another
        # setting (a 'frictionless' specimen with mu_prep 0.3).
        for key, value in named.items():
            given = getattr(o, key, None)
            if given is not None and given != value:
                raise cli.InputError("--%s %g contradicts --recipe %s, which sets %s = %g: leave --%s out, or give "
                                     "no --recipe (the assembly's default recipe with --%s %g)"
                                     % (key.replace("_", "-"), given, o.recipe, key, value, key.replace("_", "-"),
                                        key.replace("_", "-"), given))
    for k, v in assembly_defaults(o.assembly, o.recipe).items():
        if getattr(o, k) is None:
            setattr(o, k, v)
    resolve_switch(o)
    if o.assembly != "sphere":
        try:
            clump_specimen.check_count(o.assembly, o.n)
        except ValueError as exc:
            raise cli.InputError(str(exc)) from None
    # Before anything of size n is drawn (the layers' check below draws every clump): memory goes
    # with the member spheres (contacts, cell lists), not with the bodies.
    spheres = o.n * (1 if o.assembly == "sphere" else clump_specimen.members_per_clump(o.assembly))
    memory, _ = resources.preparation_estimate(spheres, o.threads or resources.cores())
    resources.check_memory(memory, "a specimen of %d %s (%d member spheres)" % (o.n, o.assembly, spheres))
    if o.d50 <= 0:
        raise cli.InputError("--d50 must be > 0 (a radius <= 0 is not a particle)")
    if o.pressure <= 0:
        raise cli.InputError("--pressure must be > 0")
    material = engines.Scene()  # the paper's material, which every specimen is made of
    problem = triaxial.hertz_range_problem(o.pressure, material.shear_modulus, material.poisson, what="--pressure")
    if problem:
        raise cli.InputError(problem)
    if o.mu_prep < 0 or o.mu < 0:
        raise cli.InputError("friction coefficients must be >= 0")
    if o.switch_pressure is not None:
        problem = switched_below(o) and specimen.switch_pressure_problem(o.switch_pressure, o.pressure,
                                                                         name="--switch-pressure")
        if problem:
            raise cli.InputError(problem)
        problem = triaxial.hertz_range_problem(o.switch_pressure, material.shear_modulus, material.poisson,
                                               what="--switch-pressure")
        if problem:
            raise cli.InputError(problem)
    if not 0.3 < o.phi_cell < 0.74:
        raise cli.InputError("--phi-cell %.3g: the size distribution cannot fit the box "
                             "(spheres fill at most 0.74 of space; use 0.3 < phi < 0.74)" % o.phi_cell)
    if not (0 < o.unbalanced < 1 and 0 < o.inertial_number < 1):
        raise cli.InputError("--unbalanced and --inertial-number must lie in (0, 1)")
    resources.check_threads(o.threads or 0)
    if not o.out.endswith(".npz"):
        raise cli.InputError("--out must name a .npz file")
    try:
        dist = psd.SizeDistribution.from_d50_cu(o.d50, o.cu)
    except ValueError as exc:  # named by option and value: "Cu must lie in (1, 6)" said neither
        raise cli.InputError("--d50 %g --cu %g: %s" % (o.d50, o.cu, exc)) from None
    # The cell must be longer than the interaction range of the largest pair (a clump's length:
    # its bounding diameter at the largest size). Checked before the layers, and the least count it
    # names also holds the layers: followed one after the other, the two checks' advice would lead
    # from --n 60 to 67 (not a multiple of clump2's 4 layers) to 80.
    clumps = dict(d50=o.d50, cu=o.cu, phi_cell=o.phi_cell)
    side = (o.n * 3.14159265 / 6 * dist.d50 ** 3 / o.phi_cell) ** (1 / 3)
    length = dist.d[-1] * (1.0 if o.assembly == "sphere" else clump_specimen.bounding_diameter(o.assembly))
    if side < 1.2 * 2 * length:
        least = int(math.ceil(o.n * (1.2 * 2 * length / side) ** 3))  # the side grows as n^(1/3)
        if o.assembly != "sphere":
            least = clump_specimen.least_layered_count(o.assembly, least, o.seed, **clumps) or least
        raise cli.InputError("%s of D50 %.3g m make a cell of %.3g m, shorter than the contact range of the "
                             "largest particles: the size distribution cannot fit the box; use --n of at least %d"
                             % (clump_specimen.particles(o.n, o.assembly), o.d50, side, least))
    if o.assembly != "sphere":
        problem = clump_specimen.layers_problem(o.assembly, o.n, o.seed, **clumps)
        if problem:
            raise cli.InputError(problem)
    problem = cli.output_problem(o.out, directory=False)
    if problem:
        raise cli.InputError(problem)
    return dist


def main():
    o = options()
    dist = validate(o)
    cli.resolve_time_step(o)
    o.given = dict(threads=o.threads, checkpoint_every=o.checkpoint_every)  # before a resumed preparation's
    cli.saves_work_in(lambda: os.path.exists(prep_checkpoint.path_for(o.out)), resumes=cli.RESUMES_PREPARATION)
    directory, name = os.path.split(os.path.abspath(o.out))
    # One preparation per output at a time; under the lock, the temporary files of an
    # interrupted preparation of this output are removed.
    with lock.held(directory, wait=o.wait, name=".%s.lock" % name, what="specimen output %s" % o.out,
                   log=progress.say):
        checkpoint = os.path.basename(prep_checkpoint.path_for(o.out))
        for stray in os.listdir(directory):
            if stray.startswith(".tmp-") and stray.endswith(("-" + name, "-" + name[:-4] + ".json", "-" + checkpoint)):
                os.unlink(os.path.join(directory, stray))
        # An interrupted preparation of these settings goes on at its own thread count and
        # checkpoint interval (its bits depend on both) unless they are given; one of other settings
        # lends neither (it is refused, or removed by --force), nor does one beside a specimen kept.
        ck = prep_checkpoint.Checkpoints(prep_checkpoint.path_for(o.out), {})
        broken = ck.unusable()
        if broken and o.force:  # its refusal says "or use --force", which must then work
            ck.remove()
            print("removed the unusable checkpoint %s (%s) (--force)" % (ck.path, broken), flush=True)
        own = None
        if o.force or not os.path.exists(o.out):
            own = ck.of_settings(settings(o))  # refuses a broken one without --force
        cli.resolve_threads(o, study=False, preparation=ck.path if own else None)
        if o.checkpoint_every is None:
            o.checkpoint_every = (own or {}).get("every", prep_checkpoint.EVERY)
            if own and "every" in own:  # said as the threads are, --quiet too
                print("%s: --checkpoint-every not given: its unfinished preparation wrote %s, so this run does too"
                      % (o.out, prep_checkpoint.interval_said(o.checkpoint_every)), flush=True)
        if o.threads:
            resources.use_threads(o.threads)
        prepare(o, dist)


def resolve_switch(o):
    """--switch-pressure when not given (the recipe's share of --pressure, specimen.default_switch_pressure),
    and whether the packing is unloaded to it (o.unload: the recipe's; the sphere variant
    grown-to-switch grows its radii to it instead). A --switch-pressure that a recipe switching the
    friction at --pressure (grown-to-target) would ignore is refused."""
    named = clump_recipes.variant(o.assembly, o.recipe) if o.recipe else {}
    o.unload = named.get("unload", True)
    if o.assembly == "sphere":
        fraction = named.get("switch_fraction", specimen.SWITCH_FRACTION)
    else:
        fraction = clump_specimen.recipe(o.assembly, switch_fraction=named.get("switch_fraction"))["switch_fraction"]
    if o.switch_pressure is None:
        o.switch_pressure = specimen.default_switch_pressure(o.pressure, fraction)
    elif fraction >= 1.0 and o.switch_pressure != o.pressure:
        raise cli.InputError("%s switches the friction at --pressure: --switch-pressure %g would change nothing it "
                             "does" % ("--recipe %s" % o.recipe if o.recipe else "the %s recipe" % o.assembly,
                                       o.switch_pressure))


def settings(o):
    """Every option that makes the specimen (what its preparation checkpoint is bound to). The time
    step rule only when it is not the one every earlier file was made with (which records none:
    cli.UNRECORDED_TIME_STEP)."""
    made = dict(assembly=o.assembly, n=o.n, seed=o.seed, pressure=o.pressure, d50=o.d50, cu=o.cu,
                mu_prep=o.mu_prep, mu=o.mu, phi_cell=o.phi_cell, inertial_number=o.inertial_number,
                unbalanced=o.unbalanced)
    if o.recipe is not None:  # the default recipe's files record none
        made["recipe"] = o.recipe
    if o.time_step != cli.UNRECORDED_TIME_STEP:
        made["time_step"] = o.time_step
    if switched_below(o):
        made["switch_pressure"] = o.switch_pressure
    return made


def unloaded(o):
    """Whether this run's packing is grown to --pressure and unloaded to the switch pressure."""
    return switched_below(o) and o.unload


def switched_below(o):
    """Whether the friction is switched below the final pressure: only then is the switch a setting,
    recorded and compared; at the final pressure it is the recipe of every file made before the
    option (the variant grown-to-target)."""
    return o.switch_pressure is not None and o.switch_pressure != o.pressure


DEFAULT_RECIPE = "the assembly's default"


def recipe_settings(o):
    """The settings of the recipe this run asks for that a file records and no option gives: each
    keyword of the preparation that a named variant sets (the growth servo's gain, the deviator
    hold), at the variant's value or the preparation's default; and those defaults."""
    import inspect
    prepare = specimen.prepare_spheres if o.assembly == "sphere" else clump_specimen.prepare_clumps
    defaults = {k: p.default for k, p in inspect.signature(prepare).parameters.items()
                if p.default is not inspect.Parameter.empty}
    named = clump_recipes.variant(o.assembly, o.recipe) if o.recipe else {}
    keys = sorted({k for variants in clump_recipes.VARIANTS.values() for v in variants.values() for k in v
                   if k in defaults and k not in SPHERE_DEFAULTS})
    return {k: named.get(k, defaults[k]) for k in keys}, {k: defaults[k] for k in keys}


def clump_recipe(o):
    """The clump recipe (clump_recipes.RECIPES, with a named variant's settings) this run prepares, as
    a file records it (lists, no friction of a free expansion there is none of); {} for spheres."""
    if o.assembly == "sphere":
        return {}
    named = clump_recipes.variant(o.assembly, o.recipe) if o.recipe else {}
    r = clump_specimen.recipe(o.assembly, **{k: v for k, v in named.items() if k in clump_recipes.RECIPES[o.assembly]})
    if r["stage1_pressure"] >= o.pressure:
        r["mu_free"] = None
    return json.loads(json.dumps(r))


def differences(o, meta):
    """The settings of this run that the specimen file was not made with ("seed: 5 there, 1 here");
    settings a file does not record (older files) are not compared, but for the recipe: its name
    always (a file of the default recipe records none) and a variant's settings where the file
    records them or their absence means the default (no deviator hold), so that a specimen of
    another --recipe is not kept."""
    p = meta.get("parameters", {})
    have = dict(p, assembly=p.get("assembly", "sphere"), seed=meta.get("seed"), mu=p.get("mu_final"),
                time_step=p.get("time_step", cli.UNRECORDED_TIME_STEP),
                switch_pressure=p.get("switch_pressure", p.get("pressure")), unloaded="unloaded_from" in p)
    want = dict(settings(o), time_step=o.time_step,
                switch_pressure=o.switch_pressure if switched_below(o) else o.pressure, unloaded=unloaded(o))
    want = {k: v for k, v in want.items() if have.get(k) is not None and k != "recipe"}
    recipe, defaults = recipe_settings(o)
    recipe = {k: v for k, v in recipe.items() if k in p or defaults[k] is None}
    # A clump recipe's own settings (shape, orientations, stages) where the file records them: the
    # default recipe changed keeps its name, so the name alone would keep a specimen of the old one.
    recipe.update({k: v for k, v in clump_recipe(o).items() if k in p and k not in want})
    want.update(recipe, recipe=o.recipe or DEFAULT_RECIPE)
    have = {k: have.get(k) for k in want}
    have["recipe"] = p.get("recipe") or DEFAULT_RECIPE
    return study_dir.said(study_dir.differences(have, want, rel_tol=1e-9))


def _kept_with(o, meta):
    """What the kept specimen was made with that this run asked otherwise, none of which changes
    the recipe and each of which can change the last bits: a --threads or --checkpoint-every given,
    and the code, so that the specimen is not kept without a word (--checkpoint-every 0 asked, the
    old file given)."""
    p, other = meta.get("parameters", {}), []
    threads = o.given["threads"] if o.given["threads"] != 0 else engines.threads()
    if o.given["threads"] is not None and p.get("threads") is not None and p["threads"] != threads:
        other.append("at %d engine thread%s (this run: %d)" % (p["threads"], "" if p["threads"] == 1 else "s", threads))
    every = o.given["checkpoint_every"]
    if every is not None and p.get("checkpoint_every") is not None and p["checkpoint_every"] != every:
        def interval(k):
            return "checkpoints every %d steps" % k if k else None
        made = interval(p["checkpoint_every"])
        other.append("%s (this run: %s)" % ("with " + made if made else "without checkpoints", interval(every) or "none"))
    code = (meta.get("versions") or {}).get("code")
    if code and code != provenance.code_version():
        other.append("by code %s (this run: %s)" % (code, provenance.code_version()))
    return "; note: it was made %s, each of which can change its last bits" % ", ".join(other) if other else ""


def _checkpoint_beside_kept(o, meta, checkpoints):
    """A checkpoint beside a specimen this run keeps: removed when it is the leftover of the run
    that saved the specimen (killed between its save and the removal: the same settings, threads,
    interval and code as the specimen's own), else kept and named. Compared with this run instead,
    the checkpoint of an interrupted --force remake with other threads would pass for such a
    leftover and be removed; and a damaged one beside a good specimen is named, not an error whose
    advice, --force, would replace the specimen."""
    broken = checkpoints.unusable()
    if broken:
        print("kept the unusable checkpoint %s beside it (%s); remove it (the specimen is complete)"
              % (checkpoints.path, broken))
        return
    saved = checkpoints.saved_recipe()
    if saved is None:
        return
    p = meta.get("parameters", {})
    made = dict(threads=p.get("threads"), every=p.get("checkpoint_every"), code=(meta.get("versions") or {}).get("code"))
    if checkpoints.of_settings(settings(o)) is not None and all(saved.get(k) == v for k, v in made.items()):
        checkpoints.remove()
        return
    if saved.get("code") != provenance.code_version():
        way = "it was made by other code, which alone can resume it (remove it if that is not wanted)"
    else:
        way = "running with those settings and --force resumes it"
    print("kept the checkpoint %s of an interrupted preparation with other settings (%s): %s"
          % (checkpoints.path, "; ".join(checkpoints.differences()), way))


def prepare(o, dist):
    checkpoints = prep_checkpoint.for_specimen(o.out, settings(o), o.checkpoint_every,
                                               log=None if o.quiet else progress.say)
    if os.path.exists(o.out) and not o.force:
        try:
            scene, meta = specimen_file.load(o.out)
        except specimen_file.SpecimenFileError as exc:
            raise cli.InputError("%s exists but is not usable (%s); remove it or use --force" % (o.out, exc))
        diff = differences(o, meta)
        if diff:
            raise cli.InputError("%s exists and was prepared with other settings (%s); use --force to prepare it "
                                 "again (it is replaced only when the new one is complete), or another --out"
                                 % (o.out, "; ".join(diff)))
        print("kept existing specimen %s (use --force to prepare again)%s" % (o.out, _kept_with(o, meta)))
        _checkpoint_beside_kept(o, meta, checkpoints)
        if specimen_file.ensure_summary(o.out, meta):
            print("wrote the missing summary %s from the specimen" % specimen_file.summary_path(o.out))
        report(scene, meta.get("parameters", {}), o, meta.get("summary"))
        return

    # The code version goes into the file; taken now, so that sources edited (and a module rebuilt)
    # while a preparation of an hour runs cannot make its save refuse (and lose a 16,000-sphere
    # run), and a module built from other sources is refused before any work.
    provenance.versions()
    stale = checkpoints.differences()
    if stale and not o.force:  # refused before the estimate line, which would read as the start of the work
        checkpoints.refuse_other()
    bar = progress.Progress("  preparation", progress.say, o.progress_every)
    if not o.quiet:
        members = o.n * (1 if o.assembly == "sphere" else clump_specimen.members_per_clump(o.assembly))
        # The engines' own count (set by main), not all cores: those would say 16 s for 31 s under OMP_NUM_THREADS=1.
        memory, seconds = resources.preparation_estimate(members, engines.threads(), o.assembly)
        print("preparing %s (seed %d, D50 %.4g m, Cu %.3g) to %.4g kPa: about %s of memory and %s%s"
              % (clump_specimen.particles(o.n, o.assembly), o.seed, o.d50, o.cu, o.pressure / 1e3,
                 resources.human_bytes(memory), resources.human_seconds(seconds),
                 resources.preparation_caveat(o.assembly, o.n)), flush=True)
        rounded = prep_checkpoint.rounding_said(o.checkpoint_every, o.assembly != "sphere")
        if rounded:
            print(rounded, flush=True)
    t0 = time.time()
    if stale and o.force:  # (one of these settings resumes; another one is refused before any work)
        checkpoints.remove()
        print("removed the checkpoint of an earlier preparation of %s with other settings (%s) (--force)"
              % (o.out, "; ".join(stale)), flush=True)
    try:
        if o.assembly == "sphere":
            scene, log = specimen.prepare_spheres(
                o.n, seed=o.seed, size_distribution=dist, pressure=o.pressure, mu_prep=o.mu_prep,
                mu_final=o.mu, phi_cell=o.phi_cell, inertial_number=o.inertial_number,
                unbalanced=o.unbalanced, progress=None if o.quiet else bar.preparation, checkpoints=checkpoints,
                switch_pressure=o.switch_pressure, unload=o.unload)
        else:
            scene, log = clump_specimen.prepare_clumps(
                o.assembly, o.n, seed=o.seed, pressure=o.pressure, d50=o.d50, cu=o.cu, mu_prep=o.mu_prep,
                mu_final=o.mu, phi_cell=o.phi_cell, inertial_number=o.inertial_number, unbalanced=o.unbalanced,
                progress=None if o.quiet else bar.preparation, checkpoints=checkpoints,
                switch_pressure=o.switch_pressure,
                **{k: v for k, v in (clump_recipes.variant(o.assembly, o.recipe) if o.recipe else {}).items()
                   if k not in assembly_defaults(o.assembly)})
    except (ValueError, specimen.PreparationError, clump_specimen.PreparationError) as exc:
        cli.fail(str(exc), 1)
    log["threads"] = engines.threads()  # the count used, not the option (0 means all cores)
    log.setdefault("assembly", o.assembly)
    if o.recipe is not None:
        log["recipe"] = o.recipe
    if o.time_step != cli.UNRECORDED_TIME_STEP:  # smallest-inertia's files record none, as every earlier one
        log["time_step"] = o.time_step
    summary = specimen.state(scene)
    meta = specimen_file.save(o.out, scene, seed=o.seed, parameters=log, summary=summary)
    specimen_file.write_summary(o.out, meta)  # derived from the .npz; rewritten from it if lost
    cli.work_done()
    checkpoints.remove()  # only now: the specimen is complete on disk
    if not o.quiet:
        this = time.time() - t0
        total = log.get("wall_time", this)  # the preparation's, over every run that made it
        # A resumed preparation says the whole preparation's time too, not only its own run's (1.0 s of 11 s).
        print("saved %s in %.1f s%s" % (o.out, this, "" if not checkpoints.resumed else
                                         " (this run; %.1f s in all, with the runs before its last checkpoint)"
                                         % total))
    report(scene, log, o, summary)


def report(scene, log, o, st=None):
    """The specimen's summary as one JSON line: the file's own (`st`, saved with it), so that a kept
    specimen says what its save said. Recomputed from a reloaded clump scene, the unbalanced force
    (a residual) comes out otherwise (5.59e-7 against the 5.17e-7 saved)."""
    st = st or specimen.state(scene)
    print(json.dumps(dict(n=st["n"], void_ratio=round(st["void_ratio"], 4), Zm=round(st["Zm"], 3),
                          sigma_kPa=[round(st[k] / 1e3, 3) for k in ("sigma_x", "sigma_y", "sigma_z")],
                          principal_kPa=[round(st[k] / 1e3, 3) for k in ("sigma_1", "sigma_2", "sigma_3")],
                          tau_max_kPa=round(st["tau_max"] / 1e3, 4),
                          unbalanced=float("%.3g" % st["unbalanced"]), friction=st["friction"])))
    if cli.in_yade():
        from trueaniso import yade_bridge
        yade_bridge.yade_scene_from(scene, import_contacts=False)


if __name__ == "__main__":  # also under yade-double -x; an import (even inside YADE) runs nothing
    cli.guarded(main, resumable=True)
else:  # loaded, not run (mpi4py.futures' workers load the script): no start-up guard left behind
    cli.release_start_guard()
