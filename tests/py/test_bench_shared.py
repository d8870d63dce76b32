"""The one writer of benchmark tables (bench/_bench.py): a block between markers is
replaced and nothing else in the document changes; a document without the markers gets the block
at the end of its heading's section, or appended (after a new heading if given); a new document is
created."""
import os
import sys

from conftest import REPO

sys.path.insert(0, os.path.join(REPO, "bench"))
import _bench  # noqa: E402


def test_block_is_replaced_in_place_and_appended_when_missing(tmp_path):
    doc = tmp_path / "bench.md"
    doc.write_text("# Title\n\n<!-- speed:begin -->\nold table\n<!-- speed:end -->\n\nText after.\n")
    _bench.replace_block(str(doc), "speed", "new table\n")
    assert doc.read_text() == "# Title\n\n<!-- speed:begin -->\nnew table\n<!-- speed:end -->\n\nText after.\n"
    _bench.replace_block(str(doc), "other", "second", heading="## Other")
    text = doc.read_text()
    assert text.endswith("Text after.\n\n## Other\n\n<!-- other:begin -->\nsecond\n<!-- other:end -->\n")
    _bench.replace_block(str(doc), "speed", "a table with a backslash \\1 and a group reference")
    assert "a table with a backslash \\1 and a group reference" in doc.read_text()  # not a regex template
    new = tmp_path / "new.md"
    _bench.replace_block(str(new), "t", "x")
    assert new.read_text() == "\n<!-- t:begin -->\nx\n<!-- t:end -->\n"
    assert not [p for p in os.listdir(tmp_path) if p.startswith(".tmp-")]  # no temporary left behind


def test_a_new_block_goes_into_its_headings_section(tmp_path):
    """A block whose heading the document already has goes at the end of that section, before the
    next heading of its level or above (a '#' comment in a code block is none); it appended a second
    copy of the heading at the end of the file (docs/benchmarks.md had two "Stepper changes")."""
    doc = tmp_path / "bench.md"
    doc.write_text("# T\n\n## Changes\n\n<!-- a:begin -->\nA\n<!-- a:end -->\n\n### Sub\n\n```\n# not a heading\n```\n\n"
                   "## Next\n\ntext\n")
    _bench.replace_block(str(doc), "b", "B", heading="## Changes")
    assert doc.read_text() == ("# T\n\n## Changes\n\n<!-- a:begin -->\nA\n<!-- a:end -->\n\n### Sub\n\n```\n# not a heading\n```\n\n"
                               "<!-- b:begin -->\nB\n<!-- b:end -->\n\n## Next\n\ntext\n")
    _bench.replace_block(str(doc), "c", "C", heading="## Next")  # the last section: at the end of the file
    assert doc.read_text().endswith("## Next\n\ntext\n\n<!-- c:begin -->\nC\n<!-- c:end -->\n")
    assert doc.read_text().count("## Changes") == 1


def test_publish_prints_the_table_and_writes_it_only_where_asked(tmp_path, capsys):
    """What every benchmark does with its table: print it, and put it between its markers only in
    the page --doc named (none: no file is written)."""
    assert _bench.publish(None, "speed", ["| a |", "| 1 |"]) == "| a |\n| 1 |"
    assert capsys.readouterr().out == "| a |\n| 1 |\n"
    assert os.listdir(tmp_path) == []
    doc = tmp_path / "bench.md"
    doc.write_text("# T\n\n## Speed\n\ntext\n")
    _bench.publish(str(doc), "speed", "one text", heading="## Speed")
    assert doc.read_text() == "# T\n\n## Speed\n\ntext\n\n<!-- speed:begin -->\none text\n<!-- speed:end -->\n"
    assert capsys.readouterr().out == "one text\n"


def test_machine_names_cpu_and_cores():
    line = _bench.machine()
    assert "%d cores" % os.cpu_count() in line


def test_lammps_peer_takes_a_prepared_specimen(specimen_100, tmp_path):
    """A prepared specimen (its cell keeps ~1e-8 of shear) is taken by the stand-alone
    lammps_peer.py, not refused as sheared: it squares the cell as bench_stepper.py does
    (_bench.orthorhombic)."""
    from conftest import run_script
    proc = run_script(os.path.join("bench", "lammps_peer.py"), "--specimen", specimen_100, "--out", tmp_path / "l",
                      "--steps", 10)
    assert proc.returncode == 0, proc.stderr
    assert "shear terms" in proc.stdout and "orthorhombic box" in proc.stdout
    data = (tmp_path / "l" / "data.lmp").read_text()
    assert "100 atoms" in data and "xy xz yz" not in data  # an orthorhombic box, every sphere


def test_bench_stepper_refuses_bad_input_before_any_run(specimen_100):
    """--dt -1 or nan, --threads 99 or 0, --repeats 0 and --steps -1: each is one line and exit 2,
    at once (not printed as the table's time step, timed as a row, or failed after the runs or
    inside the engine)."""
    from conftest import one_line_error, run_script
    for args, words in ((["--dt", "-1"], "--dt must be"), (["--dt", "nan"], "--dt must be"),
                        (["--threads", "99"], "thread counts 1 to"), (["--threads", "0"], "thread counts 1 to"),
                        (["--threads", "1,1"], "name each thread count once"),
                        (["--codes", "ours,ours"], "name each code once"),
                        (["--codes", "ours", "--dt", "1"], "unstable on this packing"),
                        (["--repeats", "0"], "--repeats >= 1"), (["--steps", "-1"], "--steps")):
        one_line_error(run_script(os.path.join("bench", "bench_stepper.py"), "--specimen", specimen_100, *args,
                                  timeout=60), words)


def test_bench_state_split_on_the_isotropic_state(specimen_100):
    """The ramp and hold split (docs/studies/paper-size.md, clump2's steps) adds up, and bad ids are one line."""
    import json
    from conftest import one_line_error, run_script
    proc = run_script(os.path.join("bench", "bench_state_split.py"), "--specimen", specimen_100, "--ids", "1",
                      "--gains", "0.01", "--chunk", "50", timeout=120)
    assert proc.returncode == 0, proc.stderr
    r = json.loads(proc.stdout.strip().splitlines()[-1])
    assert r["status"] == "reached" and r["ramp"] is not None and r["ramp"] + r["hold"] == r["steps"]
    assert r["feed_forward"] == "off" and r["waited"] == 0  # the isotropic state: no path to wait on
    assert 0 <= r["max_lag"] < 1000.0 and r["off_path"] >= 0  # within the follow tolerance, or it waited
    for args, words in ((["--ids", "40"], "no Table C1 state 40"),
                        # every gain checked before the first state runs
                        (["--ids", "1", "--gains", "0.03,5"], "--gains: 5.0 not in (0, 1]"),
                        (["--ids", "1,1"], "name each value once"),
                        (["--ids", "1", "--feed-forward", "off,yes"], "--feed-forward: off, on")):
        proc = run_script(os.path.join("bench", "bench_state_split.py"), "--specimen", specimen_100, *args, timeout=60)
        one_line_error(proc, words)
        assert proc.stdout == ""


def test_bench_stepper_times_a_second_build_in_the_same_rounds(specimen_100, tmp_path):
    """--also-build DIR: ours from a second build tree (a build for another x86-64 level) gets a row
    of its own, labelled with its level; here the same build twice, which must agree. A tree
    without the module is refused before any run; a build of other sources, or a pressure off by
    more than 1e-8 relative after the timed steps, stops the benchmark (not a speed-up of the same
    computation)."""
    from conftest import REPO, one_line_error, run_script
    build = os.environ.get("TRUEANISO_BUILD", os.path.join(REPO, "build"))
    proc = run_script(os.path.join("bench", "bench_stepper.py"), "--specimen", specimen_100, "--codes", "ours",
                      "--threads", "1", "--repeats", "2", "--steps", "200", "--also-build", build, timeout=120)
    assert proc.returncode == 0, proc.stderr
    rows = [ln for ln in proc.stdout.splitlines() if ln.startswith("| 1 |")]
    from trueaniso import engines
    assert len(rows) == 2 and all(r.startswith("| 1 | bare | %s | " % engines.build_arch()) for r in rows)
    one_line_error(run_script(os.path.join("bench", "bench_stepper.py"), "--specimen", specimen_100,
                              "--also-build", str(tmp_path), timeout=60), "has no python/_trueaniso module")
    import bench_stepper  # on the path with _bench (above)
    first = dict(source_hash="a", pressure=1e5)
    assert bench_stepper.disagreement(first, dict(source_hash="a", pressure=1e5 * (1 + 5e-9))) is None
    assert "other engine sources" in bench_stepper.disagreement(first, dict(source_hash="b", pressure=1e5))
    assert "not the same computation" in bench_stepper.disagreement(first, dict(source_hash="a", pressure=1e5 * (1 + 2e-8)))


def test_bench_stepper_speed_up_is_paired_within_rounds(specimen_100):
    """The speed-up over one thread is ours / ours on one thread in the same round (median and range),
    not a ratio of medians taken from loops over thread counts minutes apart: every thread count
    runs in every round, and the table has the column."""
    from conftest import run_script
    proc = run_script(os.path.join("bench", "bench_stepper.py"), "--specimen", specimen_100, "--codes", "ours",
                      "--threads", "1,2", "--repeats", "2", "--steps", "100", timeout=120)
    assert proc.returncode == 0, proc.stderr
    rounds = [ln.split()[:4] for ln in proc.stdout.splitlines() if ln.startswith("round ")]
    assert sorted(rounds) == [["round", "1", "threads", "1"], ["round", "1", "threads", "2"],
                              ["round", "2", "threads", "1"], ["round", "2", "threads", "2"]]
    assert rounds[0][1] == rounds[1][1] == "1"  # both thread counts of round 1 before round 2
    assert "| threads | step | build | trueaniso | x 1 thread |" in proc.stdout
    assert [ln.rstrip(" |").split(" | ")[4] == "1" for ln in proc.stdout.splitlines() if ln.startswith("| 1 |")] == [True]
    import bench_stepper
    # Round by round: 4/2 and 1/1, median 1.5; the ratio of the medians would be 2.5 / 1.5 = 1.67.
    assert bench_stepper.speedups([4.0, 1.0], [2.0, 1.0]) == "1.50 (1.00-2.00)"
    same = [3.0, 2.0]
    assert bench_stepper.speedups(same, same) == "1"


def test_bench_stepper_times_the_study_step_beside_the_bare_one(specimen_100):
    """--codes ours,ours+servo: the stepper with a study's servo in the chain (_bench.loading_servo,
    which must still be loading when the timed steps end) gets a row of its own beside the bare
    step's, each paired with the first thread count in its own rounds."""
    from conftest import run_script
    proc = run_script(os.path.join("bench", "bench_stepper.py"), "--specimen", specimen_100, "--codes",
                      "ours,ours+servo", "--threads", "1", "--repeats", "1", "--steps", "100", timeout=120)
    assert proc.returncode == 0, proc.stderr
    rows = [ln.split(" | ")[1] for ln in proc.stdout.splitlines() if ln.startswith("| 1 |")]
    assert rows == ["bare", "with the servo"]


def test_expansion_creep_steps_on_as_the_preparation_does(tmp_path, specimen_100):
    """bench/expansion_creep.py continues a preparation's expansion from its checkpoint with the
    preparation's own servo: 2000 steps from the checkpoint at 2000 end at the mean stress the
    preparation itself reached at 4000, to the bit; the checkpoint is only read."""
    import json
    from conftest import one_line_error, run_script
    from trueaniso import engines, prep_checkpoint, specimen

    class Stop(Exception):
        pass

    ck = str(tmp_path / "prep.ck")
    seen = {}

    def hook(label, scene, engine, steps):
        if label == "expansion":
            seen[steps] = float(engine.pressure)
            if steps >= 4000:
                raise Stop()
    threads = engines.threads()
    engines.set_threads(1)  # as the script runs (the packing depends on the count)
    try:
        from trueaniso import psd  # the settings prepare_specimen.py binds its checkpoints to, in part
        recipe = dict(assembly="sphere", pressure=1e5, d50=psd.PAPER_SPHERES.d50, inertial_number=0.01)
        specimen.prepare_spheres(100, seed=7, checkpoints=prep_checkpoint.Checkpoints(ck, recipe, 2000),
                                 progress=hook)
    except Stop:
        pass
    finally:
        engines.set_threads(threads)
    assert 2000 in seen and 4000 in seen
    with open(ck, "rb") as f:
        before = f.read()
    # The checkpoint on disk is the one written at 2000 steps (the next was due at 4000, after the stop).
    proc = run_script(os.path.join("bench", "expansion_creep.py"), "--checkpoint", ck, "--steps", 2000, "--every",
                      500, timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = [json.loads(x) for x in proc.stdout.strip().splitlines()]
    samples, summary = lines[:-1], lines[-1]
    assert [s["step"] for s in samples] == [500, 1000, 1500, 2000]
    assert samples[-1]["error"] == round(1e5 - seen[4000], 2)
    assert summary["expansion_steps_before"] == 2000 and summary["steps"] == 2000
    assert summary["error_min"] == min(s["error"] for s in samples) and summary["gain"] == 0.002
    assert summary["growth_per_step"] == (samples[-1]["scale"] - 1.0) / 2000
    assert summary["criterion_met_at"] is None and not any(s["criterion"] for s in samples)
    # Stepped on long enough, it stops at the first sample at which the expansion's end criterion holds.
    proc = run_script(os.path.join("bench", "expansion_creep.py"), "--checkpoint", ck, "--steps", 400000, "--every",
                      2000, timeout=300)
    assert proc.returncode == 0, proc.stderr
    lines = [json.loads(x) for x in proc.stdout.strip().splitlines()]
    samples, summary = lines[:-1], lines[-1]
    assert summary["criterion_met_at"] == samples[-1]["step"] == summary["steps"] < 400000
    assert samples[-1]["criterion"] and not any(s["criterion"] for s in samples[:-1])
    assert abs(samples[-1]["error"]) < 100.0 and samples[-1]["unbalanced"] < 0.01
    assert summary["trend_per_1000_steps"] < 0  # an approach: the error falls
    with open(ck, "rb") as f:
        assert f.read() == before
    for args, words in ((["--checkpoint", ck, "--steps", "10", "--every", "20"], "--every (20) is more than --steps"),
                        (["--checkpoint", str(tmp_path / "none.ck")], "no such file"),
                        (["--checkpoint", str(tmp_path)], "is a directory"),
                        (["--checkpoint", str(specimen_100)], "is a specimen, not a preparation checkpoint")):
        one_line_error(run_script(os.path.join("bench", "expansion_creep.py"), *args, timeout=60), words)


def test_expansion_creep_takes_the_recipe_s_target_and_servo():
    """The sphere recipe grown to its switch pressure expands to it, not to the final pressure; a named
    variant's gain and deviator hold are its own, the defaults else (prepare_spheres', prepare_clumps')."""
    import expansion_creep
    base = dict(assembly="sphere", pressure=1e5, d50=1.95e-4, inertial_number=0.01)
    d = expansion_creep.servo_settings(base)
    assert d["target"] == 1e5 and d["gain"] == 0.002 and d["hold_deviator"] is None and d["damping"] == 0.4
    assert expansion_creep.servo_settings(dict(base, recipe="grown-to-switch", switch_pressure=5000.0))["target"] == 5000.0
    assert expansion_creep.servo_settings(dict(base, recipe="unloaded-to-5kPa", switch_pressure=5000.0))["target"] == 1e5
    clump1 = dict(base, assembly="clump1")
    assert expansion_creep.servo_settings(dict(clump1, recipe="hold-deviator"))["hold_deviator"] == 0.05
    assert expansion_creep.servo_settings(dict(clump1, recipe="fast-growth"))["gain"] == 0.1


def test_chain_steps_times_a_clump_chain_with_its_time_stepper():
    """bench/chain_steps.py (docs/studies/benchmarks.md, "Stepper changes") steps a clump specimen
    under each rule and says what it timed; a missing specimen or no step is one line, exit 2."""
    import json
    from conftest import one_line_error, run_script
    clumps = os.path.join(REPO, "tests", "data", "clump1-200-s4.npz")
    for rule in ("per-axis", "smallest-inertia"):
        r = run_script(os.path.join("bench", "chain_steps.py"), "--specimen", clumps, "--steps", "20", "--time-step", rule,
                       timeout=120)
        assert r.returncode == 0, r.stderr
        line = json.loads(r.stdout.strip().splitlines()[-1])
        assert line["time_step"] == rule and line["steps"] == 20 and line["bodies"] == 200 and line["cpu_ms_a_step"] > 0
    one_line_error(run_script(os.path.join("bench", "chain_steps.py"), "--specimen", clumps + ".missing"), "no such file")
    one_line_error(run_script(os.path.join("bench", "chain_steps.py"), "--specimen", clumps, "--steps", "0"), "--steps")
