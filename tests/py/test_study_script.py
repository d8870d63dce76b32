"""The study script run_states.py: one CSV row per state and probe with the documented columns,
metadata that says what produced the rows, a resumed run that redoes nothing, and bad input
refused before any work."""
import csv
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest

from conftest import one_line_error

from trueaniso import specimen_file, study

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(REPO, "pyscripts", "run_states.py")


def run(*args, timeout=600, script=SCRIPT):
    env = dict(os.environ, OMP_NUM_THREADS=os.environ.get("OMP_NUM_THREADS", "2"))
    return subprocess.run([sys.executable, script, *args], capture_output=True, text=True, timeout=timeout, env=env)


@pytest.fixture(scope="module")
def small_specimen(tmp_path_factory):
    """prepare_spheres(150, seed=6) by the baseline build, committed (tests/data): the step counts
    compared below belong to a packing, and a build for x86-64-v3 prepares another one from the
    same seed (there --path-rate 20 took 0.72 of rate 2's steps, against the 0.7 asked)."""
    path = tmp_path_factory.mktemp("spec") / "s.npz"
    shutil.copyfile(os.path.join(REPO, "tests", "data", "spheres-150-s6.npz"), path)
    return path


@pytest.fixture(scope="module")
def finished(small_specimen, tmp_path_factory):
    out = tmp_path_factory.mktemp("study") / "out"
    proc = run("--specimen", str(small_specimen), "--ids", "1,2", "--probes", "zx", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    (out.parent / "stdout.txt").write_text(proc.stdout)  # the run's log, beside the study
    return out


def rows(out):
    with open(out / "probes.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_one_row_per_state_and_probe(finished):
    r = rows(finished)
    assert sorted((x["state"], x["probe"]) for x in r) == [("1", "x"), ("1", "z"), ("2", "x"), ("2", "z")]
    assert list(r[0].keys())[:len(study.COLUMNS)] == study.COLUMNS
    with open(finished / "probes.csv", newline="") as f:
        header = next(csv.reader(f))
    assert len(header) == len(set(header)), "a column written twice (Zm was: the row's and the fabric's)"
    for name in ("Zm", "R_xx", "H_zz", "NcV_count", "mic_E_z"):  # fabric columns are always there
        assert name in r[0], name
    for x in r:
        assert float(x["E"]) > 1e8 and float(x["gamma"]) >= 1e-6
        goal = {"1": (100e3, 100e3, 100e3), "2": (95e3, 95e3, 110e3)}[x["state"]]
        for k, g in zip(("sigma_x", "sigma_y", "sigma_z"), goal):
            assert abs(float(x[k]) - g) <= 500.0  # the servo's 0.5 kPa, measured before the probe
        # the row is the state's record: principal values and the largest
        # off-diagonal, recomputed here by numpy from the row's six stresses, all within 0.5 kPa
        s = {k: float(x["sigma_" + k]) for k in ("x", "y", "z", "yz", "xz", "xy")}
        tensor = np.array([[s["x"], s["xy"], s["xz"]], [s["xy"], s["y"], s["yz"]], [s["xz"], s["yz"], s["z"]]])
        principal = np.sort(np.linalg.eigvalsh(tensor))[::-1]
        np.testing.assert_allclose([float(x["sigma_%d" % k]) for k in (1, 2, 3)], principal, rtol=1e-12)
        np.testing.assert_allclose(principal, sorted(goal, reverse=True), atol=500.0)
        assert float(x["tau_max"]) == max(abs(s["yz"]), abs(s["xz"]), abs(s["xy"])) < 500.0



def test_the_last_line_times_the_whole_run(finished):
    """A state's 'probes done' line times its probes, its 'reached' line the loading; the run's last line
    names the whole run, so it is at least their sum (each printed to 0.1 s: 0.05 s of rounding a
    line, the run's own included)."""
    import re
    lines = (finished.parent / "stdout.txt").read_text().splitlines()
    last = re.fullmatch(r"results: (.*); this run took ([0-9.]+) s in all", lines[-1])
    assert last, lines[-1]
    assert last.group(1) == str(finished / "probes.csv")
    parts = [float(m.group(1)) for line in lines
             for m in [re.match(r"state \d+: (?:reached in \d+ steps|probes done) \(([0-9.]+) s\)", line)] if m]
    assert len(parts) == 4  # two states, each reached and probed
    assert float(last.group(2)) >= sum(parts) - 0.05 * (len(parts) + 1)

def test_metadata_says_what_produced_the_rows(finished, small_specimen):
    meta = json.loads((finished / "metadata.json").read_text())
    fp = meta["fingerprint"]
    assert fp["specimen"] == specimen_file.read(str(small_specimen))[1]["sha256"]
    assert meta["runs"][-1]["specimen"]["seed"] == 6
    assert meta["versions"]["threads"] >= 1 and "git" in meta["versions"] and fp["code"].startswith("src-")
    assert fp["probe"]["gamma"] == 1e-6 and meta["probes"] == ["z", "x"] and fp["path"] == "true-triaxial"
    assert fp["state"]["tolerance"] == 100.0 and fp["state"]["unbalanced"] == 1e-4 and fp["state"]["friction"] == 0.5
    assert "relative_tolerance" in fp["probe"]
    assert sorted(meta["states"]) == ["1", "2"] and meta["states"]["2"] == dict(b=0.0, sigma_z=110e3)


def test_resumed_run_redoes_nothing(finished, small_specimen):
    before = (finished / "probes.csv").read_bytes()
    proc = run("--specimen", str(small_specimen), "--ids", "1,2", "--probes", "zx", "--out", str(finished))
    assert proc.returncode == 0, proc.stderr
    assert ": probe " not in proc.stdout, proc.stdout  # no probe ran again (a probe's line: 'state 1: probe z  E = ...')
    assert (finished / "probes.csv").read_bytes() == before


def test_resume_adds_only_the_missing_probe(finished, small_specimen, tmp_path):
    import shutil
    out = tmp_path / "partial"
    shutil.copytree(finished, out)
    kept = [x for x in rows(out) if not (x["state"] == "2" and x["probe"] == "x")]
    with open(out / "probes.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(kept[0].keys()))
        w.writeheader()
        w.writerows(kept)
    proc = run("--specimen", str(small_specimen), "--ids", "1,2", "--probes", "zx", "--out", str(out))
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("probe x  E") == 1 and "probe z  E" not in proc.stdout
    assert "state 2: b =" not in proc.stdout  # state 2 came from its checkpoint, not a new path
    assert len(rows(out)) == 4


@pytest.mark.parametrize("args,message", [
    (["--ids", "1", "--gamma", "nan"], "--gamma"),
    (["--ids", "1", "--gamma", "inf"], "--gamma"),
    (["--ids", "1", "--gamma", "0"], "--gamma"),
    (["--ids", "1", "--probes", "xx"], "--probes"),
    (["--ids", "1", "--probes", "w"], "--probes"),
    (["--states", "1.5:100e3"], "outside [0, 1]"),
    (["--states", "0:310e3"], "must be > 0"),
    (["--states=-0.1:100e3"], "outside [0, 1]"),
    (["--ids", "40"], "40"),
    (["--ids", "1", "--path-rate", "0"], "--path-rate"),
    (["--ids", "1", "--path-rate", "nan"], "--path-rate"),
    # else 3,000,000 steps (6 min on 200 spheres), then "no equilibrium"
    (["--ids", "5", "--path-rate", "1e-9"], "--path-rate 1e-09: state 5 is"),
    (["--ids", "1", "--bogus"], "unrecognized"),
])
def test_bad_input_refused_before_any_work(small_specimen, tmp_path, args, message):
    out = tmp_path / "out"
    proc = run("--specimen", str(small_specimen), "--out", str(out), *args, timeout=60)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and message in lines[0], proc.stderr
    assert not out.exists()


def test_path_rate_is_an_option_of_the_study(finished, small_specimen, tmp_path):
    """--path-rate 20 reaches state 5 (sigma_z 100 -> 140 kPa) in fewer steps than the default 2
    (docs/state-speed.md: about 2.2x at 4000 spheres); the rate is part of the study, so a rerun of
    a study with another rate is refused, naming it."""
    steps = {}
    for rate in ("2", "20"):
        out = tmp_path / ("r" + rate)
        proc = run("--specimen", str(small_specimen), "--ids", "5", "--probes", "z", "--path-rate", rate,
                   "--out", str(out))
        assert proc.returncode == 0, proc.stderr
        steps[rate] = int(rows(out)[0]["state_steps"])
    assert steps["20"] < 0.7 * steps["2"], steps
    # a rerun without the option continues the study at its own rate, as --threads does (it was refused)
    proc = run("--specimen", str(small_specimen), "--ids", "5", "--probes", "z", "--out", str(tmp_path / "r20"))
    assert proc.returncode == 0, proc.stderr
    assert "--path-rate not given: its study reached its states at 20 Pa per step" in proc.stdout
    assert "no state to run" in proc.stdout
    proc = run("--specimen", str(small_specimen), "--ids", "1,2", "--probes", "zx", "--path-rate", "20",
               "--out", str(finished))
    assert proc.returncode == 2 and "path_rate" in proc.stderr and "the path rate (--path-rate; state.path_rate) is 2.0 there, 20.0 in this run" in proc.stderr, proc.stderr


def test_metadata_stays_standard_json_with_an_infinite_path_rate(small_specimen, tmp_path):
    """--path-rate inf wrote "path_rate": Infinity, which strict JSON parsers refuse (an outside
    try); the rate is kept as the text "inf", and a rerun with it is the same study."""
    out = tmp_path / "s"
    for _ in range(2):
        proc = run("--specimen", str(small_specimen), "--ids", "1", "--probes", "z", "--path-rate", "inf",
                   "--out", str(out))
        assert proc.returncode == 0, proc.stderr

    def strict(name):
        raise ValueError("not standard JSON: %s" % name)

    meta = json.loads((out / "metadata.json").read_text(), parse_constant=strict)
    assert meta["fingerprint"]["state"]["path_rate"] == "inf"
    assert "no state to run" in proc.stdout


def test_run_study_on_a_study_of_run_states_says_whose_it_is(finished, small_specimen, tmp_path):
    """run_study.py pointed at a run_states.py study without --specimen names the specimen and the
    option that continues it, instead of calling the specimen file (which such a study never held)
    missing."""
    out = tmp_path / "W"
    shutil.copytree(finished, out)
    before = sorted(p.name for p in out.iterdir())
    proc = run("--n", "150", "--seed", "6", "--out", str(out), script=os.path.join(REPO, "pyscripts", "run_study.py"))
    one_line_error(proc, "a study of the specimen", str(small_specimen), "--specimen SPECIMEN")
    assert sorted(p.name for p in out.iterdir()) == before


def test_run_study_takes_the_options_of_run_states(finished, small_specimen, tmp_path):
    """run_study.py continues a run_states.py study given its specimen and the same options (one
    option set: --specimen, --probes and the rest), adds the statics and the report, and refuses
    --n with --specimen."""
    out = tmp_path / "W"
    shutil.copytree(finished, out)
    script = os.path.join(REPO, "pyscripts", "run_study.py")
    proc = run("--specimen", str(small_specimen), "--n", "150", "--ids", "1,2", "--probes", "zx", "--out", str(out),
               script=script)
    one_line_error(proc, "--n describes the specimen run_study.py prepares")
    before = rows(out)
    proc = run("--specimen", str(small_specimen), "--ids", "1,2", "--probes", "zx", "--out", str(out), script=script)
    assert proc.returncode == 0, proc.stderr
    assert rows(out) == before  # continued, nothing run again
    assert (out / "statics_isotropic.json").exists() and (out / "report" / "report.md").exists()
    record = json.loads((out / "statics_isotropic.json").read_text())
    assert record["study"]["specimen"] == specimen_file.read(str(small_specimen))[1]["sha256"]
    proc = run("--specimen", str(small_specimen), "--ids", "1,2", "--probes", "zx", "--rotations", "restrained",
               "--out", str(out), script=script)
    one_line_error(proc, "another study", "rotations")


def test_run_study_does_not_keep_a_specimen_of_another_recipe(tmp_path):
    """A specimen in run_study.py's --out made by another recipe than the default one of this code
    (the committed spheres-150-s4: the variant grown-to-target, switched at 100 kPa; the default
    unloads to 20 kPa) is refused naming the setting, not kept for a study of the default recipe."""
    out = tmp_path / "W"
    out.mkdir()
    shutil.copyfile(os.path.join(REPO, "tests", "data", "spheres-150-s4.npz"), out / "specimen.npz")
    proc = run("--n", "150", "--seed", "4", "--ids", "1", "--out", str(out),
               script=os.path.join(REPO, "pyscripts", "run_study.py"), timeout=120)
    one_line_error(proc, "another recipe", "switch_pressure: 100000.0 there, 20000.0 here")
    assert not (out / "probes.csv").exists()


def test_run_study_keys_its_checkpoint_and_fingerprint_on_the_recipe(monkeypatch):
    """The preparation's checkpoint and the study's fingerprint are keyed on the recipe's name and
    settings: a default recipe changed (here clump2's mu_prep) is another key, so a checkpoint or a
    study of the old one is refused (prep_checkpoint compares the key, study_dir the fingerprint)."""
    import types
    sys.path.insert(0, os.path.join(REPO, "pyscripts"))
    import run_study
    from trueaniso import clump_recipes, study_dir
    o = types.SimpleNamespace(assembly="clump2", n=1000, seed=1)
    before = run_study.recipe(o)
    assert before["recipe"] == "default" and before["settings"]["mu_prep"] == clump_recipes.RECIPES["clump2"]["mu_prep"]
    monkeypatch.setitem(clump_recipes.RECIPES, "clump2", dict(clump_recipes.RECIPES["clump2"], mu_prep=0.3))
    after = run_study.recipe(o)
    assert study_dir.said(study_dir.differences(before, after))[0].startswith("settings.mu_prep:")
    assert "another recipe" in run_study.recipe_said(before, after)
    assert run_study.recipe_said(before, before) is None
    assert "before run_study.py recorded its recipe" in run_study.recipe_said(dict(assembly="clump2", n=1000, seed=1),
                                                                             after)
