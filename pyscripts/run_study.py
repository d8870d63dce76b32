"""The default study, run by ./main.sh: a specimen, Table C1 states probed on x, y, z, statics, zeta, figures.

    yade-double -n -x pyscripts/run_study.py [--assembly sphere] [--n 1000] [--seed 1]
                                             [--ids 1,5,9,13,17,21,25,35,39] [--out results/default]
    /usr/bin/python3 pyscripts/run_study.py --specimen S.npz --rotations restrained --out results/r

1. a specimen (spheres, or clumps with --assembly clump1|clump2) consolidated isotropically to
   100 kPa (docs/specimens.md);
2. a selection of the paper's Table C1 states, each reached by the b-controlled servo and probed
   on z, x and y (docs/triaxial.md), with the micro-structure of each state (docs/fabric.md);
3. the exact static stiffness at the isotropic state and the rotation factor zeta it implies
   (docs/statics.md), and zeta fitted on the contrast over the probed states (pyscripts/trueaniso/analysis/zeta_contrast.py);
4. figures (E_i against sigma_i, K and G against Zm), the report beside the paper's numbers
   (OUT/report/report.md, pyscripts/trueaniso/analysis/report.py) and a summary.
The output directory is one study (docs/runs.md): a rerun continues it where it stopped, also
after a kill, and may add states (--ids 1,5 then --ids 1,5,9); a rerun that asks for another
specimen or other settings refuses in one line.
"""
import inspect
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
sys.path.insert(0, HERE)  # this checkout's trueaniso, under yade-double too (it does not put the script's folder first)
from trueaniso import start_guard  # noqa: E402  (first: Ctrl-C while numpy and the engines load is one line)
start_guard.install()
try:
    from trueaniso.analysis import figures, report, zeta_contrast
    from trueaniso import (atomic, clump_specimen, cli, engines, lock, prep_checkpoint, progress, psd, resources,
                           specimen, statics, specimen_file, study, study_dir, study_options, triaxial)
except ImportError as exc:  # the compiled module not built (or a Debian package missing): one line, not a traceback
    sys.stderr.write("error: %s\n" % exc)
    os._exit(2)

DEFAULT_IDS = "1,5,9,13,17,21,25,35,39"
SPECIMEN = "specimen.npz"


def parser():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", help="a specimen file (prepare_specimen.py, .npz) to study instead of preparing one "
                                      "in --out; --n and --seed are then the file's, and --assembly, when given, must "
                                      "be its assembly")
    p.add_argument("--assembly", type=cli.assembly,
                   help="sphere, clump1 or clump2 (docs/specimens.md) (default: sphere)")
    p.add_argument("--n", type=cli.at_least(100, "a study specimen"),
                   help="particles in the specimen the study prepares (>= 100) (default: %d)" % DEFAULT_N)
    p.add_argument("--seed", type=cli.count, help="seed of the random packing (>= 0) (default: %d)" % DEFAULT_SEED)
    p.add_argument("--ids", help="Table C1 states to run, by number (default: %s)" % DEFAULT_IDS)
    p.add_argument("--table-c1", action="store_true", help="all 39 states of the paper's Table C1")
    p.add_argument("--states", help="b:sigma_z pairs, sigma_z in Pa, comma separated (e.g. 0.5:140e3,0:60e3); a "
                                    "state's id is its Table C1 number, else b<b>_sz<sigma_z>")
    study_options.add_probe_options(p, "zxy")
    study_options.add_servo_options(p)
    study_options.add_run_options(p, out_default="results/default")
    p.add_argument("--host", choices=study.HOSTS, default="trueaniso",
                   help="who steps the states and probes: trueaniso (our stepper) or yade (YADE's own loop with the "
                        "plugin's classes in O.engines; under yade-double with YADE_PREFIX=<repository>/build/"
                        "yade-prefix, docs/yade-peer.md); the specimen and the static solve are ours either way")
    return p


DEFAULT_N, DEFAULT_SEED = 1000, 1


def validate(o):
    problem = cli.output_problem(o.out)  # first: the thread count below is read from what --out holds
    if problem:
        raise cli.InputError(problem)
    # A study, or a preparation for one killed before the study began, goes on at its own count.
    cli.resolve_threads(o, preparation=None if o.specimen else prep_checkpoint.path_for(os.path.join(o.out, SPECIMEN)))
    cli.resolve_path_rate(o)
    cli.resolve_study_time_step(o)
    if sum(x is not None and x is not False for x in (o.ids, o.table_c1 or None, o.states)) > 1:
        raise cli.InputError("give at most one of --ids, --table-c1, --states")
    try:
        if o.states is not None:
            states = study.parse_states(o.states)
        elif o.table_c1:
            states = study.table_states()
        else:
            states = study.table_states(study.parse_ids(o.ids if o.ids is not None else DEFAULT_IDS))
        for _, b, sz in states:
            triaxial.validate_path_state("true-triaxial", b, sz)
    except ValueError as exc:
        raise cli.InputError("%s: %s" % ("--states" if o.states is not None else "--ids", exc)) from None
    o.probe_axes = study_options.probe_axes(o.probes, "true-triaxial")
    study_options.check(o)
    if o.specimen:
        given = [name for name, value in (("--n", o.n), ("--seed", o.seed)) if value is not None]
        if given:
            raise cli.InputError("%s describe%s the specimen run_study.py prepares; --specimen gives the specimen: "
                                 "leave %s out" % (" and ".join(given), "" if len(given) > 1 else "s",
                                                   "them" if len(given) > 1 else "it"))
        try:
            arrays, meta = specimen_file.read(o.specimen)
            assembly = study.assembly_of(meta, arrays["member_begin"])
        except specimen_file.SpecimenFileError as exc:
            raise cli.InputError(str(exc)) from None
        except cli.InputError as exc:
            raise cli.InputError("%s: %s" % (o.specimen, exc)) from None
        if o.assembly and assembly != o.assembly:
            raise cli.InputError("%s is a %s specimen, not %s (--assembly)" % (o.specimen, assembly, o.assembly))
        o.assembly = assembly
        problem = triaxial.rolling_problem(o.rolling_stiffness, o.rolling_friction, assembly != "sphere")
        if problem:
            raise cli.InputError(problem)
        return states  # the specimen's checks against the states are the study's own (study.check)
    o.assembly = o.assembly or "sphere"
    o.n = DEFAULT_N if o.n is None else o.n
    o.seed = DEFAULT_SEED if o.seed is None else o.seed
    problem = triaxial.rolling_problem(o.rolling_stiffness, o.rolling_friction, o.assembly != "sphere")
    if problem:
        raise cli.InputError(problem)
    if o.assembly != "sphere":
        try:
            clump_specimen.check_count(o.assembly, o.n)
        except ValueError as exc:
            raise cli.InputError(str(exc)) from None
        check_memory(o)  # before the layers' check, which draws every clump
        problem = clump_specimen.layers_problem(o.assembly, o.n, o.seed)
        if problem:
            raise cli.InputError(problem)
    # Before the specimen is prepared (minutes at 4000 spheres), not after it: the specimen will sit
    # at its preparation pressure within the preparation's stress tolerance, so the path rate is
    # checked from there now, that far off (study.check checks it again on the file).
    defaults = inspect.signature(specimen.prepare_spheres if o.assembly == "sphere"
                                 else clump_specimen.prepare_clumps).parameters
    study.refuse_slow_paths(states, "true-triaxial", (defaults["pressure"].default,) * 3, dict(path_rate=o.path_rate),
                            start_within=defaults["stress_tolerance"].default)
    check_memory(o)
    study.host_named(o.host)  # --host yade outside yade-double, or without the plugin: said before any work
    return states


def check_memory(o):
    spheres = o.n * members(o.assembly)
    prep, _ = resources.preparation_estimate(spheres, o.threads or resources.cores())
    # The static solve's memory goes with the bodies' degrees of freedom and the contacts (members).
    statics_memory = resources.interpreter_bytes() + resources.STATICS_BYTES_PER_SPHERE * spheres
    resources.check_memory(max(prep, statics_memory), "a study of %s (its exact static solve)"
                           % clump_specimen.particles(o.n, o.assembly))


def members(assembly):
    return 1 if assembly == "sphere" else clump_specimen.members_per_clump(assembly)


def recipe(o):
    """What the study's specimen is made from: the assembly, count and seed, and the assembly's
    recipe by name and settings (`recipe_settings`). It keys the preparation's checkpoint and is
    part of the study's fingerprint, so that a specimen or checkpoint made by another recipe (the
    default changed since) is never taken for this one."""
    return dict(assembly=o.assembly, n=o.n, seed=o.seed, recipe="default", settings=recipe_settings(o.assembly))


# Keywords of a preparation that are not settings of its recipe.
_NOT_RECIPE = ("n", "seed", "progress", "checkpoints", "max_steps", "switch_pressure", "size_distribution", "assembly")


def recipe_settings(assembly):
    """Every setting the assembly's default preparation is made with: the preparation's own defaults
    (friction, rates, tolerances), the clumps' recipe (clump_recipes.RECIPES: shape, sizes,
    orientations, stages), the size distribution and the switch pressure it resolves to."""
    prepare = specimen.prepare_spheres if assembly == "sphere" else clump_specimen.prepare_clumps
    out = {k: p.default for k, p in inspect.signature(prepare).parameters.items()
           if p.default is not inspect.Parameter.empty and k not in _NOT_RECIPE and p.default is not None}
    if assembly == "sphere":
        out.update(d50=psd.PAPER_SPHERES.d50, cu=psd.PAPER_SPHERES.cu)
        fraction = out["switch_fraction"]
    else:
        out.update(clump_specimen.recipe(assembly))
        fraction = out["switch_fraction"]
    out["switch_pressure"] = specimen.default_switch_pressure(out["pressure"], fraction, out["stress_tolerance"])
    return json.loads(json.dumps(out))  # as metadata.json holds it (tuples as lists)


def describe(r):
    return "--assembly %s --n %s --seed %s" % (r.get("assembly", "sphere"), r.get("n"), r.get("seed"))


def recipe_said(have, want):
    """How the recipe of `have` differs from `want` ("settings.mu_prep: 0.01 there, 0 here"; a
    study or specimen made before its recipe was recorded says so), or None when it is the same."""
    if have.get("settings") is None:
        return "made before run_study.py recorded its recipe, so not provably by this one (%s)" % want.get("recipe")
    diff = study_dir.said(study_dir.differences({k: have.get(k) for k in ("recipe", "settings")},
                                                {k: want[k] for k in ("recipe", "settings")}, rel_tol=1e-9))
    return "made by another recipe (%s)" % "; ".join(diff) if diff else None


def specimen_recipe_problem(params, want):
    """How the recipe a specimen file records (its parameters) differs from `want`'s settings, or
    None. Only what the file records is compared; a switch pressure it lacks is its final pressure
    (every file made before the unloading)."""
    settings = want["settings"]
    have = {k: params[k] for k in settings if k in params}
    have["switch_pressure"] = params.get("switch_pressure", params.get("pressure", settings["pressure"]))
    diff = study_dir.said(study_dir.differences(json.loads(json.dumps(have)), {k: settings[k] for k in have},
                                                rel_tol=1e-9))
    return "made by another recipe than this run's default (%s)" % "; ".join(diff) if diff else None


def check_recipe(o, log):
    """Refuse, before any preparation, a rerun that asks for another specimen than the study's."""
    meta = study_dir.read_metadata(o.out)
    want = recipe(o)
    if meta is not None:
        study_dir.require_layout(o.out, meta)
        have = meta.get("fingerprint", {}).get("recipe")
        if have is not None:
            have = dict(dict(assembly="sphere"), **have)  # studies written before clumps are sphere studies
        if have is not None and describe(have) != describe(want):
            raise study_dir.StudyMismatch(
                "%s holds another study: its specimen is %s, this run asks %s; %s"
                % (o.out, describe(have), describe(want),
                   study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
        other = have is not None and recipe_said(have, want)
        if other:
            raise study_dir.StudyMismatch("%s holds another study: its specimen was %s; %s" % (
                o.out, other, study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
    path = os.path.join(o.out, SPECIMEN)
    if not os.path.exists(path):
        if meta is not None and meta.get("fingerprint", {}).get("recipe") is None:
            # A run_states.py study keeps its specimen where the user had it, not in the directory.
            raise study_dir.StudyMismatch(
                "%s holds a study of the specimen %s, not of one run_study.py prepared in it: continue it with "
                "--specimen SPECIMEN (run_study.py or run_states.py), or %s"
                % (o.out, meta.get("specimen", {}).get("path", "?"),
                   study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
        if meta is not None:
            raise study_dir.StudyMismatch("%s holds a study whose %s is missing; %s" % (
                o.out, SPECIMEN, study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
        return None
    try:
        scene, spec_meta = specimen_file.load(path)
    except specimen_file.SpecimenFileError as exc:
        raise study_dir.StudyMismatch("%s; %s" % (exc, study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
    have = dict(assembly=spec_meta["parameters"].get("assembly", "sphere"), n=spec_meta["parameters"].get("n"),
                seed=spec_meta["seed"])
    if describe(have) != describe(want):
        raise study_dir.StudyMismatch(
            "%s holds another study: its specimen is %s, this run asks %s; %s"
            % (o.out, describe(have), describe(want),
               study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
    other = specimen_recipe_problem(spec_meta["parameters"], want)
    if other:
        raise study_dir.StudyMismatch("%s holds another study: its specimen (%s) was %s; %s" % (
            o.out, describe(have), other, study_dir.WAY_OUT % os.path.join(o.out, study_dir.SUPERSEDED)))
    log("specimen: kept %s" % path)
    prep_checkpoint.Checkpoints(prep_checkpoint.path_for(path), {}).remove()  # of a run killed after its save
    return scene


def prepare(o, log):
    path = os.path.join(o.out, SPECIMEN)
    # The engines' own count (set by main), not all cores: those would say 16 s for 31 s under OMP_NUM_THREADS=1.
    memory, seconds = resources.preparation_estimate(o.n * members(o.assembly), engines.threads(), o.assembly)
    log("specimen: preparing %s (seed %d): about %s of memory and %s%s ..."
        % (clump_specimen.particles(o.n, o.assembly), o.seed, resources.human_bytes(memory),
           resources.human_seconds(seconds), resources.preparation_caveat(o.assembly, o.n)))
    t0 = time.time()
    bar = progress.Progress("specimen", log, o.progress_every)
    # Checkpoints every so many steps: a run killed while it prepares resumes (prep_checkpoint).
    checkpoints = prep_checkpoint.for_specimen(path, recipe(o), log=log, way_out="--force-new")
    if o.assembly == "sphere":
        scene, params = specimen.prepare_spheres(o.n, seed=o.seed, progress=bar.preparation, checkpoints=checkpoints)
    else:
        scene, params = clump_specimen.prepare_clumps(o.assembly, o.n, seed=o.seed, progress=bar.preparation,
                                                      checkpoints=checkpoints)
    params.setdefault("assembly", o.assembly)
    params["threads"] = engines.threads()
    specimen_file.save(path, scene, seed=o.seed, parameters=params, summary=specimen.state(scene))
    checkpoints.remove()  # only now: the specimen is complete on disk
    log("specimen: saved %s (%.1f s)" % (path, time.time() - t0))
    # Everything after this starts from the file, as a rerun does: the same numbers either way.
    return specimen_file.load(path)[0]


def main(argv=None):
    o = cli.parse(parser(), argv)
    states = validate(o)
    specimen_path = o.specimen or os.path.join(o.out, SPECIMEN)
    cli.saves_work_in(lambda: study_dir.has_saved_work(o.out) or (
        not o.specimen and (os.path.exists(specimen_path) or os.path.exists(prep_checkpoint.path_for(specimen_path)))),
        resumes=lambda: cli.RESUMES_STUDY if os.path.exists(specimen_path) else cli.RESUMES_PREPARATION)
    if o.threads:
        resources.use_threads(o.threads)

    log = progress.say
    t0 = time.time()
    with lock.held(o.out, wait=o.wait, log=log):
        if o.force_new:
            study_dir.supersede(o.out, log)
        path = specimen_path
        walk, servo, probe = study_options.objects(o)
        options = dict(path=walk, servo=servo, probe=probe, recipe=None if o.specimen else recipe(o), host=o.host)
        if o.specimen:  # the user's file: checked whole, as run_states.py checks it
            try:
                scene = specimen_file.load(path)[0]
            except specimen_file.SpecimenFileError as exc:
                raise cli.InputError(str(exc)) from None
        else:
            scene = check_recipe(o, log)  # a refusal changes nothing
        if scene is not None:
            study.check(path, states, o.out, **options)  # the whole fingerprint, before anything is written
        study_dir.clean_strays(o.out, log)
        scene = scene or prepare(o, log)
        # The summary is derived; it is written again at the end, so a run that stops never
        # leaves one that describes other rows than probes.csv holds.
        study_dir.remove([os.path.join(o.out, "summary.json")])
        st = specimen.state(scene)
        atomic.write_json(os.path.join(o.out, "specimen_state.json"), st)
        log("specimen: e = %.4f, Zm = %.3f, sigma = (%.2f, %.2f, %.2f) kPa, principal (%.2f, %.2f, %.2f) kPa, "
            "largest off-diagonal %.3f kPa, unbalanced = %.2e"
            % (st["void_ratio"], st["Zm"], st["sigma_x"] / 1e3, st["sigma_y"] / 1e3, st["sigma_z"] / 1e3,
               st["sigma_1"] / 1e3, st["sigma_2"] / 1e3, st["sigma_3"] / 1e3, st["tau_max"] / 1e3, st["unbalanced"]))
        # State 21's static solve reads its checkpoint: one lost after its probes were done is
        # reached again rather than leaving the study stuck (the record, once written, suffices).
        b1 = "21" in {str(sid) for sid, _, _ in states} and not os.path.exists(statics.state_file(o.out, "21"))
        try:
            study.run_states(path, states, o.out, log=log, progress_every=o.progress_every,
                             checkpoints=("21",) if b1 else (), **options)
        except triaxial.StateNotReached as exc:
            cli.fail(str(exc), 1)
        # The isotropic state, and state 21 (Table B1's second state) when asked: each solve's
        # result line after its own "solving" line, state 21's too.
        sres = None
        spec_meta = specimen_file.read(path)[1]  # what the records are of (statics.identity)
        for what, state in (("isotropic state", None), ("state 21", "21")):
            if state is not None and state not in {str(sid) for sid, _, _ in states}:
                continue
            rec = statics.cached_record(o.out, state, scene=scene if state is None else None, log=log,
                                        meta=spec_meta if state is None else None)
            sres = sres or rec
            log("statics (%s): E_free = %s MPa, E_blocked = %s MPa, magnitude zeta_h = %s, zeta_v = %s"
                % (what, [round(e / 1e6, 1) for e in rec["E_free"]], [round(e / 1e6, 1) for e in rec["E_blocked"]],
                   statics.said_zeta(rec["zeta_h"]), statics.said_zeta(rec["zeta_v"])))
        csv_path = os.path.join(o.out, study.CSV_NAME)
        material = spec_meta["material"]
        contrast = zeta_contrast.fit(csv_path, material["shear_modulus"], material["poisson"])
        if contrast:
            log("%s; the magnitude zeta above answers another question (docs/statics.md 7.1)"
                % zeta_contrast.said(contrast))
        fig_dir = os.path.join(o.out, "figures")
        os.makedirs(fig_dir, exist_ok=True)
        rows = study.read_rows(csv_path)
        who = figures.study_who(o.out)
        figures.modulus_vs_stress(rows, os.path.join(fig_dir, "E_vs_sigma.png"), who)
        fits = figures.scalar_moduli_vs_zm(rows, os.path.join(fig_dir, "K_G_vs_Zm.png"), who)
        report_path, _ = report.build(o.out, os.path.join(o.out, "report"), log=log)
        atomic.write_json(os.path.join(o.out, "summary.json"), dict(
            specimen=st, states=len({r["state"] for r in rows}), probes=len(rows), statics=sres, K_G_fits=fits,
            zeta_contrast=contrast, report=os.path.relpath(report_path, o.out),
            # this run's: a resumed study's earlier runs are in probes.csv's state and probe times
            run_wall_time=time.time() - t0))
    cli.work_done()  # the rest is lines and YADE's O: a Ctrl-C now ends a finished run
    log("results: %s (probes.csv, figures/, summary.json); this run took %.0f s" % (o.out, time.time() - t0))
    log("report: %s" % report_path)
    if cli.in_yade():
        from trueaniso import yade_bridge
        yade_bridge.yade_scene_from(scene, import_contacts=False)
        log("specimen written into YADE's O (%d particles) for viewing/export" % scene.num_bodies)


if __name__ == "__main__":  # also under yade-double -x; an import (even inside YADE) runs nothing
    cli.guarded(main, resumable=True)
else:  # loaded, not run (mpi4py.futures' workers load the script): no start-up guard left behind
    cli.release_start_guard()
