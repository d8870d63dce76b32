"""The report and the figures apply the study's own checks (trueaniso/study_checks.py): a
checkpoint in DIR/states/ of another study is refused before it is solved, rows of states the
study's metadata.json does not define (or defines otherwise) are refused, and a NaN or infinite
cell leaves its row out with a line in report.md, never a LinAlgError."""
import csv
import json
import os
import shutil
import subprocess
import sys

import pytest
from conftest import REPO, one_line_error

from trueaniso import specimen_file, study, study_dir

STUDY = os.path.join(REPO, "docs", "data", "spheres-4000-s1")  # committed: metadata.json and probes.csv
ENV = dict(os.environ, OMP_NUM_THREADS="1")


def _module(*args):
    return subprocess.run([sys.executable, "-m", *map(str, args)], cwd=REPO, capture_output=True, text=True, env=ENV,
                          timeout=300)


def _study_with_checkpoint(tmp_path, specimen_path, **changes):
    """A study directory of `specimen` defining states 1 and 5, with states/1.npz saved as a
    checkpoint whose parameters are state 1 of this study, changed by `changes`."""
    scene, meta = specimen_file.load(str(specimen_path))
    fp = study.fingerprint(meta, "sphere", 1e-6, False, False, 0.4, dict(friction=0.5, path_rate=2.0))
    out = tmp_path / "study"
    states = [(1, 0.0, 100e3), (5, 0.0, 140e3)]
    study_dir.write_metadata(str(out), fp, states, ["z"], dict(specimen=dict(material=meta["material"])))
    params = dict(state="1", b=0.0, sigma_z=100e3, path="true-triaxial", steps=10, wall_time=1.0, start="specimen",
                  specimen=meta["sha256"], code=fp["code"], study=study_dir.states_key(fp))
    params.update(changes)
    specimen_file.save(str(out / "states" / "1.npz"), scene, seed=3, parameters=params)
    shutil.copy(os.path.join(STUDY, "probes.csv"), out / "probes.csv")  # refused or not, not read first
    return out


@pytest.mark.parametrize("changes,words", [
    (dict(study="0123456789abcdef"), "made by another study"),  # would give Table B1 of the other study
    (dict(specimen="f" * 64), "another specimen"),
    (dict(sigma_z=110e3), "sigma_z = 110000 Pa"),
    (dict(state="5"), "checkpoint of state 5, not of state 1"),
    (dict(b="zero"), "parameters.b: must be a finite number"),
])
def test_statics_refuses_a_checkpoint_of_another_study(specimen_100, tmp_path, changes, words):
    out = _study_with_checkpoint(tmp_path, specimen_100, **changes)
    proc = _module("trueaniso.analysis.report", out, "--statics")
    one_line_error(proc, "states/1.npz", words)
    assert not (out / "statics_state-1.json").exists() and not (out / "report").exists()


def test_statics_solves_the_study_s_own_checkpoint(specimen_100, tmp_path):
    """The control of the test above: the same file with this study's parameters passes the checks
    (the report then refuses the committed rows, which are another study's)."""
    out = _study_with_checkpoint(tmp_path, specimen_100)
    proc = _module("trueaniso.analysis.report", out, "--statics")
    assert (out / "statics_state-1.json").exists(), proc.stderr
    last = proc.stderr.strip().splitlines()[-1]  # after the solve's own line
    assert proc.returncode == 2 and last.startswith("error: ") and "does not define" in last, proc.stderr


def _copy_study(tmp_path, edit_meta=None, edit_rows=None):
    out = tmp_path / "copy"
    out.mkdir()
    meta = json.loads(open(os.path.join(STUDY, "metadata.json")).read())
    if edit_meta:
        edit_meta(meta)
    (out / "metadata.json").write_text(json.dumps(meta))
    with open(os.path.join(STUDY, "probes.csv")) as f:
        rows = list(csv.reader(f))
    if edit_rows:
        edit_rows(rows)
    with open(out / "probes.csv", "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)
    return out


def _set(line, column, value):
    """Every column of that name (the committed table has Zm twice: the row's and the fabric's)."""
    def edit(rows):
        for k, name in enumerate(rows[0]):
            if name == column:
                rows[line - 1][k] = value
    return edit


def _drop_state(sid):
    def edit(meta):
        del meta["states"][sid]
    return edit


@pytest.mark.parametrize("edit_meta,edit_rows,words", [
    # rows of a state the study does not define would go into Table 2 and the fit of zeta
    (_drop_state("5"), None, ["rows of state 5", "does not define"]),
    (None, _set(4, "b", "0.25"), ["line 4", "b = 0.25", "defines it with b"]),
    (None, _set(4, "sigma_z_goal", "150000.0"), ["line 4", "sigma_z_goal = 150000.0"]),
    (None, _set(4, "path", "cross-anisotropic"), ["line 4", "cross-anisotropic path"]),
])
def test_rows_that_are_not_the_study_s_are_refused_by_every_analysis(tmp_path, edit_meta, edit_rows, words):
    out = _copy_study(tmp_path, edit_meta, edit_rows)
    for tool in (["trueaniso.analysis.report", out], ["trueaniso.analysis.figures", out / "probes.csv", "--out", tmp_path / "f"],
                 ["trueaniso.analysis.path_fidelity", out]):
        one_line_error(_module(*tool), *words)
    assert not (out / "report").exists() and not (tmp_path / "f").exists()


def test_a_nan_cell_leaves_its_row_out_and_the_report_says_so(tmp_path):
    """One NaN Zm is left out of the report, the figures and path_fidelity, each saying which line:
    kept, it fails the report's fit as a LinAlgError (SVD did not converge) and the figures as a
    SystemError."""
    out = _copy_study(tmp_path, edit_rows=_set(5, "Zm", "nan"))
    proc = _module("trueaniso.analysis.report", out)
    assert proc.returncode == 0, proc.stderr
    text = (out / "report" / "report.md").read_text()
    assert "1 row with a NaN or infinite cell left out: line 5 (state 6 probe z: Zm = nan)" in text, text[:3000]
    proc = _module("trueaniso.analysis.figures", out / "probes.csv", "--out", tmp_path / "f")
    assert proc.returncode == 0 and "left out: line 5" in proc.stderr, proc.stderr
    proc = _module("trueaniso.analysis.path_fidelity", out / "probes.csv")  # says so too, not only the report
    assert proc.returncode == 0 and "left out: line 5" in proc.stderr, proc.stderr


def test_an_infinite_cell_in_every_row_is_refused(tmp_path):
    def edit(rows):
        for line in range(2, len(rows) + 1):
            _set(line, "Zm", "inf")(rows)
    out = _copy_study(tmp_path, edit_rows=edit)
    one_line_error(_module("trueaniso.analysis.report", out), "every row has a NaN or infinite cell")
