"""An interrupted preparation resumes from its last checkpoint to the specimen an uninterrupted one
makes, bit for bit (prep_checkpoint's module doc says why it reloads in both runs); a checkpoint of
other settings is refused; the script cleans up, adopts the checkpoint's thread count, and gets
through kill -9."""
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from conftest import SCRIPTS, one_line_error, run_script
from trueaniso import clump_specimen, engines, prep_checkpoint, specimen, specimen_file


@pytest.fixture(autouse=True)
def one_thread():
    threads = engines.threads()
    engines.set_threads(1)  # the packing depends on the count; the recipe records it
    yield
    engines.set_threads(threads)


class Interrupt(Exception):
    pass


def _stop_after_checkpoints(path, count):
    """A progress hook that stops the run (as a kill would) once `count` checkpoints were written."""
    seen = {"n": 0, "mtime": None}

    def hook(label, scene, engine, steps):
        if os.path.exists(path):
            m = os.stat(path).st_mtime_ns
            if m != seen["mtime"]:
                seen["mtime"], seen["n"] = m, seen["n"] + 1
                if seen["n"] >= count:
                    raise Interrupt()
    return hook


def _same_bits(a, b):
    x, y = specimen_file.scene_arrays(a), specimen_file.scene_arrays(b)
    differ = [k for k in x if not np.array_equal(np.asarray(x[k]), np.asarray(y[k]))]
    assert not differ, "arrays differ: %s" % differ


def _resumed_equals_uninterrupted(tmp_path, prepare, every, stop_after):
    whole = prep_checkpoint.Checkpoints(str(tmp_path / "whole.ck"), dict(case=1), every)
    written = []
    whole.log = written.append
    ref, ref_log = prepare(whole, None)
    assert sum("checkpoint:" in m for m in written) >= stop_after + 1  # else nothing is resumed below

    path = str(tmp_path / "cut.ck")
    with pytest.raises(Interrupt):
        prepare(prep_checkpoint.Checkpoints(path, dict(case=1), every), _stop_after_checkpoints(path, stop_after))
    again = prep_checkpoint.Checkpoints(path, dict(case=1), every)
    said = []
    again.log = said.append
    got, got_log = prepare(again, None)
    assert said and said[0].startswith("resuming the preparation from")
    _same_bits(ref, got)
    for k in ("steps_expansion", "steps_consolidation"):
        assert got_log[k] == ref_log[k]
    return ref, got_log


def test_spheres_resume_to_the_same_bits(tmp_path):
    # 100 spheres take ~110,000 steps: checkpoints every 20,000 land in the expansion; the cut
    # after the second leaves work in both stages.
    def prepare(ck, hook):
        return specimen.prepare_spheres(100, seed=7, checkpoints=ck, progress=hook)
    ref, log = _resumed_equals_uninterrupted(tmp_path, prepare, 20_000, 2)
    # Without checkpoints the specimen is another one (reloads change the last bits), which is
    # why the interval is part of the recipe; and a checkpoint never due changes nothing.
    plain, _ = specimen.prepare_spheres(100, seed=7)
    never, _ = specimen.prepare_spheres(100, seed=7, checkpoints=prep_checkpoint.Checkpoints(
        str(tmp_path / "never.ck"), {}, 10_000_000))
    _same_bits(plain, never)
    assert not np.array_equal(plain.positions, ref.positions)


def test_clumps_resume_to_the_same_bits_across_stages(tmp_path):
    # clump1's recipe has four stages (gas, stage 1 with rotations blocked, expansion, consolidation);
    # 60 dimers at inertial number 0.05 take ~20,000 steps. A checkpoint every 500 steps, one chunk
    # of the gas stage and stage 1, cuts every stage many times. After such a checkpoint the new
    # controller has measured nothing yet (p = 0): a gas stage that asked it whether it was done
    # would never end (5,000,000 steps, then stage 1 skipped and a looser specimen saved);
    # max_steps stops that here.
    def prepare(ck, hook):
        return clump_specimen.prepare_clumps("clump1", 60, seed=4, inertial_number=5e-2, shape="dimer-1.5",
                                             checkpoints=ck, progress=hook, max_steps=200_000)
    _, log = _resumed_equals_uninterrupted(tmp_path, prepare, 500, 7)
    _, plain = prepare(None, None)
    assert log["steps_consolidation"] > 0
    assert log["steps_expansion"] < 1.5 * plain["steps_expansion"]  # reloads perturb the path, not its length


def test_a_checkpoint_of_other_settings_is_refused(tmp_path, monkeypatch):
    path = str(tmp_path / "ck")
    with pytest.raises(Interrupt):
        specimen.prepare_spheres(100, seed=7, progress=_stop_after_checkpoints(path, 1),
                                 checkpoints=prep_checkpoint.Checkpoints(path, dict(seed=7, n=100), 20_000))
    other = prep_checkpoint.Checkpoints(path, dict(seed=8, n=100), 20_000)
    # One full read per version of the file, however often it is asked (not one per question: 20 MB
    # each at 53,004 spheres); a file written since is read again (below: "unusable").
    reads = []
    read = specimen_file.read
    monkeypatch.setattr(specimen_file, "read", lambda p: reads.append(p) or read(p))
    assert [other.differences(), other.differences(), prep_checkpoint.saved_threads(path)] == \
        [["seed: 7 there, 8 here"]] * 2 + [None]  # (this recipe records no thread count)
    assert len(reads) == 1
    with pytest.raises(prep_checkpoint.CheckpointMismatch, match="seed: 7 there, 8 here.*--force"):
        specimen.prepare_spheres(100, seed=8, checkpoints=other)
    with open(path, "wb") as f:
        f.write(b"not a checkpoint")
    with pytest.raises(prep_checkpoint.CheckpointMismatch, match="unusable.*remove it, or use --force"):
        specimen.prepare_spheres(100, seed=7, checkpoints=prep_checkpoint.Checkpoints(path, dict(seed=7, n=100)))


def test_a_second_preparation_of_the_same_file_is_refused_naming_the_file(tmp_path):
    """The refusal names the file, not its directory, which holds other specimens that can be
    prepared at the same time."""
    from trueaniso import lock
    out = tmp_path / "s.npz"
    with lock.held(str(tmp_path), name=".s.npz.lock"):
        proc = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--out", out)
        other = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--checkpoint-every", 0,
                           "--out", tmp_path / "t.npz")
    one_line_error(proc, "specimen output %s is in use by another run" % out, "--wait")
    assert not out.exists()
    assert other.returncode == 0, other.stderr  # another file of the same directory is not locked


def _script(out, *extra):
    return [sys.executable, os.path.join(SCRIPTS, "prepare_specimen.py"), "--n", "100", "--seed", "9",
            "--checkpoint-every", "20000", "--progress-every", "0", "--out", str(out), *extra]


def test_script_killed_then_rerun_writes_the_uninterrupted_specimen(tmp_path):
    whole = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--checkpoint-every", 20000, "--threads", 1,
                       "--out", tmp_path / "whole.npz")
    assert whole.returncode == 0, whole.stderr
    assert not os.path.exists(prep_checkpoint.path_for(str(tmp_path / "whole.npz")))  # removed once saved

    out = tmp_path / "cut.npz"
    ck = prep_checkpoint.path_for(str(out))
    proc = subprocess.Popen(_script(out, "--threads", "1"), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            env=dict(os.environ, OMP_NUM_THREADS="1"))
    deadline = time.time() + 300
    while not os.path.exists(ck) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    assert proc.poll() is None, "finished before its first checkpoint"
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert os.path.exists(ck) and not out.exists()

    # A rerun without --threads continues at the checkpoint's count, and says so.
    again = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--checkpoint-every", 20000,
                       "--out", out, env=dict(OMP_NUM_THREADS="2"))
    assert again.returncode == 0, again.stderr
    assert "its unfinished preparation ran at 1 engine thread, so this run does too" in again.stdout
    assert "resuming the preparation from" in again.stdout
    # the time said is this run's and the whole preparation's
    assert "s (this run; " in again.stdout and "s in all, with the runs before its last checkpoint)" in again.stdout
    assert not os.path.exists(ck)
    a, _ = specimen_file.load(str(tmp_path / "whole.npz"))
    b, meta = specimen_file.load(str(out))
    _same_bits(a, b)
    assert meta["parameters"]["checkpoint_every"] == 20000 and meta["parameters"]["threads"] == 1


def test_script_refuses_other_options_on_a_checkpoint_and_force_starts_over(tmp_path):
    out = tmp_path / "s.npz"
    ck = prep_checkpoint.path_for(str(out))
    with pytest.raises(Interrupt):
        specimen.prepare_spheres(100, seed=9, progress=_stop_after_checkpoints(ck, 1),
                                 checkpoints=prep_checkpoint.Checkpoints(ck, dict(seed=9), 20_000))
    proc = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--out", out)
    one_line_error(proc, "other settings", "--force")
    assert "preparing" not in proc.stdout  # refused before the estimate line, which reads as a start
    assert os.path.exists(ck) and not out.exists()  # nothing lost by the refusal
    forced = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--checkpoint-every", 0,
                        "--force", "--out", out)
    assert forced.returncode == 0, forced.stderr
    assert "removed the checkpoint of an earlier preparation" in forced.stdout
    assert out.exists() and not os.path.exists(ck)


def test_an_existing_specimen_of_other_settings_is_refused_and_a_checkpoint_beside_it_kept(tmp_path, specimen_100):
    """An existing --out made with other options is refused, not kept (seed 5 for --seed 1), and a
    checkpoint of an interrupted --force remake beside it is kept, not deleted without a word."""
    import shutil
    out = tmp_path / "s.npz"
    shutil.copy(specimen_100, out)  # 100 spheres, seed 3
    one_line_error(run_script("prepare_specimen.py", "--n", 100, "--seed", 4, "--threads", 1, "--out", out),
                   "prepared with other settings", "seed: 3 there, 4 here", "--force")
    ck = prep_checkpoint.path_for(str(out))
    with pytest.raises(Interrupt):  # an interrupted remake with seed 4 (as --force --seed 4 would leave)
        specimen.prepare_spheres(100, seed=4, progress=_stop_after_checkpoints(ck, 1),
                                 checkpoints=prep_checkpoint.Checkpoints(ck, dict(seed=4), 20_000))
    kept = run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--threads", 1, "--out", out)
    assert kept.returncode == 0 and "kept existing specimen" in kept.stdout, kept.stderr
    assert "kept the checkpoint" in kept.stdout and os.path.exists(ck)


def test_force_resumes_a_checkpoint_of_its_own_settings_and_adopts_its_interval(tmp_path, specimen_100):
    """--force redoes a finished specimen; an interrupted --force run of the same settings resumes
    (starting over would give the same bits, later). Without --checkpoint-every, the checkpoint's
    interval is taken, as its thread count is."""
    import shutil
    out = tmp_path / "s.npz"
    shutil.copy(specimen_100, out)
    ck = prep_checkpoint.path_for(str(out))
    proc = subprocess.Popen(_script(out, "--threads", "1", "--force"), stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, env=dict(os.environ, OMP_NUM_THREADS="1"))
    deadline = time.time() + 300
    while not os.path.exists(ck) and proc.poll() is None and time.time() < deadline:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert os.path.exists(ck)
    again = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--force", "--out", out)
    assert again.returncode == 0, again.stderr
    assert "resuming the preparation from" in again.stdout and not os.path.exists(ck)
    assert specimen_file.read(str(out))[1]["parameters"]["checkpoint_every"] == 20000
    # and says so, as it says the thread count it took
    assert ("--checkpoint-every not given: its unfinished preparation wrote checkpoints every 20000 steps, so this "
            "run does too") in again.stdout
    assert "where a chunk of" not in again.stdout  # 20000 is a multiple of the chunks: nothing to explain


def test_an_interval_between_chunks_is_said_as_the_one_that_runs(tmp_path):
    """A checkpoint falls where a chunk of steps ends: --checkpoint-every 3000 writes one every 4000
    steps of an expansion, and the run says so (asked for 100, a user gets 500 or 2000)."""
    proc = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--checkpoint-every", 3000,
                      "--progress-every", 0, "--out", tmp_path / "s.npz")
    assert proc.returncode == 0, proc.stderr
    assert ("checkpoints every 3000 steps are written where a chunk of steps ends, at least 3000 steps apart: every "
            "4000 steps within the expansion or the consolidation (chunks of 2000)\n") in proc.stdout
    assert "checkpoint: expansion, step 4000 of it" in proc.stdout  # what it said is what ran
    assert "step 3000 of it" not in proc.stdout
    # A clump preparation's first stages run chunks of 500 steps: 3000 there is 3000.
    said = prep_checkpoint.rounding_said(3000, clumps=True)
    assert said.endswith("every 4000 steps within the expansion or the consolidation (chunks of 2000), every 3000 "
                         "within the first stages (chunks of 500)")
    assert prep_checkpoint.rounding_said(100, clumps=True).startswith(
        "checkpoints every 100 steps are written after every chunk of steps: every 2000 steps")
    assert prep_checkpoint.rounding_said(0, clumps=True) is None and prep_checkpoint.rounding_said(4000, False) is None
    quiet = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--checkpoint-every", 3000,
                       "--quiet", "--force", "--out", tmp_path / "s.npz")
    assert quiet.returncode == 0 and "chunk" not in quiet.stdout, quiet.stderr  # --quiet is quiet


def test_the_leftover_checkpoint_of_the_kept_specimen_is_removed_quietly(tmp_path):
    """A run killed between its save and its checkpoint's removal leaves both; the rerun keeps the
    specimen and removes the checkpoint (its recipe is the specimen's own: settings, threads,
    interval, code), and says nothing of threads and interval it would have taken, as it prepares
    nothing. A rerun without the options took the checkpoint for another run's and kept it."""
    out = tmp_path / "s.npz"
    made = run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--threads", 1, "--checkpoint-every", 2000,
                      "--quiet", "--out", out)
    assert made.returncode == 0, made.stderr
    ck = prep_checkpoint.path_for(str(out))
    before = engines.threads()
    engines.set_threads(1)
    try:  # the checkpoint that run wrote: the same recipe
        with pytest.raises(Interrupt):
            specimen.prepare_spheres(100, seed=3, progress=_stop_after_checkpoints(ck, 1),
                                     checkpoints=prep_checkpoint.for_specimen(str(out), _settings_of(100, 3), 2000))
    finally:
        engines.set_threads(before)
    kept = run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--out", out, env=dict(OMP_NUM_THREADS="2"))
    assert kept.returncode == 0 and "kept existing specimen" in kept.stdout, kept.stderr
    assert "not given" not in kept.stdout and "kept the checkpoint" not in kept.stdout, kept.stdout
    assert not os.path.exists(ck)


def test_beside_a_kept_specimen_a_remake_checkpoint_and_a_broken_one_are_kept(tmp_path, specimen_100):
    """The checkpoint of an interrupted --force remake with other threads and interval is not the
    leftover of the specimen's own run: kept. A damaged one is named and the run ends well, not in
    an error whose advice, --force, would replace the good specimen."""
    import shutil
    out = tmp_path / "s.npz"
    shutil.copy(specimen_100, out)  # 100 spheres, seed 3, 1 thread, made without checkpoints
    ck = prep_checkpoint.path_for(str(out))
    with pytest.raises(Interrupt):  # the remake: the same settings, 3000 steps a checkpoint
        specimen.prepare_spheres(100, seed=3, progress=_stop_after_checkpoints(ck, 1),
                                 checkpoints=prep_checkpoint.for_specimen(str(out), _settings_of(100, 3), 3000))
    kept = run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--threads", 1, "--out", out)
    assert kept.returncode == 0 and "kept existing specimen" in kept.stdout, kept.stderr
    assert "kept the checkpoint %s" % ck in kept.stdout and "checkpoint-every: 3000 there" in kept.stdout, kept.stdout
    assert os.path.exists(ck)

    with open(ck, "wb") as f:
        f.write(b"PK\x03\x04 cut short")
    before = open(out, "rb").read()
    kept = run_script("prepare_specimen.py", "--n", 100, "--seed", 3, "--threads", 1, "--out", out)
    assert kept.returncode == 0, kept.stderr
    assert "kept existing specimen" in kept.stdout and "kept the unusable checkpoint %s" % ck in kept.stdout
    assert "--force" not in kept.stdout.split("kept the unusable")[1]  # no advice that replaces the specimen
    assert open(out, "rb").read() == before and os.path.exists(ck)


def test_the_time_estimate_is_for_the_threads_that_run(tmp_path):
    """Without --threads the engines run OMP_NUM_THREADS threads, and the estimate is for that
    count, not for all the cores (16 s would be said for 31 s under OMP_NUM_THREADS=1 on 2 cores)."""
    from trueaniso import resources
    proc = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--checkpoint-every", 0, "--out",
                      tmp_path / "s.npz", env=dict(OMP_NUM_THREADS="1"))
    assert proc.returncode == 0, proc.stderr
    _, seconds = resources.preparation_estimate(100, 1)
    assert "of memory and %s\n" % resources.human_seconds(seconds) in proc.stdout, proc.stdout


def _settings_of(n, seed):
    """prepare_specimen.py's settings for a sphere specimen of its defaults."""
    sys.path.insert(0, SCRIPTS)
    try:
        import prepare_specimen
    finally:
        sys.path.remove(SCRIPTS)
    o = prepare_specimen.options(["--n", str(n), "--seed", str(seed), "--out", "x.npz"])
    prepare_specimen.validate(o)
    return prepare_specimen.settings(o)


def test_force_takes_nothing_from_a_checkpoint_it_removes_nor_is_refused_by_a_broken_one(tmp_path):
    """--force --seed 2 takes nothing (threads, interval) from a seed-1 checkpoint it removes, so one
    command makes one specimen whatever lies beside it; a damaged checkpoint's refusal offers
    --force, and --force then goes through."""
    out = tmp_path / "s.npz"
    ck = prep_checkpoint.path_for(str(out))
    with pytest.raises(Interrupt):
        specimen.prepare_spheres(100, seed=1, progress=_stop_after_checkpoints(ck, 1),
                                 checkpoints=prep_checkpoint.for_specimen(str(out), dict(seed=1), 3000))
    forced = run_script("prepare_specimen.py", "--n", 100, "--seed", 2, "--threads", 1, "--force", "--out", out)
    assert forced.returncode == 0, forced.stderr
    assert "removed the checkpoint of an earlier preparation" in forced.stdout
    assert "--checkpoint-every not given" not in forced.stdout and "chunk" not in forced.stdout
    assert specimen_file.read(str(out))[1]["parameters"]["checkpoint_every"] == prep_checkpoint.EVERY

    broken = tmp_path / "b.npz"
    ck = prep_checkpoint.path_for(str(broken))
    with open(ck, "wb") as f:
        f.write(b"PK\x03\x04 a checkpoint cut short")
    refused = run_script("prepare_specimen.py", "--n", 100, "--seed", 2, "--threads", 1, "--out", broken)
    one_line_error(refused, "is unusable", "--force")
    assert os.path.exists(ck)  # nothing removed without --force
    forced = run_script("prepare_specimen.py", "--n", 100, "--seed", 2, "--threads", 1, "--force", "--out", broken)
    assert forced.returncode == 0, forced.stderr
    assert "removed the unusable checkpoint %s (" % ck in forced.stdout and "(--force)" in forced.stdout
    assert broken.exists() and not os.path.exists(ck)


def _running(out, every, *extra):
    """prepare_specimen.py (300 spheres, 10-50 s) started in the background, handed back once it
    printed its first progress line (the start-up guard is gone by then)."""
    cmd = [sys.executable, os.path.join(SCRIPTS, "prepare_specimen.py"), "--n", "300", "--seed", "9", "--threads", "1",
           "--checkpoint-every", str(every), "--progress-every", "0.2", "--out", str(out), *extra]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=dict(os.environ, OMP_NUM_THREADS="1"))
    while "preparation: step" not in proc.stdout.readline():
        assert proc.poll() is None, proc.stderr.read()
    return proc


def test_sigterm_promises_a_resume_only_when_a_checkpoint_was_written(tmp_path):
    """'the same command resumes the preparation from its last checkpoint' only when one was written (else the rerun
    starts over)."""
    out = tmp_path / "none.npz"
    proc = _running(out, 0)  # --checkpoint-every 0: no checkpoint, ever
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert err.splitlines()[-1] == "error: interrupted before the first checkpoint; the same command starts over", err

    out = tmp_path / "some.npz"
    ck = prep_checkpoint.path_for(str(out))
    proc = _running(out, 2000)
    deadline = time.time() + 300
    while not os.path.exists(ck) and proc.poll() is None and time.time() < deadline:
        proc.stdout.readline()
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 143, err
    assert err.splitlines()[-1] == "error: interrupted; the same command resumes the preparation from its last checkpoint", err


def test_closed_output_is_one_line_not_a_traceback(tmp_path):
    """`prepare_specimen.py ... | head -2`: the first progress line after head has gone ends the run
    with one line on stderr saying what was kept, and SIGPIPE's status (141), not a BrokenPipeError
    traceback."""
    proc = _running(tmp_path / "s.npz", 0)
    proc.stdout.close()  # the reader goes away
    err = proc.stderr.read()
    proc.wait(timeout=120)
    assert proc.returncode == 141, err
    assert err == "error: output closed (broken pipe) before the first checkpoint; the same command starts over\n", err


def test_a_checkpoint_of_another_build_level_says_which_build_continues_it(tmp_path, monkeypatch):
    """A checkpoint written by a v3 build, resumed by the baseline build: the recipe names the level,
    and the refusal says which build goes on, not two code hashes and --force (which would throw
    away up to 82 minutes of clump preparation)."""
    path = str(tmp_path / "ck")
    with pytest.raises(Interrupt):
        specimen.prepare_spheres(100, seed=7, progress=_stop_after_checkpoints(path, 1),
                                 checkpoints=prep_checkpoint.Checkpoints(path, dict(seed=7, code="src-v3", build="x86-64-v3"),
                                                                         20_000))
    here = prep_checkpoint.Checkpoints(path, dict(seed=7, code="src-base", build="x86-64"), 20_000)
    import re
    from trueaniso import buildarch
    how = buildarch.how_to_run_at("x86-64-v3", os.path.dirname(engines.__file__))  # TRUEANISO_LEVEL, or a build
    with pytest.raises(prep_checkpoint.CheckpointMismatch,
                       match=re.escape("made by engines built for x86-64-v3, this run's are for x86-64; to run at "
                                       "x86-64-v3: %s" % how)):
        specimen.prepare_spheres(100, seed=7, checkpoints=here)
    same = prep_checkpoint.Checkpoints(path, dict(seed=8, code="src-v3", build="x86-64-v3"), 20_000)
    with pytest.raises(prep_checkpoint.CheckpointMismatch) as refused:  # same level: no word of builds
        specimen.prepare_spheres(100, seed=8, checkpoints=same)
    assert "engines built for" not in str(refused.value)
    # the real recipe names this build's level
    assert prep_checkpoint.for_specimen(str(tmp_path / "s.npz"), dict(n=1)).recipe["build"] == engines.build_arch()


def test_a_kept_clump_specimen_reports_the_summary_it_was_saved_with(tmp_path):
    """Rerun on a finished clump preparation, prepare_specimen.py prints the file's own summary, as
    the first run did: one recomputed from the reloaded scene gives another unbalanced force (a
    residual: 4.59e-7 where the save said and stored 4.20e-7, 100 clump1 clumps)."""
    import json
    from conftest import run_script
    out = tmp_path / "c.npz"
    args = ("--assembly", "clump1", "--n", "100", "--seed", "3", "--threads", "1", "--quiet", "--out", out)
    first = run_script("prepare_specimen.py", *args, timeout=600)
    assert first.returncode == 0, first.stderr
    again = run_script("prepare_specimen.py", *args, timeout=120)
    assert again.returncode == 0 and "kept existing specimen" in again.stdout, again.stderr
    said = [json.loads(p.stdout.strip().splitlines()[-1]) for p in (first, again)]
    assert said[0] == said[1]
    assert said[0]["unbalanced"] == float("%.3g" % json.load(open(tmp_path / "c.json"))["summary"]["unbalanced"])


def _written_checkpoint(tmp_path, prepare, settings):
    """The preparation checkpoint that `prepare(checkpoints, hook)` writes first, as for_specimen
    binds it (threads, code, build, interval), the run stopped right after it."""
    out = str(tmp_path / "s.npz")
    ck = prep_checkpoint.path_for(out)
    with pytest.raises(Interrupt):
        prepare(prep_checkpoint.for_specimen(out, settings, prep_checkpoint.CHUNK), _stop_after_checkpoints(ck, 1))
    return ck


@pytest.mark.parametrize("assembly", ["sphere", "clump1"])
def test_a_written_checkpoint_fits_its_schema_which_names_every_field(tmp_path, assembly):
    """What the code writes validates, and every field of the place and every key for_specimen adds
    to the recipe is a property of schemas/prep_checkpoint.schema.json (a field written but not
    described would be neither checked nor on the format's reference page)."""
    from trueaniso import validate
    if assembly == "sphere":
        ck = _written_checkpoint(tmp_path, lambda c, h: specimen.prepare_spheres(100, seed=7, checkpoints=c, progress=h),
                                 dict(assembly="sphere", n=100, seed=7))
    else:
        ck = _written_checkpoint(tmp_path, lambda c, h: clump_specimen.prepare_clumps(
            "clump1", 60, seed=4, inertial_number=5e-2, shape="dimer-1.5", checkpoints=c, progress=h,
            max_steps=200_000), dict(assembly="clump1", n=60, seed=4))
    meta = specimen_file.read(ck)[1]
    assert validate.problem(meta, "prep_checkpoint") is None
    written = meta["parameters"]["checkpoint"]
    described = validate.schema("prep_checkpoint")["allOf"][1]["properties"]["parameters"]["properties"]["checkpoint"]
    assert set(written) == set(described["properties"])
    assert set(written["place"]) <= set(described["properties"]["place"]["properties"])
    assert {"threads", "code", "build", "every"} <= set(written["recipe"])
    assert {"threads", "code", "build", "every"} == set(described["properties"]["recipe"]["properties"])
    if assembly == "clump1":
        assert "generation_time" in written["place"]
    # The study's state checkpoint schema does not take it (it names no state), nor this one a plain specimen.
    assert validate.problem(meta, "checkpoint")[1] == "missing"


def _drop(*keys):
    def edit(meta):
        d = meta["parameters"]
        for k in keys[:-1]:
            d = d[k]
        del d[keys[-1]]
    return edit


def _set(value, *keys):
    def edit(meta):
        d = meta["parameters"]
        for k in keys[:-1]:
            d = d[k]
        d[keys[-1]] = value
    return edit


@pytest.mark.parametrize("edit,words", [
    (_drop("checkpoint", "place", "stage"), "parameters.checkpoint.place.stage: missing"),
    (_set("stage 2", "checkpoint", "place", "stage"), "parameters.checkpoint.place.stage: must be one of"),
    (_set("many", "checkpoint", "place", "steps", "expansion"),
     "parameters.checkpoint.place.steps.expansion: must be an integer >= 0, not \"many\""),
    (_set(-1.0, "checkpoint", "place", "grown_scale"), "parameters.checkpoint.place.grown_scale: must be a finite "
                                                       "number > 0"),
    (_set(0, "checkpoint", "recipe", "threads"), "parameters.checkpoint.recipe.threads: must be an integer >= 1"),
    (_set([1, 2], "checkpoint", "recipe"), "parameters.checkpoint.recipe: must be a table"),
    (_drop("checkpoint"), "parameters.checkpoint: missing"),  # a specimen (sealed, valid) where the checkpoint lies
])
def test_a_malformed_checkpoint_is_refused_naming_the_field(tmp_path, edit, words):
    """A checkpoint whose metadata parse but do not fit the schema (resealed, so the checksum
    passes) is refused before any step, naming the field, by the library and by the script, not
    met as a KeyError or TypeError when the preparation resumes."""
    from test_specimen_file import _rewrite
    settings = dict(assembly="sphere", n=100, seed=9, pressure=100e3, d50=None)
    ck = _written_checkpoint(tmp_path, lambda c, h: specimen.prepare_spheres(100, seed=9, checkpoints=c, progress=h),
                             settings)
    _rewrite(ck, ck + ".npz", edit_meta=edit, reseal=True)
    os.replace(ck + ".npz", ck)
    with pytest.raises(prep_checkpoint.CheckpointMismatch) as exc:
        specimen.prepare_spheres(100, seed=9, checkpoints=prep_checkpoint.for_specimen(str(tmp_path / "s.npz"),
                                                                                       settings, 2000))
    assert "the preparation checkpoint %s is unusable (%s" % (ck, words) in str(exc.value), str(exc.value)
    assert str(exc.value).endswith("remove it, or use --force to prepare from the start")
    proc = run_script("prepare_specimen.py", "--n", 100, "--seed", 9, "--threads", 1, "--out", tmp_path / "s.npz")
    one_line_error(proc, "is unusable (%s" % words, "--force")
