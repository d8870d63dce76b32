"""bench_study.py, the whole study's clock (docs/benchmarks.md and docs/studies/benchmarks.md, "The
whole study's clock"): what it refuses before any run, that its tables add up what the runs
recorded (steps from probes.csv, parts of a study timed in two runs added, the speed-up the first
code's time over the other's, no speed-up between runs of other states, one code's table without
one), and that the commands under a table name the checkout's paths, not this machine's. Timings
are printed, never asserted."""
import csv
import json
import os
import shutil
import sys

from conftest import REPO, one_line_error, run_script

sys.path.insert(0, os.path.join(REPO, "bench"))


def bench(*args, timeout=600):
    return run_script("bench/bench_study.py", *args, timeout=timeout)


def test_refused_before_any_run(tmp_path, specimen_150):
    runs = tmp_path / "runs"
    for args, words in (
            ((), "nothing to do"),
            (("--prepare", "--specimen", specimen_150), "give one of them"),
            (("--specimen", specimen_150, "--assembly", "clump2"), "with --prepare"),
            (("--specimen", specimen_150, "--tree", REPO, "--tree", REPO, "--label", "a"), "one for each --tree"),
            (("--specimen", specimen_150, "--tree", REPO, "--tree", REPO, "--label", "a", "--label", "a"), "each once"),
            (("--specimen", specimen_150, "--ids", "0,1"), "states of Table C1"),
            (("--specimen", specimen_150, "--ids", "1,1"), "each once"),
            (("--specimen", specimen_150, "--ids", "1-x"), "numbers and ranges"),
            (("--specimen", specimen_150, "--doc", tmp_path / "b.md"), "with --tabulate"),
            (("--specimen", specimen_150, "--tree", tmp_path), "not a trueaniso checkout"),
            (("--specimen", tmp_path / "missing.npz"), "missing.npz"),
            (("--tabulate", "--tree", REPO), "give --specimen or --prepare"),
            (("--specimen", specimen_150, "--runs", tmp_path / "other"), "one folder for a run"),
            (("--prepare", "--time-step", "per-axis"), "without --prepare"),
    ):
        proc = bench(*args, "--runs", runs)
        one_line_error(proc, words)
    proc = bench("--tabulate", "--runs", runs)
    assert proc.returncode == 2 and "no runs recorded" in proc.stderr
    assert not runs.exists() or not os.listdir(runs)


def _rows(text, first_cell):
    return [[c.strip() for c in ln.split("|")[1:-1]] for ln in text.splitlines() if ln.startswith("| %s |" % first_cell)]


def test_the_tables_add_up_the_runs(tmp_path, specimen_150):
    """Two labels of this tree on the 150-sphere specimen: 'a' times states 1 and 21 in two runs
    (a study continued), 'b' both at once, 'c' state 1 alone. The table's steps are probes.csv's,
    a's wall and CPU the sum of its two runs, b's speed-up a's time over b's, c's none."""
    runs, doc = tmp_path / "runs", tmp_path / "bench.md"
    doc.write_text("# B\n\n<!-- study-clock:begin -->\nold\n<!-- study-clock:end -->\n\nafter\n")
    for args in (("--label", "a", "--ids", "1"), ("--label", "a", "--ids", "1,21"), ("--label", "b", "--ids", "1,21"),
                 ("--label", "c", "--ids", "1")):
        proc = bench("--tree", REPO, "--specimen", specimen_150, "--runs", runs, *args)
        assert proc.returncode == 0, proc.stderr
    again = bench("--tree", REPO, "--label", "b", "--specimen", specimen_150, "--runs", runs, "--ids", "21")
    assert again.returncode == 0 and "already timed" in again.stdout  # nothing run twice
    proc = bench("--tabulate", "--runs", runs, "--label", "a", "--label", "b", "--label", "c", "--doc", doc,
                 "--note", "nothing paused")
    assert proc.returncode == 0, proc.stderr
    text = doc.read_text()
    assert text.startswith("# B\n\n<!-- study-clock:begin -->\nMachine: ") and text.endswith("<!-- study-clock:end -->\n\nafter\n")
    assert "nothing paused" in text and "timed in 2 runs (states 1; 21)" in text and "c ran states 1, a no round of the same: not compared" in text
    # The commands under the table run in a reader's checkout: this tree is the default (no --tree),
    # the runs folder outside the checkout is the default's, the specimen outside it is named in
    # specimens/ and said what it is; no path of this machine is printed.
    commands = [ln.strip() for ln in text.splitlines() if ln.startswith("    /usr/bin/python3 bench/bench_study.py")]
    assert "/usr/bin/python3 bench/bench_study.py --label a --specimen specimens/spheres-150-s4.npz --ids 1" in commands
    assert commands[-1] == ("/usr/bin/python3 bench/bench_study.py --tabulate --label a --label b --label c --note "
                            "'nothing paused' --doc %s --block study-clock" % doc)
    assert "specimens/spheres-150-s4.npz is a sphere specimen of the default recipe, 150 particles" in text
    assert str(tmp_path) not in text.replace(str(doc), "") and REPO not in text and "--tree" not in text

    record = {lb: json.loads((runs / lb / "spheres-150-s4.json").read_text()) for lb in "abc"}
    assert [p["ids"] for p in record["a"]["parts"]] == [[1], [21]]
    with open(runs / "b" / "spheres-150-s4" / "probes.csv") as f:
        rows = list(csv.DictReader(f))
    state_steps = sum({r["state"]: int(r["state_steps"]) for r in rows}.values())
    probe_steps = sum(int(r["probe_steps"]) for r in rows)
    clock = {r[2].split(" ")[0]: r for r in _rows(text, "sphere") if r[1] == "150"}
    assert set(clock) == {"a", "b", "c"}
    a, b, c = clock["a"], clock["b"], clock["c"]
    assert a[3] == b[3] == "1,21" and c[3] == "1" and a[6] == "1"
    assert (int(b[4]), int(b[5])) == (state_steps, probe_steps) == (int(a[4]), int(a[5]))  # the same study
    wall = {lb: sum(p["wall"] for p in record[lb]["parts"]) for lb in "abc"}
    cpu = {lb: sum(p["cpu"] for p in record[lb]["parts"]) for lb in "abc"}
    assert abs(float(a[7]) - wall["a"]) <= 0.5 and abs(float(a[8]) - cpu["a"]) <= 0.5
    assert a[9] == a[10] == "1.00" and c[9] == c[10] == "-"
    assert float(b[9]) == round(wall["a"] / wall["b"], 2) and float(b[10]) == round(cpu["a"] / cpu["b"], 2)

    # A second round (another --runs folder) of b alone: b's times are the median of its two rounds,
    # its speed-up only the round a also ran.
    shutil.copytree(runs / "b", tmp_path / "round2" / "b")
    moved = json.loads((tmp_path / "round2" / "b" / "spheres-150-s4.json").read_text())
    moved["parts"][0]["wall"] *= 3.0
    (tmp_path / "round2" / "b" / "spheres-150-s4.json").write_text(json.dumps(moved))
    proc = bench("--tabulate", "--runs", runs, "--runs", tmp_path / "round2", "--label", "a", "--label", "b")
    assert proc.returncode == 0, proc.stderr
    b2 = {r[2].split(" ")[0]: r for r in _rows(proc.stdout, "sphere") if r[1] == "150"}["b"]
    assert b2[6] == "2" and b2[7] == "%.0f (%.0f-%.0f)" % (2.0 * wall["b"], wall["b"], 3.0 * wall["b"])
    assert float(b2[9]) == round(wall["a"] / wall["b"], 2) and "1 of its 2 rounds without a run of a" in proc.stdout
    # b's run, made in both rounds, is one command with the second round named; c is not tabulated
    assert ("/usr/bin/python3 bench/bench_study.py --label b --specimen specimens/spheres-150-s4.npz --ids 1,21   "
            "# and again with --runs results/bench-study-2 (a round each)") in proc.stdout
    assert "--label c" not in proc.stdout and "| c (" not in proc.stdout

    # One code alone (the current code's table): no speed-up columns and no label; a tree other
    # than this checkout is named by its label in capitals and said to be a checkout of its commit.
    moved = json.loads((runs / "b" / "spheres-150-s4.json").read_text())
    moved["tree"], moved["parts"][0]["commit"] = "/elsewhere/tree", "1234567"
    (runs / "b" / "spheres-150-s4.json").write_text(json.dumps(moved))
    proc = bench("--tabulate", "--runs", runs, "--label", "b")
    assert proc.returncode == 0, proc.stderr
    alone = _rows(proc.stdout, "sphere")
    assert alone[0][2].startswith("1234567, ") and len(alone[0]) == 9 and "first / this" not in proc.stdout
    assert "--tree B --label b --specimen specimens/spheres-150-s4.npz" in proc.stdout
    assert "B is a built checkout of 1234567, made by `git worktree add --detach B 1234567`" in proc.stdout
    proc = bench("--tabulate", "--runs", runs, "--label", "d")
    assert proc.returncode == 2 and "--label d: no runs of that label" in proc.stderr

    where = {r[1]: r for r in _rows(text, "sphere") if r[1] != "150"}
    states_s = sum({r["state"]: float(r["state_wall_time"]) for r in rows}.values())
    assert abs(float(where["b"][2]) - states_s) <= 0.5
    parts = [float(x) for x in where["b"][5:]]
    assert parts[0] > 0 and abs(sum(parts) - wall["b"]) <= 0.35 * wall["b"] + 3  # the profile covers the run


def test_each_function_belongs_to_one_part():
    import bench_study
    assert bench_study.part_of("/x/pyscripts/trueaniso/dem.py", "run") == "stepping"
    assert bench_study.part_of("/x/pyscripts/trueaniso/dem.py", "__init__") == "python"
    assert bench_study.part_of("/x/pyscripts/trueaniso/fabric.py", "fabric_row") == "measurement"
    assert bench_study.part_of("/x/pyscripts/trueaniso/statics.py", "static_stiffness") == "statics"
    assert bench_study.part_of("~", "<built-in method posix.fsync>") == "io"
    assert bench_study.part_of("/usr/lib/python3/dist-packages/numpy/lib/npyio.py", "savez") == "io"
    assert bench_study.part_of("/usr/lib/python3/dist-packages/matplotlib/figure.py", "savefig") == "analysis"
    assert bench_study.part_of("~", "<built-in method builtins.compile>") == "python"
    assert bench_study.parse_ids("1-3,21") == [1, 2, 3, 21]


def test_an_interrupted_run_is_not_timed_again_as_if_whole(tmp_path, specimen_150):
    """A study that holds rows no timed run recorded (a run killed after its first states) would be
    continued, its clock counting only the rest: refused, naming the folder to remove."""
    runs = tmp_path / "runs"
    proc = bench("--tree", REPO, "--label", "a", "--specimen", specimen_150, "--runs", runs, "--ids", "1")
    assert proc.returncode == 0, proc.stderr
    (runs / "a" / "spheres-150-s4.json").unlink()  # as if the run had been killed before its record
    proc = bench("--tree", REPO, "--label", "a", "--specimen", specimen_150, "--runs", runs, "--ids", "1,21")
    one_line_error(proc, "already has rows of states 1", "remove")


def test_a_run_on_two_threads_says_so(tmp_path, specimen_150):
    """--threads 2 reaches run_study.py, the table's code column and the command under the table
    say it, and the same label on another thread count is refused before any run."""
    runs = tmp_path / "runs"
    proc = bench("--tree", REPO, "--label", "two", "--threads", "2", "--specimen", specimen_150, "--runs", runs,
                 "--ids", "1")
    assert proc.returncode == 0, proc.stderr
    record = json.loads((runs / "two" / "spheres-150-s4.json").read_text())
    assert record["threads"] == 2
    with open(runs / "two" / "spheres-150-s4" / "metadata.json") as f:
        assert json.load(f)["runs"][-1]["versions"]["threads"] == 2
    one_line_error(bench("--tree", REPO, "--label", "two", "--specimen", specimen_150, "--runs", runs, "--ids", "21"),
                   "another --label")
    proc = bench("--tabulate", "--runs", runs)
    assert proc.returncode == 0, proc.stderr
    assert _rows(proc.stdout, "sphere")[0][2].endswith(", 2 threads")
    assert "engine threads as the code column says" in proc.stdout
    assert "bench/bench_study.py --label two --threads 2 --specimen specimens/spheres-150-s4.npz --ids 1" in proc.stdout
