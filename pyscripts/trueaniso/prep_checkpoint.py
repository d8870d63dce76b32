"""Checkpoints of a preparation in progress, so that an interrupted one resumes where it stopped.

A preparation runs in stages (spheres: expansion, consolidation; clumps: a gas stage and a first
stage before them). Every ``every`` steps it writes the scene and its place in the stages to one
file, then goes on *from that file, reloaded*, exactly as a run resumed after an interruption
does. Both continue from the same bits, so a resumed preparation ends in the specimen that an
uninterrupted one writes (tests/py/test_prep_checkpoint.py). Reloading is what makes this exact: a
scene in memory carries more than its file (contacts inside the detection skin, the controllers'
memory, each contact's radius as grown step by step), and all of it is rebuilt from the file in
both runs.

The file is bound to the recipe: the options that make the specimen, the engine threads (the
packing depends on them) and the code version. A run with other options or code refuses to go on
from it, naming what differs and the way out. ``every`` = 0 writes no checkpoints: then the
specimen is bit for bit what the code before checkpoints made (how the committed specimens were
prepared; docs/specimens.md).
"""
import json
import os

from . import buildarch, engines, provenance, run_cost, specimen_file, study_dir, validate
from .refusal import Refusal

EVERY = 50_000  # steps: 3 min of a 4000-sphere preparation, 11 min of clump1-4000, 30 min at 53,004
# Steps a stage runs between its checks (of its goal, then of a checkpoint due): the expansion and
# consolidation of every assembly, and a clump preparation's gas stage and stage 1.
CHUNK = 2000
FIRST_STAGES_CHUNK = 500


def interval_said(every):
    return ("checkpoints every %d step%s" % (every, "" if every == 1 else "s")) if every else "no checkpoints"


def rounding_said(every, clumps):
    """What an interval that is no multiple of the chunks becomes, in words; None when it is one
    (or 0). A checkpoint is due only where a chunk ends (Stages.run), so 100 writes one every 500
    or 2000 steps, which is said."""
    if every == 0 or every % CHUNK == 0:
        return None
    def after(chunk):
        return -(-every // chunk) * chunk
    # "At least": the chunk that ends a stage is not counted, so across a stage's end the gap is
    # longer (6000 between the stages of a 3000 run).
    smallest = FIRST_STAGES_CHUNK if clumps else CHUNK
    where = ("after every chunk of steps" if every <= smallest else
             "where a chunk of steps ends, at least %d steps apart" % every)
    said = ("%s are written %s: every %d steps within the expansion or the consolidation (chunks of %d)"
            % (interval_said(every), where, after(CHUNK), CHUNK))
    if clumps:
        said += ", every %d within the first stages (chunks of %d)" % (after(FIRST_STAGES_CHUNK), FIRST_STAGES_CHUNK)
    return said


class CheckpointMismatch(Refusal):
    """The checkpoint was written by a preparation with other options or code."""


def path_for(out):
    """The checkpoint of the preparation of specimen file `out`: hidden beside it, like its lock."""
    directory, name = os.path.split(os.path.abspath(out))
    return os.path.join(directory, ".%s.checkpoint" % name)


def for_specimen(out, settings, every=EVERY, log=None, way_out="--force"):
    """The checkpoints of the preparation of specimen file `out` with `settings` (a dict of every
    option that makes the specimen: assembly, count, seed, recipe), bound also to the engine
    threads (set them first) and the code version, whose x86-64 level is named (build) so that a
    refusal can say which build continues it."""
    recipe = dict(settings, threads=engines.threads(), code=provenance.code_version(), build=engines.build_arch(),
                  every=every)
    return Checkpoints(path_for(out), recipe, every, log, way_out)


def saved_threads(path):
    """The engine threads of the checkpoint `path`, or None when there is none: an interrupted
    preparation continues at its own count (its bits depend on it)."""
    ck = Checkpoints(path, {})
    saved = ck.saved_recipe()
    return None if saved is None else saved.get("threads")


_read = {}  # the recipe of the last checkpoint file read, by (path, mtime, size, inode)


def _normal(obj):
    return json.loads(json.dumps(obj, sort_keys=True))


class Checkpoints:
    """Where a preparation writes its place (``path``), what it is bound to (``recipe``, a
    JSON-able dict) and how often (``every`` steps; 0: never)."""

    def __init__(self, path, recipe, every=EVERY, log=None, way_out="--force"):
        if not (isinstance(every, int) and every >= 0):
            raise ValueError("checkpoint interval must be an integer >= 0 (steps), not %r" % (every,))
        self.path, self.recipe, self.every = path, _normal(recipe), every
        self.log = log or (lambda m: None)
        self.way_out = way_out  # the option that starts afresh, named in refusals
        self.since = 0  # steps since the last checkpoint (or the start of this run)
        self.resumed = False  # set by resume()

    def saved_recipe(self):
        """The recipe of the checkpoint on disk, or None when there is none (read without the
        scene: to adopt its thread count before the engines start)."""
        try:
            st = os.stat(self.path)
        except FileNotFoundError:
            return None
        if os.path.isdir(self.path):  # "or use --force" was no way out: --force cannot remove it
            refusal = CheckpointMismatch("%s should be a preparation checkpoint but is a directory; move it away"
                                         % self.path)
            refusal.reason = "a directory"
            raise refusal
        # Read once per version of the file: a run asks for it up to four times before it resumes
        # (threads, interval, comparison), each a full read and check (20 MB at 53,004 spheres).
        key = (self.path, st.st_mtime_ns, st.st_size, st.st_ino)
        try:
            if key not in _read:
                _, meta = specimen_file.read(self.path)
                # Checked whole here, where every reader of the file starts (resume() reads the place
                # of the version checked): a field missing or of the wrong kind is named, not met
                # later as a KeyError or TypeError (schemas/prep_checkpoint.schema.json).
                found = validate.problem(meta, "prep_checkpoint")
                if found:
                    raise specimen_file.SpecimenFileError("%s: %s" % found)
                _read.clear()
                _read[key] = meta["parameters"]["checkpoint"]["recipe"]
            return dict(_read[key])
        except (specimen_file.SpecimenFileError, KeyError, TypeError) as exc:
            refusal = CheckpointMismatch("the preparation checkpoint %s is unusable (%s); remove it, or use %s "
                                         "to prepare from the start" % (self.path, exc, self.way_out))
            refusal.reason = str(exc)
            raise refusal from None

    def differences(self):
        """What differs between the checkpoint on disk and this run ("seed: 7 there, 8 here"), []
        when it is this run's, None when there is none. The interval is named by its option
        (not the file's field, "every: 3000 there")."""
        saved = self.saved_recipe()
        if saved is None:
            return None
        diff = study_dir.differences(saved, self.recipe)
        return study_dir.said([("checkpoint-every" if k == "every" else k, x, y) for k, x, y in diff])

    def of_settings(self, settings):
        """The checkpoint's recipe when it was written by a preparation of these `settings` (the
        options that make the specimen), whatever its threads, interval and code; else None (none
        on disk, or another preparation's, which this run refuses or, with --force, removes). Only
        then may a run take the threads and interval it was written with: --force --seed 2 must not
        take them from a seed-1 checkpoint it then removes."""
        saved = self.saved_recipe()
        if saved is None:
            return None
        mine = _normal(settings)
        return None if study_dir.differences({k: saved.get(k) for k in mine}, mine) else saved

    def unusable(self):
        """Why the checkpoint on disk cannot be read ("File is not a zip file"), or None."""
        try:
            self.saved_recipe()
        except CheckpointMismatch as exc:
            return exc.reason
        return None

    def refuse_other(self):
        """Refuses a checkpoint on disk of another recipe (CheckpointMismatch); differences() else."""
        diff = self.differences()
        if diff:
            built = self.saved_recipe().get("build")
            rebuild = ""
            if built is not None and built != self.recipe.get("build"):  # named: two hashes alone say nothing
                rebuild = (" (it was made by engines built for %s, this run's are for %s; to run at %s: %s)"
                           % (built, self.recipe.get("build"), built,
                              buildarch.how_to_run_at(built, os.path.dirname(engines.__file__))))
            raise CheckpointMismatch(
                "the preparation checkpoint %s was made with other settings (%s); this run cannot go on "
                "from it. Use the same options (and code%s) to resume, or %s to prepare from the start"
                % (self.path, "; ".join(diff), rebuild, self.way_out))
        return diff

    def resume(self):
        """(scene, place) of the checkpoint on disk, or None. Refuses one of another recipe."""
        if self.refuse_other() is None:
            return None
        scene, meta = specimen_file.load(self.path)
        place = meta["parameters"]["checkpoint"]["place"]
        self.resumed = True  # the script's last line then says the time of every run, not only its own
        self.log("resuming the preparation from %s (%s, %d steps done)"
                 % (self.path, place["stage"], sum(place["steps"].values())))
        return scene, place

    def due(self, steps):
        """Counts `steps` just run; True when a checkpoint is due."""
        self.since += steps
        return self.every > 0 and self.since >= self.every

    def write(self, scene, place):
        """Writes the checkpoint atomically and returns the scene reloaded from it (module doc)."""
        specimen_file.save(self.path, scene, parameters=dict(checkpoint=dict(recipe=self.recipe, place=place)))
        self.since = 0
        reloaded, meta = specimen_file.load(self.path)
        self.log("checkpoint: %s, step %d of it, %d in all (%s)" % (place["stage"], place["steps"][place["stage"]],
                                                                  sum(place["steps"].values()), self.path))
        return reloaded

    def remove(self):
        if os.path.isdir(self.path):
            raise CheckpointMismatch("%s should be a preparation checkpoint but is a directory; move it away"
                                     % self.path)
        if os.path.exists(self.path):
            os.unlink(self.path)


class Stages:
    """The place of a preparation in its stages, and the loop every stage runs.

    ``place`` is what a checkpoint holds besides the scene: the current stage, the steps each
    stage has run, and whatever the recipe carries from stage to stage (the radius scale grown
    so far, the time step cap, the elapsed time). ``build(stages)`` makes the current stage's
    chain and controller for ``stages.scene``: after a checkpoint's reload, and whenever a stage
    asks for new engines.
    """

    def __init__(self, scene, place, checkpoints=None, build=None, fold=None):
        self.scene, self.place, self.checkpoints = scene, place, checkpoints
        self.build, self.fold = build, fold
        self.chain = self.controller = None
        # Wall and CPU time, peak memory and load over every run of the preparation (run_cost), carried
        # in the place: the wall time as "elapsed" (the placement's included), the rest as "cost". A
        # run without a carried cost (a new preparation, or a checkpoint made before it) counts its
        # CPU from its process's start.
        cost = place.get("cost")
        self.meter = run_cost.Meter(dict(cost or {}, wall_time=place.get("elapsed", 0.0)),
                                    cpu_from_process_start=cost is None)

    def at(self, stage):
        return self.place["stage"] == stage

    def steps(self, stage):
        return self.place["steps"].get(stage, 0)

    def elapsed(self):
        """Wall seconds of the preparation so far, every run up to its last checkpoint and this one."""
        return self.meter.spent()["wall_time"]

    def cost(self):
        """The rest of its cost so far: the specimen's log keys cpu_time, peak_memory_mb, load_min,
        load_max and runs (the wall time is elapsed())."""
        c = self.meter.totals()
        del c["wall_time"]
        return c

    def run(self, stage, chunk, finished, max_steps, progress=None, label=None, check_first=False):
        """Runs the current stage `stage` in chunks until finished(), checked after each chunk and,
        if check_first (a stage that may have nothing left to do), before the first; False when
        max_steps of the stage ran out first."""
        if not self.at(stage):
            return True
        steps = self.place["steps"]
        steps.setdefault(stage, 0)
        fresh = self.chain is None  # new engines (a start, a resume): finished() has nothing measured yet
        if fresh:
            self.build(self)
        while True:
            # A condition checked first reads the controller's last measurement; a checkpoint is
            # written only when the stage is not finished, so after its reload the stage goes on
            # without asking (the new controller has measured nothing: it would say p = 0).
            if check_first and not fresh and finished():
                return True
            if steps[stage] >= max_steps:
                return False
            n = self.chain.run(min(chunk, max_steps - steps[stage]))
            fresh = False
            steps[stage] += n
            self.meter.sample()
            if progress:
                progress(label or stage, self.scene, self.controller, steps[stage])
            if finished():
                return True
            if self.checkpoints is not None and self.checkpoints.due(n):
                self.checkpoint()
                fresh = True

    def checkpoint(self):
        """Writes the place and goes on from the reloaded scene with new engines (module doc)."""
        if self.fold:
            self.fold(self)  # e.g. the radius scale the controller grew, before it is replaced
        self.place["elapsed"] = self.elapsed()
        self.place["cost"] = self.cost()
        self.scene = self.checkpoints.write(self.scene, self.place)
        self.chain = self.controller = None
        self.build(self)

    def advance(self, stage, new_engines=True):
        """On to `stage`; with new engines (built when it starts) or the current ones."""
        self.place["stage"] = stage
        if new_engines:
            self.chain = self.controller = None
