"""Runs true-triaxial states and their probes on a specimen, with results written as they come.

Layout of a results directory (one study: trueaniso/study_dir.py, docs/runs.md)::

  metadata.json    the study's fingerprint (the loading path included), its states (id -> b,
                   sigma_z), the runs that wrote it
  probes.csv       one row per state and probe direction, appended as each probe ends
  states/ID.npz    the specimen held at state ID (a checkpoint, with the steps that made it)
  .lock            the lock a run holds while it writes here

Every state and every probe starts from a file: a state from the checkpoint of the state before it
on its loading path (or from the specimen), a probe from its state's checkpoint, re-loaded for
each probe. A run that was interrupted and resumed therefore computes exactly what an
uninterrupted run computes, bit for bit: both start every piece of work from the same bytes.
Rows already in probes.csv are not run again.
"""
import contextlib
import math
import os
import sys
import time

import numpy as np

from . import (cli, dem, engines, fabric, lock, provenance, resources, results_csv, run_cost, specimen, specimen_file,
               study_checks, study_dir, triaxial, validate)
from .options import UNRECORDED_TIME_STEP, PathOptions, ProbeOptions, ServoOptions, flag
from .progress import EVERY, Progress, chunk_for, say
from .refusal import InputError

# A row is also the state's record: its six stresses, the principal values and the largest
# off-diagonal. E and nu_* are empty in a shear probe's row, G in a normal probe's. `specimen` is
# the specimen's checksum (metadata.json's fingerprint.specimen): a row of another study's
# specimen put into the table is refused by every reader (study_checks.specimen_problem). A table
# whose header lacks it keeps its columns: rows appended to it are written without it.
__all__ = ["run_states", "table_states", "parse_ids", "parse_states", "state_id", "read_rows"]

COLUMNS = ["path", "state", "b", "sigma_z_goal", "sigma_x", "sigma_y", "sigma_z", "sigma_yz", "sigma_xz",
           "sigma_xy", "sigma_1", "sigma_2", "sigma_3", "tau_max", "q", "probe", "sign",
           "d_sigma_x", "d_sigma_y", "d_sigma_z", "d_sigma_yz", "d_sigma_xz", "d_sigma_xy", "d_eps_x", "d_eps_y",
           "d_eps_z", "d_gamma_yz", "d_gamma_xz", "d_gamma_xy", "E", "nu_1", "nu_2", "nu_1_name", "nu_2_name", "G",
           "gamma", "Zm", "void_ratio", "rotations", "detection", "damping",
           "probe_steps", "probe_wall_time", "state_steps", "state_wall_time", "state_from", "specimen"]
WALL_TIME_COLUMNS = ("probe_wall_time", "state_wall_time")  # the only columns a rerun does not reproduce
CSV_NAME = study_dir.CSV_NAME


def read_rows(path):
    """The complete rows of a probe table, probes.csv; a torn last row is left out (`results_csv`).

    Returns:
        list: one dict of text per row, by column name.

    Example:
        >>> import tempfile
        >>> from trueaniso import study
        >>> from trueaniso.options import PathOptions
        >>> out = tempfile.mkdtemp()
        >>> _ = study.run_states("tests/data/spheres-150-s4.npz", study.table_states([1]), out,
        ...                      path=PathOptions(probes=("z",)), log=lambda line: None)
        >>> [(r["state"], r["probe"]) for r in study.read_rows(out + "/probes.csv")]
        [('1', 'z')]
    """
    return results_csv.read(path).rows


def _recorded(options):
    """A fingerprint's part as metadata.json stays standard JSON (which has no Infinity or NaN;
    --path-rate inf wrote "path_rate": Infinity, which JavaScript's and other strict parsers
    refuse): a non-finite number is kept as its text, "inf"."""
    return {k: repr(v) if isinstance(v, float) and not math.isfinite(v) else v for k, v in options.items()}


def options_of(path=None, servo=None, probe=None, probes=None, gamma=None, restrain_rotations=None,
               skip_detection=None, damping=None, state_options=None, probe_options=None):
    """(PathOptions, ServoOptions, ProbeOptions) of a study from the objects and/or the keywords
    run_states took before them: probes, gamma, restrain_rotations, skip_detection, damping (the
    servo's and the probes' both), state_options (fields of ServoOptions), probe_options (of
    ProbeOptions). Each is checked once, here."""
    if isinstance(path, str):
        path = PathOptions(path=path)
    path = PathOptions.of(path, {} if probes is None else dict(probes=tuple(probes)), "run_states")
    shared = {} if damping is None else dict(damping=damping)
    servo = ServoOptions.of(servo, dict(state_options or {}, **shared), "run_states (state_options)")
    given = dict(gamma=gamma, restrain_rotations=restrain_rotations, skip_detection=skip_detection)
    probe = ProbeOptions.of(probe, dict(probe_options or {}, **shared, **{k: v for k, v in given.items() if v is not None}),
                            "run_states (probe_options)")
    return path, servo, probe


# Who steps the states and probes (run_states.py --host): our own stepper, or YADE's loop with the
# plugin's classes in O.engines (yade_host). The same protocol, specimen, checkpoints and rows.
HOSTS = ("trueaniso", "yade")


class _Stepper:
    """Our own stepper: triaxial.reach_state, triaxial.probe and fabric.fabric_row on the scene."""
    name = "trueaniso"

    @staticmethod
    def reach_state(scene, *args, **kw):
        return scene, triaxial.reach_state(scene, *args, **kw)

    probe = staticmethod(triaxial.probe)
    fabric_row = staticmethod(fabric.fabric_row)


def host_named(name):
    """The host of that name (HOSTS), or InputError saying why it cannot run here."""
    if name == "trueaniso":
        return _Stepper
    if name == "yade":
        from . import yade_host
        problem = yade_host.problem()
        if problem:
            raise InputError(problem)
        return yade_host
    raise InputError("unknown host %r: the hosts are %s" % (name, ", ".join(HOSTS)))


def _host_fingerprint(name):
    """What a study's rows depend on of its host, beyond our engines: none for our stepper (its
    studies' fingerprints are as they were); YADE's name and thread count for YADE's loop."""
    if name == "trueaniso":
        return None
    from . import yade_host
    return dict(name=name, threads=yade_host.threads())


ASSEMBLIES = ("sphere", "clump1", "clump2")  # what prepare_specimen.py builds (the paper's three)
UNNAMED_CLUMPS = "clumps"  # a clump packing saved without an assembly (the YADE bridge, a script)


def assembly_of(specimen_meta, member_begin):
    """The assembly of a specimen: the one prepare_specimen.py recorded, checked against the file's
    bodies (sphere: no clumps; clump1, clump2: clumps), or, when none is recorded, sphere for a
    file without clumps and UNNAMED_CLUMPS for one with clumps, so that a clump packing saved
    without the parameter is not taken for spheres (and its report compared with the paper's
    spheres). Raises InputError for a recorded assembly that is unknown or contradicts the
    bodies."""
    import numpy as np
    spheres = bool(np.all(np.diff(np.asarray(member_begin)) == 1))
    declared = (specimen_meta.get("parameters") or {}).get("assembly")
    if declared is None:
        return "sphere" if spheres else UNNAMED_CLUMPS
    if declared not in ASSEMBLIES:
        raise InputError("the specimen records assembly %r, which is none of %s" % (declared, ", ".join(ASSEMBLIES)))
    if (declared == "sphere") != spheres:
        raise InputError("the specimen records assembly %s but holds %s" % (declared, "no clumps" if spheres
                                                                               else "clumps"))
    return declared


def fingerprint(specimen_meta, assembly, gamma, restrain_rotations, skip_detection, damping, state_options=None,
                probe_options=None, recipe=None, path="true-triaxial", host="trueaniso"):
    """What every row and checkpoint of a study depends on (study_dir compares it on reruns), from
    the keywords of run_states before its option objects (study_fingerprint takes those)."""
    path, servo, probe = options_of(path, None, None, None, gamma, restrain_rotations, skip_detection, damping,
                                    state_options, probe_options)
    return study_fingerprint(specimen_meta, assembly, path, servo, probe, recipe, host)


def study_fingerprint(specimen_meta, assembly, path, servo, probe, recipe=None, host="trueaniso"):
    """What every row and checkpoint of a study depends on (study_dir compares it on reruns); the
    loading path too, which gives a state definition (b, sigma_z) its mean stress."""
    # The assembly is also behind the specimen's checksum; named here so a refusal can say it.
    fp = dict(specimen=specimen_meta["sha256"], assembly=assembly,
              code=provenance.code_version(), threads=engines.threads(), path=path.path,
              state=_recorded(dict(damping=servo.damping, **servo.fingerprint())),
              probe=_recorded(probe.fingerprint(assembly != "sphere", specimen_meta.get("block_rotations"))))
    if recipe:
        fp["recipe"] = recipe
    stepped_by = _host_fingerprint(host)
    if stepped_by:
        fp["host"] = stepped_by
    return fp


def _study(specimen_path, states, path_o, servo, probe, recipe, host="trueaniso"):
    """Every check that needs no work, then (ids, axes, specimen metadata, fingerprint)."""
    stepper = host_named(host)
    if host != "trueaniso":
        try:
            stepper.check_options(servo.keywords(), probe.keywords())
        except ValueError as exc:
            raise InputError(str(exc)) from None
    path = path_o.path
    for i, b, sz in states:
        try:
            triaxial.validate_path_state(path, b, sz)  # every state checked before any work
        except ValueError as exc:
            raise InputError("state %s: %s" % (i, exc)) from None
    ids = [str(i) for i, _, _ in states]
    if len(set(ids)) != len(ids):
        raise InputError("a state is given twice (ids %s)" % ", ".join(sorted({i for i in ids if ids.count(i) > 1})))
    # One state under two names: at sigma_z = p every b gives the isotropic state, which was
    # reached and probed once per name (the same rows twice, and twice the work).
    named = {}
    for i, b, sz in states:
        key = tuple(float("%.12g" % x) for x in triaxial.path_stresses(path, b, sz))
        if key in named:
            raise InputError("states %s and %s are one state: both have principal stresses (%s) Pa; give it once"
                             % (named[key], i, ", ".join("%.12g" % x for x in key)))
        named[key] = i
    axes = list(path_o.probes)
    # The whole load (the scene built, its contacts checked against its positions), not only the
    # file's read: a specimen refused at its load after metadata.json was written left a study
    # behind in a new --out, and --force-new had moved the old study aside for it.
    scene, spec_meta = specimen_file.load(specimen_path)
    assembly = assembly_of(spec_meta, scene.member_begin)
    if "checkpoint" in (spec_meta.get("parameters") or {}):  # prep_checkpoint's: mid-preparation, not at rest
        raise InputError("%s is a preparation checkpoint, a specimen not yet made; finish it by running its "
                         "preparation again (the same prepare_specimen.py or run_study.py command)" % specimen_path)
    summary = _summary(specimen_path, spec_meta)
    prepared_with = (spec_meta.get("parameters") or {}).get("time_step", UNRECORDED_TIME_STEP)
    states_with = servo.time_step
    if prepared_with not in (states_with, UNRECORDED_TIME_STEP):
        # The rule is in the study's fingerprint (state.time_step), the specimen's in its file: two
        # choices. A specimen prepared with the longer step is another packing, not the same one
        # made faster, and a study that does not take that rule may be a surprise: said.
        say("note: %s was prepared with the %s time step; the states are run with the %s one (--time-step)"
            % (specimen_path, prepared_with, states_with))
    _refuse_unloaded(specimen_path, summary)
    _refuse_exploded(specimen_path, scene, states, path)
    _refuse_unreachable(states, path, dict(spec_meta, summary=summary), servo.keywords())
    if spec_meta["block_rotations"] and not probe.restrain_rotations:
        raise InputError("specimen %s blocks rotations (block_rotations true), so its probes are rotation-"
                         "restrained: ask for --rotations restrained" % specimen_path)
    fp = study_fingerprint(spec_meta, assembly, path_o, servo, probe, recipe, host)
    return ids, axes, spec_meta, fp


def _listed(ids, most=12):
    """'1, 5, 9' or, for a long list, its first ids and how many more."""
    return ", ".join(ids) if len(ids) <= most else "%s and %d more" % (", ".join(ids[:most]), len(ids) - most)


def _summary(specimen_path, spec_meta):
    """The specimen's summary (its stresses, void ratio, Zm): as saved, or measured on the file's
    scene when it has none. A specimen saved from a YADE scene (yade_bridge, specimen_file.save)
    carries none, and the checks that read it would be skipped (--path-rate 1e-9 would start
    loading)."""
    summary = spec_meta.get("summary") or {}
    if all(k in summary for k in ("sigma_x", "sigma_y", "sigma_z", "void_ratio", "Zm")):
        return summary
    scene, _ = specimen_file.load(specimen_path)
    dem.refresh(scene)  # the forces of the saved positions: what a loaded scene lacks
    try:
        return specimen.state(scene)
    except ValueError:  # no contact carries a force: no stress to start from, nothing to check
        return summary


def _refuse_unloaded(specimen_path, summary):
    """InputError for a specimen that carries no stress (a loose cloud, no loaded contact, as a YADE
    scene saved before it was consolidated): the servo would strain it to its 5 % limit and report
    that 'the specimen fails' at stresses (0, 0, 0) kPa."""
    stresses = [summary.get(k) for k in ("sigma_x", "sigma_y", "sigma_z")]
    if None in stresses:  # nothing measured (a scene that could not be evaluated): the servo's own checks
        return
    if summary.get("Nc", 1) == 0 or max(abs(x) for x in stresses) == 0:
        raise InputError("specimen %s carries no stress (%s loaded contacts, void ratio %s): a stress path starts "
                         "from a consolidated packing; prepare one with prepare_specimen.py, or consolidate the "
                         "scene (in YADE, say) before saving it" % (specimen_path, summary.get("Nc", 0),
                                                                   "%.3g" % summary["void_ratio"]
                                                                   if "void_ratio" in summary else "unknown"))


EXPLODED = 100.0  # a specimen stressed this many times the largest stress its study asks for is refused


def _refuse_exploded(specimen_path, scene, states, path):
    """InputError for a specimen whose contacts carry far more than any stress the study asks for
    (an exploded or over-compressed packing, measured on its contacts, whatever its summary says):
    at 800 MPa against 100-200 kPa states the servo would run its 3,000,000 steps and give up. A
    specimen prepared at 1 MPa for a study at 100 kPa (10 times) is still taken."""
    if not states:
        return
    try:
        sig = np.linalg.eigvalsh(np.asarray(engines.stress(scene)))
    except (ValueError, RuntimeError):
        return
    largest = float(np.max(np.abs(sig)))
    asked = max(max(abs(x) for x in triaxial.path_stresses(path, b, sz)) for _, b, sz in states)
    if np.isfinite(largest) and asked > 0 and largest > EXPLODED * asked:
        raise InputError("specimen %s carries a stress of %.4g kPa on its contacts (largest principal, measured), %.0f "
                         "times the largest stress this study asks for (%.4g kPa): an exploded or over-compressed "
                         "packing, which the servo cannot bring back; prepare it again (prepare_specimen.py)"
                         % (specimen_path, largest / 1e3, largest / asked, asked / 1e3))
    if not np.isfinite(largest):
        raise InputError("specimen %s carries a non-finite stress on its contacts: prepare it again" % specimen_path)


def _refuse_unreachable(states, path, spec_meta, state_options):
    """InputError for a state the servo cannot reach from this specimen: one whose stress presses
    the contacts beyond Hertz's range (triaxial.hertz_range_problem, in the specimen's own
    packing), checked first for every state, or one too far for the path rate (refuse_slow_paths)."""
    m, summary = spec_meta["material"], spec_meta.get("summary") or {}
    packing = dict(solid_fraction=1.0 / (1.0 + summary["void_ratio"]), coordination=summary["Zm"]) \
        if summary.get("void_ratio", 0) > 0 and summary.get("Zm", 0) > 0 else triaxial.DENSE_PACKING
    for i, b, sz in states:
        problem = triaxial.hertz_range_problem(max(triaxial.path_stresses(path, b, sz)), m["shear_modulus"],
                                               m["poisson"], what="state %s: its largest principal stress" % i,
                                               **packing)
        if problem:
            raise InputError(problem)
    start = [summary.get(k) for k in ("sigma_x", "sigma_y", "sigma_z")]
    if None not in start:
        refuse_slow_paths(states, path, start, state_options)


def refuse_slow_paths(states, path, start, state_options=None, start_within=0.0):
    """InputError for a state too far for the servo's path rate within its max_steps (1e-9 Pa per
    step ran 3,000,000 steps, then blamed equilibrium). Each state is measured from where it
    starts, as run_states walks the paths (triaxial.paths): from the state before it on its
    loading path, the first from `start` (the specimen's principal stresses, known to within
    `start_within` Pa before the specimen exists): measured from the specimen, state 3 would be
    refused at rates state 2's checkpoint reaches it at. The ramp must end `settle_steps`
    before max_steps: the servo holds the goal that long before it calls a state reached (a ramp
    ending within them was accepted, then ran out of steps)."""
    servo = dict(ServoOptions.defaults(), **(state_options or {}))
    # .get: a stand-in for the servo (a test's) declares no defaults, and so sets no limit
    rate, limit = float(servo.get("path_rate", math.inf)), servo.get("max_steps", math.inf)
    room = limit - engines.TrueTriaxialServo().settle_steps
    for group in triaxial.paths(states).values():
        where, before, within = "the specimen's stress, where its path starts", start, start_within
        for i, b, sz in group:
            goal = triaxial.path_stresses(path, b, sz)
            way = max(abs(g - s0) for g, s0 in zip(goal, before)) + within
            if way / rate > room:
                least = _rounded_up(way / room)
                raise InputError("--path-rate %g: state %s is %s%.6g Pa from %s%s: about %.3g steps at that rate, "
                                 "beyond the servo's %d (less the %d it holds a state before calling it reached); "
                                 "the least rate that fits is %.3g Pa per step, and twice that leaves half its steps "
                                 "to settle%s"
                                 % (rate, i, "up to " if within else "", way, where,
                                    " (known to within %g Pa before it is prepared)" % within
                                    if within else "", way / rate, limit, limit - room, least,
                                    _nearer_states(path, i, b, sz, [str(s[0]) for s in group])))
            where, before, within = "state %s's stress, the state before it on its path" % i, goal, 0.0


def _rounded_up(x):
    """x rounded up at its third significant digit (a least rate printed lower would not fit)."""
    unit = 10.0 ** (math.floor(math.log10(x)) - 2)
    return math.ceil(x / unit - 1e-9) * unit


def _nearer_states(path, sid, b, sz, asked):
    """'; or ask for the states before it on its path too (--ids 2,3,4,5)': a Table C1 state is
    reached from the one before it that is asked, so the nearer ones shorten its way at any rate
    (a study's rate is fixed: advice to raise it would lead to another refusal)."""
    if path != "true-triaxial":
        return ""
    for group in triaxial.paths(triaxial.table_c1_states()).values():
        ids = [str(i) for i, _, _ in group]
        if str(sid) in ids and (group[ids.index(str(sid))][1:] == (b, sz)):
            before = ids[:ids.index(str(sid))]
            if before and not set(before) <= set(asked):
                return "; or ask for the states before it on its path too (--ids %s)" % ",".join(
                    [i for i in ids if i in set(before) | set(asked) | {str(sid)}])
    return ""


def check(specimen_path, states, out, path=None, servo=None, probe=None, recipe=None, host="trueaniso", **settings):
    """What run_states checks before any work, alone (run_study.py asks before it writes anything):
    the metadata of the study in `out` (None for a new one), or a refusal. The caller holds the
    lock. The options as run_states takes them."""
    assert lock.is_held(out)
    path, servo, probe = options_of(path, servo, probe, **settings)
    _, _, _, fp = _study(specimen_path, states, path, servo, probe, recipe, host)
    return study_dir.check(out, fp, states)


def run_states(specimen_path, states, out, path=None, servo=None, probe=None, log=print, wait=False, force_new=False,
               progress_every=EVERY, recipe=None, executor=None, checkpoints=(), host="trueaniso", **settings):
    """Run true-triaxial states and their probes on a specimen, writing each result as it comes (module doc).

    The results directory `out` is one study: a rerun continues it where it stopped (after a kill
    too) and may add states; a rerun that asks for other settings is refused (study_dir). Each state
    is reached from the checkpoint of the state before it on its loading path, each probe from its
    state's checkpoint, so a resumed run computes what an uninterrupted one does, bit for bit.

    Args:
        specimen_path: the specimen file (.npz) the study starts from.
        states: (id, b, sigma_z) per state (`table_states`, `parse_states`,
            `triaxial.cross_anisotropic_states`); ids name the rows and the checkpoints.
        out: the results directory (made if missing).
        path: `options.PathOptions` (the loading path, which sets each state's mean stress, and the
            probe axes), or the path's name (one of `triaxial.PATHS`); None: the true-triaxial path,
            probes z, x, y.
        servo: `options.ServoOptions`, how the states are reached and held (None: the defaults).
        probe: `options.ProbeOptions`, how they are probed (None: the defaults).
        log: called with each line the run says (print by default).
        wait: True waits for another run that holds the study's lock instead of refusing.
        force_new: True moves an existing study in `out` into out/superseded/ and starts a new one.
        progress_every: seconds between progress lines.
        recipe: a description of the specimen's recipe, recorded in the study's fingerprint.
        executor: a concurrent.futures executor (e.g. mpi4py.futures.MPIPoolExecutor) whose workers
            each walk whole loading paths and hand their rows back; the values equal a serial run's,
            the rows come in the order the paths end.
        checkpoints: ids of states whose checkpoint must exist when the run ends even if their probes
            are all done; a missing one is reached again along its path, which reproduces its bytes.
        **settings: the keywords run_states took before the option objects, on top of them
            (`options_of`): ``probes`` (axes 0-5 or "x", "y", "z", "yz", "xz", "xy"), ``gamma``,
            ``restrain_rotations``, ``skip_detection``, ``damping`` (the servo's and the probes'),
            ``state_options`` (fields of ServoOptions), ``probe_options`` (fields of ProbeOptions).
        host: "trueaniso" (our stepper) or "yade" (YADE's loop with the plugin's classes, under
            yade-double: `trueaniso.yade_host`, docs/yade-peer.md section 8); "yade" takes no executor.

    Returns:
        list: the complete rows of probes.csv after the run, one dict of text per state and probe
        (columns: `COLUMNS`, reference/formats/probes-csv).

    Raises:
        trueaniso.refusal.InputError: a specimen, state, option or study directory that does not fit
            (an option of the wrong type too: ``wait="no"``), before any work.
        TypeError: a keyword that is no option.
        trueaniso.study_dir.StudyMismatch: a rerun that asks for other settings than the study's.

    Example:
        >>> import tempfile
        >>> from trueaniso import study
        >>> from trueaniso.options import PathOptions, ProbeOptions
        >>> out = tempfile.mkdtemp()
        >>> rows = study.run_states("tests/data/spheres-150-s4.npz", study.table_states([1]), out,
        ...                         path=PathOptions(probes=("z", "x", "y")), probe=ProbeOptions(gamma=1e-6),
        ...                         log=lambda line: None)
        >>> [(r["state"], r["probe"], "%.0f MPa" % (float(r["E"]) / 1e6)) for r in rows]
        [('1', 'z', '278 MPa'), ('1', 'x', '278 MPa'), ('1', 'y', '288 MPa')]
    """
    if executor is not None and host != "trueaniso":
        raise InputError("--host %s steps the states in this process's YADE: it takes no MPI workers" % host)
    path_o, servo, probe = options_of(path, servo, probe, **settings)
    wait, force_new = flag("run_states", "wait", wait), flag("run_states", "force_new", force_new)
    path = path_o.path
    ids, axes, spec_meta, fp = _study(specimen_path, states, path_o, servo, probe, recipe, host)
    record = dict(started=time.strftime("%Y-%m-%dT%H:%M:%S%z"), argv=sys.argv, table=os.environ.get("YADE_BATCH"),
                  states=ids, probes=axes,
                  versions=provenance.versions(),
                  specimen=dict(path=os.path.abspath(specimen_path), sha256=spec_meta["sha256"],
                                seed=spec_meta["seed"], summary=spec_meta.get("summary"),
                                material=spec_meta.get("material"),
                                # its preparation's rule (a file that records none: smallest-inertia)
                                time_step=(spec_meta.get("parameters") or {}).get("time_step", UNRECORDED_TIME_STEP)))
    made_as = (spec_meta.get("parameters") or {}).get("state")
    if made_as is not None:  # allowed (a study may start from a state), but said: its states start stressed
        log("note: %s is the checkpoint of state %s of a study, not a specimen at its preparation pressure; "
            "this study's states are reached from that state" % (specimen_path, made_as))
    had = (spec_meta.get("material") or {}).get("rolling_stiffness", 0.0)
    if had and not servo.rolling_stiffness:
        # A state's checkpoint keeps its rolling resistance; the options of this run set the law.
        log("note: %s was made with rolling resistance (beta %g), which this run turns off; give "
            "--rolling-stiffness and --rolling-friction to keep it (docs/rolling.md)" % (specimen_path, had))
    csv_path = os.path.join(out, CSV_NAME)
    with lock.held(out, wait=wait, log=log), contextlib.ExitStack() as undo:
        if force_new:  # only now: every input passed its checks (_study)
            study_dir.supersede(out, log)
        previous = study_dir.check(out, fp, states)  # a refusal changes nothing
        undo.enter_context(study_dir.undone_if_nothing_saved(out, previous is None, log))
        study_dir.clean_strays(out, log)
        try:
            table = results_csv.repair(results_csv.read(csv_path), log)
        except results_csv.TableError as exc:
            raise study_dir.StudyMismatch("%s; %s" % (exc, study_dir.WAY_OUT % os.path.join(out, study_dir.SUPERSEDED)))
        mixed = previous and study_checks.specimen_problem(previous, table.rows)
        if mixed:
            raise study_dir.StudyMismatch("%s: %s; %s" % (csv_path, mixed,
                                                          study_dir.WAY_OUT % os.path.join(out, study_dir.SUPERSEDED)))
        known = set((previous or {}).get("states", {}))
        strange = sorted({r["state"] for r in table.rows} - known)
        if strange:
            raise study_dir.StudyMismatch("%s has rows of states %s that metadata.json does not define; %s"
                                          % (csv_path, ", ".join(strange),
                                             study_dir.WAY_OUT % os.path.join(out, study_dir.SUPERSEDED)))
        run = _Run(specimen_path, spec_meta, out, fp, axes, csv_path, table, log, progress_every, path,
                   probe.keywords(), servo.keywords(), keep=checkpoints, asked=ids, host=host)
        # The paths run over the states asked and the states earlier runs defined: a state is
        # reached from the nearest one before it on its path, so adding states to a study in path
        # order gives the rows of asking them all at once (paths of the states asked alone would
        # reach 5 from the specimen after --ids 1,2,3 then --ids 5, not from 3, and differ from one
        # run's rows, E_z by 3e-6). An earlier state whose checkpoint is
        # gone is reached again on the way, as it was first reached (_Run.start_of).
        walk = states + held_states(previous, ids)
        ordered = [path for _, path in sorted(triaxial.paths(walk).items(), key=lambda kv: (kv[0][1] != 0, kv[0]))]
        if not any(run.needs(sid) for path in ordered for sid, _, _ in path):  # said, so that a rerun that does nothing is not silent
            log("%s: the rows of every state asked for are already there; no state to run" % out)
        else:  # a run that does nothing leaves metadata.json as it was (it adds no entry to the runs)
            done = [str(sid) for sid, _, _ in states if not run.wanted(sid)]
            if done:  # a resumed run says what it keeps before it begins at its next state
                log("%s: continuing the study; %d of the %d states asked for already %s (%s)"
                    % (out, len(done), len(states), "has its rows" if len(done) == 1 else "have their rows",
                       _listed(done)))
            run.metadata = study_dir.write_metadata(out, fp, states, axes, record, previous)
            os.makedirs(os.path.join(out, "states"), exist_ok=True)
            run.meter = run_cost.Meter()
        # A state the specimen cannot reach (near its strength, the servo holds it without settling)
        # ends its own path only: the other paths go on, and the run fails at the end naming every
        # such state, rather than stopping the whole study at the first.
        failed = []
        with _cost_recorded(run, out, executor is not None, lambda: failed):
            if executor is None:
                for path in ordered:
                    try:
                        run.path(path)
                    except triaxial.StateNotReached as exc:
                        failed.append(run.path_failed(path, exc))
            else:
                failed = _run_paths_on(executor, run, ordered)
        if failed:
            raise triaxial.StateNotReached("%d loading path%s stopped (the rows of every other state are written): %s"
                                           % (len(failed), "" if len(failed) == 1 else "s", "; ".join(failed)))
        return results_csv.read(csv_path).rows


@contextlib.contextmanager
def _cost_recorded(run, out, workers_elsewhere, failed):
    """The run's cost (run_cost) added to its entry in metadata.json however the walk ends:
    'complete', 'failed' (a state not reached: `failed()` lists the paths), 'interrupted' (SIGINT,
    SIGTERM) or 'error'. A run with no work wrote no entry, and records nothing."""
    if run.meter is None:
        yield
        return
    ended = "error"

    def record():
        try:
            study_dir.record_cost(out, run.metadata, cost)
        except Exception as exc:  # the results are written; a cost unrecorded must not hide why the run ended
            run.log("note: this run's cost was not recorded in %s (%s)" % (os.path.join(out, study_dir.METADATA), exc))
    try:
        yield
        ended = "failed" if failed() else "complete"
    except BaseException as exc:
        if isinstance(exc, (KeyboardInterrupt, cli.Terminated)):
            ended = "interrupted"
        raise
    finally:
        cost = run.meter.record(ended, workers_elsewhere)
        if ended == "interrupted":
            cli.after_exit_line(record)  # the line that says the run resumes comes first
        else:
            record()


def held_states(previous, asked):
    """[(id, b, sigma_z)] of the states earlier runs of the study defined (its metadata.json,
    `previous`) that are not among `asked`: where the paths of this run continue from. Their
    checkpoints, when missing, are reached again (removing state 3's, as a refusal of a damaged
    one advises, must not make --ids 5 start from state 2)."""
    asked = {str(i) for i in asked}
    return [(int(sid) if sid.isdigit() else sid, float(d["b"]), float(d["sigma_z"]))
            for sid, d in ((previous or {}).get("states") or {}).items() if sid not in asked]


def _run_paths_on(executor, run, paths):
    """The states of each loading path go to the executor's workers one at a time, in path order
    (a state starts from the checkpoint of the one before it), the paths side by side; each
    state's rows are appended here as it ends, so an interruption loses at most the states in
    flight, not a whole path's (a worker walking a whole path would hand its rows back only at
    the path's end).
    A state not reached ends its path and the others go on; returns the failures' messages. Any
    other error stops the run (the rows of states already ended are kept)."""
    import concurrent.futures as cf
    todo = [p for p in paths if any(run.needs(sid) for sid, _, _ in p)]
    if todo:  # none: the run has said "no state to run"
        run.log("%d loading path%s with work left, on %s"
                % (len(todo), "" if len(todo) == 1 else "s", type(executor).__name__))
    running = {}

    def submit(path, k):
        running[executor.submit(_state_worker, run.job(path, k))] = (path, k)
    for path in todo:
        submit(path, 0)
    failed = []
    try:
        while running:
            ended, _ = cf.wait(running, return_when=cf.FIRST_COMPLETED)
            for fut in ended:
                path, k = running.pop(fut)
                rows, failure = fut.result()
                for row, columns in rows:
                    run.append(row, columns)
                if rows:
                    run.log("state %s: %d row%s appended" % (path[k][0], len(rows), "" if len(rows) == 1 else "s"))
                if failure:
                    failed.append(run.path_failed(path, failure))
                elif k + 1 < len(path):
                    submit(path, k + 1)
        return failed
    finally:
        for f in running:
            f.cancel()


def _state_worker(job):
    """One state of a loading path in a worker process: reached if its checkpoint is missing and
    it or a later state of the path has work, then probed; its rows and a failure (the message
    of a state not reached, else None) are returned."""
    resources.use_threads(job["fp"]["threads"])  # the study's thread count: the same bits as serial
    rows = []
    run = _Run(job["specimen_path"], job["spec_meta"], job["out"], job["fp"], job["axes"], None,
               results_csv.Table(None, job["columns"], [], None), say, job["every"],
               job["loading"], job["probe_kw"], job["state_kw"], sink=lambda row, columns: rows.append((row, columns)),
               keep=job["keep"], asked=job["asked"])
    run.done = set(job["done"])
    run.started = dict(job["started"])
    try:
        run.step(job["path"], job["k"])
    except triaxial.StateNotReached as exc:  # this path ends; the manager goes on with the others
        return rows, str(exc)
    return rows, None


class _Run:
    """One run's walk over the loading paths (the caller holds the lock)."""

    def __init__(self, specimen_path, spec_meta, out, fp, axes, csv_path, table, log, every, path, probe_kw, state_kw,
                 sink=None, keep=(), asked=None, host="trueaniso"):
        self.specimen_path, self.spec_meta, self.out, self.fp, self.loading = specimen_path, spec_meta, out, fp, path
        self.stepper = host_named(host)
        self.axes, self.csv_path, self.log, self.every = axes, csv_path, log, every
        self.columns = list(table.columns)
        self.done = {(r["state"], r["probe"]) for r in table.rows}
        # Where each state with rows was reached from: a checkpoint reached again starts there too.
        self.started = {r["state"]: r["state_from"] for r in table.rows if r.get("state_from")}
        self.probe_kw, self.state_kw = probe_kw, state_kw
        self.sink = sink or self.append
        self.keep = {str(k) for k in keep}
        # The states this run probes (None: every state on its paths); the others are where it starts.
        self.asked = None if asked is None else {str(k) for k in asked}
        self.meter = self.metadata = None  # the run's cost (run_cost.Meter) and its metadata.json, once it has work

    def job(self, path, k):
        """What a worker needs to do state k of `path` as this run would (picklable)."""
        return dict(specimen_path=self.specimen_path, spec_meta=self.spec_meta, out=self.out, fp=self.fp,
                    axes=self.axes, columns=self.columns, every=self.every, loading=self.loading, probe_kw=self.probe_kw,
                    state_kw=self.state_kw, done=sorted(self.done), path=path, k=k, keep=sorted(self.keep),
                    asked=None if self.asked is None else sorted(self.asked), started=self.started)

    def append(self, row, columns):
        """A row into probes.csv (this process holds the lock)."""
        if not self.columns:
            self.columns = list(columns)
        if set(row) != set(self.columns):
            raise study_dir.StudyMismatch("%s has other columns than this trueaniso writes; %s"
                                          % (self.csv_path, study_dir.WAY_OUT
                                             % os.path.join(self.out, study_dir.SUPERSEDED)))
        results_csv.append(self.csv_path, row, self.columns)
        self.done.add((str(row["state"]), row["probe"]))
        if self.meter is not None:
            self.meter.sample()  # the machine's load while the study ran, at each row

    def checkpoint(self, sid):
        return study_dir.checkpoint_path(self.out, sid)

    def wanted(self, sid):
        if self.asked is not None and str(sid) not in self.asked:  # an earlier run's state: a start only
            return []
        return [a for a in self.axes if (str(sid), a) not in self.done]

    def path_failed(self, path, exc):
        """The message of a path that stopped at a state not reached, logged as it happens."""
        left = [str(s[0]) for s in path if self.wanted(s[0])]
        msg = "%s (states left without probes on this path: %s)" % (exc, ", ".join(left) or "none")
        self.log("error: %s; the other paths go on" % msg)
        return msg

    def needs(self, sid):
        """The state has work left: probes to run, or a checkpoint to keep that is missing."""
        return bool(self.wanted(sid)) or (str(sid) in self.keep and not os.path.exists(self.checkpoint(sid)))

    def path(self, path):
        """States in loading order; a checkpoint is made when its state has probes to run or a
        later state of the path starts from it (so the path is always the requested one)."""
        for k in range(len(path)):
            self.step(path, k)

    def step(self, path, k):
        """State k of the path: reached from the state before it (or the specimen) when its
        checkpoint is missing and it or a later state of the path has work; probed if it has."""
        self._path_states = path
        sid, b, sz = path[k]
        ck = self.checkpoint(sid)
        if not os.path.exists(ck) and any(self.needs(s) for s, _, _ in path[k:]):
            self.reach(sid, b, sz, self.start_of(path, k), ck)
        elif self.wanted(sid):  # an earlier run reached it and was stopped before its rows
            self.log("state %s: reached by an earlier run; probed from its checkpoint %s" % (sid, ck))
        if self.wanted(sid):
            self.probe_state(sid, b, sz, ck)

    def start_of(self, path, k):
        """Where state k of the path is reached from: the state before it on the path (None: the
        specimen), or, for a state whose rows are written, the start they record, so that its
        checkpoint reached again has the bytes its rows came from (the study may have grown out of
        path order since: --ids 1,5 then 3 reached 3 from the specimen, not from a later 2)."""
        recorded = self.started.get(str(path[k][0]))
        if recorded == "specimen":
            return None
        if recorded is not None and any(str(s) == recorded for s, _, _ in path[:k]):
            return recorded
        return path[k - 1][0] if k else None

    def load(self, path, sid=None, b=None, sz=None):
        """A scene from a file of this study: the specimen (checked against the fingerprint) or a
        checkpoint (checked against its state's definition)."""
        try:
            scene, meta = specimen_file.load(path)
        except specimen_file.SpecimenFileError as exc:
            # The specimen was read whole before the study began (_study), so it changed since: it
            # is the user's file, not the study's to compute again (that advice is a checkpoint's).
            raise study_dir.StudyMismatch("%s; the specimen changed since this study began: restore it, or start a "
                                          "new study with --force-new" % exc if sid is None
                                          else study_dir.checkpoint_problem(exc, sid)) from None
        if sid is not None:
            found = validate.problem(meta, "checkpoint")
            if found:
                raise study_dir.StudyMismatch("%s: %s: %s (not a checkpoint of a state); remove it and rerun"
                                              % (path, *found))
        p = meta["parameters"]
        if sid is None:
            ok = meta["sha256"] == self.fp["specimen"]
            what = "the specimen changed since this run started (checksum differs)"
        else:
            ok = (str(p.get("state")) == str(sid) and p.get("b") == b and p.get("sigma_z") == sz
                  and p.get("specimen") == self.fp["specimen"] and p.get("path", "true-triaxial") == self.loading)
            what = "it is not state %s (b = %g, sigma_z = %g Pa) of this study's specimen" % (sid, b, sz)
            # A checkpoint that records no study key (an older layout) passes on the checks above.
            if ok and p.get("study", study_dir.states_key(self.fp)) != study_dir.states_key(self.fp):
                ok, what = False, ("it was made by another study (another friction, path rate, thread count or "
                                   "code: the study's fingerprint differs)")
        if not ok:
            raise study_dir.StudyMismatch("%s: %s; remove it and rerun" % (path, what))
        return scene, meta

    def reach(self, sid, b, sz, start, ck):
        if start is None:
            scene, _ = self.load(self.specimen_path)
        else:
            prev = next(s for s in self._path_states if str(s[0]) == str(start))
            scene, _ = self.load(self.checkpoint(start), *prev)
        self.log("state %s: b = %.2f, sigma_z = %.1f kPa, from %s ..."
                 % (sid, b, sz / 1e3, "the specimen" if start is None else "state %s" % start))
        progress = Progress("state %s" % sid, self.log, self.every)
        scene, info = self.stepper.reach_state(scene, b, sz, p=triaxial.path_mean_stress(self.loading, b, sz),
                                               progress=progress.servo if self.stepper is _Stepper else progress,
                                               chunk=chunk_for(scene.num_bodies), **self.state_kw)
        specimen_file.save(ck, scene, seed=self.spec_meta["seed"], summary=specimen.state(scene),
                           parameters=dict(state=str(sid), b=b, sigma_z=sz, path=self.loading, steps=info["steps"],
                                           wall_time=info["wall_time"],
                                           start="specimen" if start is None else str(start),
                                           specimen=self.fp["specimen"], code=self.fp["code"],
                                           study=study_dir.states_key(self.fp)))
        self.log("state %s: reached in %d steps (%.1f s); principal stresses %.2f, %.2f, %.2f kPa, largest "
                 "off-diagonal %.3f kPa" % (sid, info["steps"], info["wall_time"], info["sigma_1"] / 1e3,
                                            info["sigma_2"] / 1e3, info["sigma_3"] / 1e3, info["tau_max"] / 1e3))

    def probe_state(self, sid, b, sz, ck):
        t0 = time.time()
        hold = triaxial.path_stresses(self.loading, b, sz)
        scene, meta = self.load(ck, sid, b, sz)
        p = meta["parameters"]
        st = specimen.state(scene)
        extra = self.stepper.fabric_row(scene)
        for name in self.wanted(sid):
            scene, _ = self.load(ck, sid, b, sz)  # every probe from the checkpoint's bytes
            progress = Progress("state %s probe %s" % (sid, name), self.log, self.every)
            r = self.stepper.probe(scene, hold, name,
                                   progress=progress.probe if self.stepper is _Stepper else progress,
                                   chunk=chunk_for(scene.num_bodies, 1_000_000, largest=500), **self.probe_kw)
            nus = sorted(k for k in r if k.startswith("nu_"))
            ds, de = r["d_stress"], r["d_strain"]
            row = dict(path=self.loading, state=sid, b=b, sigma_z_goal=sz,
                       **{k: st[k] for k in ("sigma_x", "sigma_y", "sigma_z", "sigma_yz", "sigma_xz", "sigma_xy",
                                             "sigma_1", "sigma_2", "sigma_3", "tau_max")},
                       q=engines.deviatoric_q(b, sz, triaxial.path_mean_stress(self.loading, b, sz)), probe=name,
                       sign=r["sign"], d_sigma_x=ds[0], d_sigma_y=ds[1], d_sigma_z=ds[2], d_sigma_yz=ds[3],
                       d_sigma_xz=ds[4], d_sigma_xy=ds[5], d_eps_x=de[0], d_eps_y=de[1], d_eps_z=de[2],
                       d_gamma_yz=de[3], d_gamma_xz=de[4], d_gamma_xy=de[5],
                       E=r.get("E", ""), nu_1=r[nus[0]] if nus else "", nu_2=r[nus[1]] if nus else "",
                       nu_1_name=nus[0] if nus else "", nu_2_name=nus[1] if nus else "", G=r.get("G", ""),
                       gamma=r["gamma"], Zm=st["Zm"], void_ratio=st["void_ratio"], rotations=r["rotations"],
                       detection=r["detection"], damping=r["damping"], probe_steps=r["steps"],
                       probe_wall_time=r["wall_time"], state_steps=p["steps"], state_wall_time=p["wall_time"],
                       state_from=p["start"])
            row.update(extra)
            # The fabric's own Zm is the row's Zm (the same value): one column, not two (pandas read the
            # second as 'Zm.1').
            columns = self.columns or COLUMNS + [k for k in extra if k not in COLUMNS]
            if "specimen" in columns:  # the table's header decides (module comment at COLUMNS)
                row["specimen"] = self.fp["specimen"]
            self.sink(row, columns)
            self.done.add((str(sid), name))
            if nus:
                self.log("state %s: probe %s  E = %.1f MPa  %s = %.4f  %s = %.4f  (%d steps, %.1f s)"
                         % (sid, name, r["E"] / 1e6, nus[0], r[nus[0]], nus[1], r[nus[1]], r["steps"], r["wall_time"]))
            else:
                self.log("state %s: probe %s  G = %.1f MPa  (%d steps, %.1f s)"
                         % (sid, name, r["G"] / 1e6, r["steps"], r["wall_time"]))
        self.log("state %s: probes done (%.1f s)" % (sid, time.time() - t0))


def state_id(b, sigma_z):
    """The id of a state given by its definition.

    Its Table C1 number when it is one of the table's states, else 'b<b>_sz<sigma_z in Pa>' (exact:
    the shortest text that reads back as the same float). Ids are functions of the state, never
    positions in a list, so the same id means the same state in every run.

    Example:
        >>> from trueaniso import study
        >>> study.state_id(0.5, 140e3), study.state_id(0.3, 120e3)
        (21, 'b0.3_sz120000')
    """
    for i, tb, tsz in triaxial.table_c1_states():
        if tb == b and tsz == sigma_z:
            return i

    def text(x):
        t = repr(float(x))
        return t[:-2] if t.endswith(".0") else t
    return "b%s_sz%s" % (text(b), text(sigma_z))


def parse_states(text):
    """States given by their definition, 'b:sigma_z,b:sigma_z' (sigma_z in Pa) -> [(id, b, sigma_z)].

    Ids come from `state_id`. An empty item ('0.5:140e3,') is refused, as `parse_ids` refuses one: a
    state left out, perhaps the one meant.

    Raises:
        ValueError: with the reason.

    Example:
        >>> from trueaniso import study
        >>> study.parse_states("0.5:140e3,0.3:120e3")
        [(21, 0.5, 140000.0), ('b0.3_sz120000', 0.3, 120000.0)]
    """
    items = text.split(",")
    if any(t.strip() for t in items) and not all(t.strip() for t in items):
        raise ValueError("%r has an empty item: give b:sigma_z pairs separated by commas, e.g. 0.5:140e3,0:60e3" % text)
    out = []
    for item in (t for t in items if t.strip()):
        try:
            b, sz = (float(v) for v in item.split(":"))
        except ValueError:
            raise ValueError("state %r: expected b:sigma_z, e.g. 0.5:140e3" % item) from None
        out.append((state_id(b, sz), b, sz))
    if not out:
        raise ValueError("no states given")
    ids = [str(i) for i, _, _ in out]
    twice = sorted({i for i in ids if ids.count(i) > 1})
    if twice:
        raise ValueError("state %s is given twice" % ", ".join(twice))
    return out


def parse_ids(text):
    """Table C1 numbers from the text of --ids, '1,5,21' -> [1, 5, 21].

    An empty list or item, a non-number or a state given twice is refused: never "all states", never
    a silent de-duplication.

    Raises:
        ValueError: with the reason; the caller names the option.

    Example:
        >>> from trueaniso import study
        >>> study.parse_ids("1,5,21")
        [1, 5, 21]
    """
    items = [t.strip() for t in text.split(",")]
    if not any(items):
        raise ValueError("no state named (give Table C1 numbers 1-39, e.g. 1,5,21)")
    if not all(items):  # "1," or "1,,5": a number left out, perhaps the one meant
        raise ValueError("%r has an empty item: give Table C1 numbers 1-39 separated by commas, e.g. 1,5,21" % text)
    # Plain ASCII digits only: int() also reads "1_0" as 10 and a full-width digit as a digit.
    if not all(t.isascii() and t.isdigit() for t in items):
        raise ValueError("%r: Table C1 states are numbers 1-39, e.g. 1,5,21" % text)
    ids = [int(t) for t in items]
    twice = sorted({i for i in ids if ids.count(i) > 1})
    if twice:
        raise ValueError("state %s is given twice" % ", ".join(map(str, twice)))
    return ids


def table_states(ids=None):
    """States of the paper's Table C1 as `run_states` takes them.

    Args:
        ids: Table C1 numbers (1-39); None: all 39.

    Returns:
        list: (id, b, sigma_z in Pa) per state, by id.

    Raises:
        ValueError: an empty list or an id not in the table.

    Example:
        >>> from trueaniso import study
        >>> study.table_states([1, 21])
        [(1, 0.0, 100000.0), (21, 0.5, 140000.0)]
    """
    states = triaxial.table_c1_states()
    if ids is not None:
        want = set(ids)
        if not want:
            raise ValueError("no states given")
        unknown = want - {i for i, _, _ in states}
        if unknown:
            raise ValueError("Table C1 has states 1-39; unknown: %s" % sorted(unknown))
        states = [s for s in states if s[0] in want]
    return states
