"""bench_builds.py, the before/after timing of a stepper change (docs/benchmarks.md, "Stepper
changes"): it times two builds on the same packing only when they compute the same thing, and
refuses what is not a checkout. Timings are printed, never asserted."""
import os
import shutil

from conftest import REPO, one_line_error, run_script


def bench(before, after, specimen, *extra):
    return run_script("bench/bench_builds.py", "--before", before, "--after", after, "--specimen", specimen,
                      "--repeats", "2", "--particle-steps", "2e4", *extra, timeout=300)


def test_one_build_against_itself_gives_a_row_and_the_same_bits(tmp_path, specimen_100):
    doc = tmp_path / "bench.md"
    proc = bench(REPO, REPO, specimen_100, "--change", "nothing", "--doc", doc)
    assert proc.returncode == 0, proc.stderr
    text = doc.read_text()
    assert "<!-- stepper-builds:begin -->" in text and "nothing:" in text
    rows = [ln for ln in text.splitlines() if ln.startswith("| 100 |")]
    assert len(rows) == 1
    before, after, ratio = (float(x) for x in rows[0].split("|")[2:5])
    assert before > 0 and after > 0 and abs(ratio - after / before) < 0.2 * ratio  # median of ratios


def test_a_whole_state_timed_against_itself(tmp_path, specimen_100):
    doc = tmp_path / "bench.md"
    proc = run_script("bench/bench_builds.py", "--before", REPO, "--after", REPO, "--specimen", specimen_100,
                      "--state", "5", "--repeats", "1", "--doc", doc, "--block", "state", timeout=300)
    assert proc.returncode == 0, proc.stderr
    rows = [ln for ln in doc.read_text().splitlines() if ln.startswith("| 5 |")]
    assert len(rows) == 1
    steps, before, after = (float(x) for x in rows[0].split("|")[2:5])
    assert steps > 200 and before > 0 and after > 0


def test_builds_that_compute_differently_are_refused(tmp_path, specimen_100):
    """A tree whose chain damps half as much steps the packing elsewhere: not the same computation."""
    other = tmp_path / "other"
    shutil.copytree(os.path.join(REPO, "pyscripts"), other / "pyscripts",
                    ignore=shutil.ignore_patterns("__pycache__"))
    os.symlink(os.path.join(REPO, "build"), other / "build")
    dem = other / "pyscripts" / "trueaniso" / "dem.py"
    text = dem.read_text()
    assert "self.integrator.damping = damping\n" in text
    dem.write_text(text.replace("self.integrator.damping = damping\n", "self.integrator.damping = 0.5 * damping\n"))
    proc = bench(REPO, other, specimen_100)
    assert proc.returncode == 1 and "different results" in proc.stderr, proc.stderr


def test_refuses_a_folder_that_is_not_a_checkout_or_not_built(tmp_path, specimen_100):
    one_line_error(bench(tmp_path, REPO, specimen_100), "not a trueaniso checkout")
    unbuilt = tmp_path / "unbuilt"
    shutil.copytree(os.path.join(REPO, "pyscripts"), unbuilt / "pyscripts", ignore=shutil.ignore_patterns("__pycache__"))
    one_line_error(bench(REPO, unbuilt, specimen_100), "not built")


def test_a_team_of_threads_is_timed_in_wall_seconds(tmp_path, specimen_100):
    """--threads 2: a change for threads removes the waits at a team's barriers, which CPU time
    counts as work; the table says wall time. Refused before any run: 0 threads, more than the
    machine allows, and a team with --state (run_states.py runs at 1)."""
    proc = bench(REPO, REPO, specimen_100, "--threads", "2")
    assert proc.returncode == 0, proc.stderr
    assert "2 engine threads, wall time" in proc.stdout and "M particle-steps per wall s" in proc.stdout
    for args, words in ((["--threads", "0"], "--threads must be 1 to"), (["--threads", "999"], "--threads must be 1 to"),
                        (["--threads", "2", "--state", "5"], "1 with --state")):
        proc = bench(REPO, REPO, specimen_100, *args)
        one_line_error(proc, words)
        assert proc.stdout == ""


def test_a_tree_against_itself_keeps_two_sides_and_the_asked_particle_steps(specimen_100):
    """A/A (the same tree as before and after, a check of the noise): the two sides' runs are kept
    apart (one list keyed by the tree would say 1.000 (1.000 - 1.000) whatever the runs gave), and
    --particle-steps is divided by the specimen's own count, not 4000. The ratios must be the
    printed runs' own, and the steps n / 100."""
    import ast
    import statistics
    proc = bench(REPO, REPO, specimen_100, "--particle-steps", "3e4", "--repeats", "3")
    assert proc.returncode == 0, proc.stderr
    runs = {"before": [], "after": []}
    for ln in proc.stdout.splitlines():
        words = ln.split(None, 2)
        if words and words[0] in runs:
            runs[words[0]].append(ast.literal_eval(words[2]))
    assert [len(runs["before"]), len(runs["after"])] == [3, 3]
    assert all(r["steps"] == 300 for side in runs.values() for r in side)  # 3e4 particle-steps / 100 spheres
    ratios = [(a["n"] * a["steps"] / a["cpu"]) / (b["n"] * b["steps"] / b["cpu"]) for a, b in zip(runs["after"], runs["before"])]
    row = [ln for ln in proc.stdout.splitlines() if ln.startswith("| 100 |")][0].rstrip(" |").split(" | ")
    assert row[3] == "%.3f" % statistics.median(ratios) and row[4] == "%.3f - %.3f" % (min(ratios), max(ratios))


def test_bad_input_is_one_line_before_any_run(tmp_path, specimen_100):
    """Each is one line before any run, not a worker's traceback after starting, nor timed as a row."""
    from trueaniso import specimen_file
    scene, _ = specimen_file.load(specimen_100)
    clumps = tmp_path / "c.npz"
    specimen_file.save(str(clumps), scene, parameters=dict(assembly="clump1"))
    notes = tmp_path / "notes.json"
    notes.write_text("{}")
    for specimen, args, words in ((str(notes), [], "is not a specimen file"),
                                  (str(clumps), [], "sphere specimens only"),
                                  (specimen_100, ["--state", "99"], "a state of Table C1"),
                                  (specimen_100, ["--particle-steps", "0"], "--particle-steps must be"),
                                  (specimen_100, ["--particle-steps", "nan"], "--particle-steps must be"),
                                  (specimen_100, ["--doc", str(tmp_path / "no" / "b.md")], "cannot write a file there")):
        proc = bench(REPO, REPO, specimen, *args)
        one_line_error(proc, words)
        assert proc.stdout == ""
