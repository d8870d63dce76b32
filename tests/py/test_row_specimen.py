"""Every row of a probe table names its study's specimen (the `specimen` column, the checksum
metadata.json records), so that rows of two studies of the same states put into one table are
refused by every reader, not fitted together; a table written before the column existed is read
and resumed as it is.

The studies here are one state of the committed 150- and 300-sphere specimens (a few seconds each);
the report's control runs on the committed 4000-sphere study (docs/data/spheres-4000-s1)."""
import concurrent.futures
import csv
import json
import os
import shutil
import subprocess
import sys

import pytest
from conftest import REPO, one_line_error, run_script

from trueaniso.analysis import results
from trueaniso import specimen_file, study

WALL = set(study.WALL_TIME_COLUMNS)  # the only columns a rerun may change
COMMITTED = os.path.join(REPO, "docs", "data", "spheres-4000-s1")  # metadata.json and probes.csv, no specimen column
ENV = dict(os.environ, OMP_NUM_THREADS="1")


def _module(*args):
    return subprocess.run([sys.executable, "-m", *map(str, args)], cwd=REPO, capture_output=True, text=True, env=ENV,
                          timeout=300)


def _table(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], rows[1:]


def _write(path, header, rows):
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows([header] + rows)


def _checksum(spec):
    """The specimen's checksum as its own file states it (specimen_file checks it on load)."""
    return specimen_file.load(str(spec))[1]["sha256"]


def _own(out):
    with open(os.path.join(out, "metadata.json")) as f:
        return json.load(f)["fingerprint"]["specimen"]


def _state_1(spec, probes, out):
    proc = run_script("run_states.py", "--specimen", spec, "--out", out, "--ids", "1", "--probes", probes)
    assert proc.returncode == 0, proc.stderr
    return out


@pytest.fixture(scope="module")
def study_a(specimen_300, tmp_path_factory):
    """State 1 of the 300-sphere specimen, probes z and x."""
    return _state_1(specimen_300, "zx", tmp_path_factory.mktemp("a") / "study")


@pytest.fixture(scope="module")
def study_b(specimen_150, tmp_path_factory):
    """State 1 (the same definition as study_a's) of the 150-sphere specimen, probe y."""
    return _state_1(specimen_150, "y", tmp_path_factory.mktemp("b") / "study")


def test_a_new_study_s_rows_name_its_specimen(study_a, specimen_300):
    header, rows = _table(study_a / "probes.csv")
    assert header.count("specimen") == 1 and len(rows) == 2
    expected = _checksum(specimen_300)
    assert len(expected) == 64 and _own(study_a) == expected
    k = header.index("specimen")
    assert [r[k] for r in rows] == [expected, expected]


def test_rows_made_on_worker_processes_name_it_too(specimen_300, study_a, tmp_path):
    """The path of run_states.py --mpi: workers hand rows back, the master appends them."""
    threads = study.engines.threads()
    study.engines.set_threads(1)  # the study's thread count, as run_script's OMP_NUM_THREADS=1
    try:
        with concurrent.futures.ProcessPoolExecutor(1) as pool:
            rows = study.run_states(str(specimen_300), study.table_states([1]), str(tmp_path / "pooled"),
                                    probes="zx", log=lambda m: None, executor=pool)
    finally:
        study.engines.set_threads(threads)
    assert [r["specimen"] for r in rows] == [_checksum(specimen_300)] * 2
    strip = [{k: v for k, v in r.items() if k not in WALL} for r in rows]
    assert strip == [{k: v for k, v in r.items() if k not in WALL} for r in study.read_rows(str(study_a / "probes.csv"))]


@pytest.fixture
def mixed(study_a, study_b, tmp_path):
    """study_a with study_b's row (state 1, probe y: the same state's definition) appended to its
    table: one probe a row, every state defined, only the specimen tells them apart."""
    out = tmp_path / "mixed"
    shutil.copytree(study_a, out)
    header, rows = _table(out / "probes.csv")
    header_b, rows_b = _table(study_b / "probes.csv")
    assert header_b == header
    _write(out / "probes.csv", header, rows + rows_b)
    return out


def test_rows_of_two_studies_are_refused_by_every_analysis(mixed, study_b, tmp_path):
    a, b = _own(mixed), _own(study_b)
    assert a != b
    for tool in (["trueaniso.analysis.report", mixed], ["trueaniso.analysis.figures", mixed / "probes.csv", "--out", tmp_path / "f"],
                 ["trueaniso.analysis.path_fidelity", mixed], ["trueaniso.analysis.zeta_contrast", mixed]):
        line = one_line_error(_module(*tool), str(mixed / "probes.csv"), "line 4", a, b)
        assert "another study" in line
    assert not (mixed / "report").exists() and not (tmp_path / "f").exists()


def test_a_resumed_run_refuses_them_too(mixed, specimen_300):
    before = (mixed / "probes.csv").read_text()
    proc = run_script("run_states.py", "--specimen", specimen_300, "--out", mixed, "--ids", "1", "--probes", "zxy")
    one_line_error(proc, "probes.csv", "line 4", _own(mixed))
    assert (mixed / "probes.csv").read_text() == before


def test_a_mixed_table_away_from_its_study_is_refused_too(mixed, study_b, tmp_path):
    """A copy under another name has no metadata.json to compare with: its rows must still name one
    specimen, else figures and zeta would fit two studies together."""
    bare = tmp_path / "bare"
    bare.mkdir()
    shutil.copyfile(mixed / "probes.csv", bare / "copy.csv")
    proc = _module("trueaniso.analysis.figures", bare / "copy.csv", "--out", tmp_path / "f")
    line = one_line_error(proc, "copy.csv", "line 4", _own(mixed), _own(study_b))
    assert "two studies" in line
    assert not (tmp_path / "f").exists()
    shutil.copyfile(study_b / "probes.csv", bare / "one.csv")  # one study's rows alone: read
    assert len(results.read_probes(str(bare / "one.csv"))) == 1


def test_without_the_column_the_same_mix_is_caught_by_its_physics_only(mixed):
    """The control: the column alone names the mix. The same table without it (an older study's
    layout) is refused only because the two specimens' moduli break the state's reciprocity
    (row_checks), which a mix of two similar specimens need not do."""
    header, rows = _table(mixed / "probes.csv")
    k = header.index("specimen")
    _write(mixed / "probes.csv", header[:k] + header[k + 1:], [r[:k] + r[k + 1:] for r in rows])
    with pytest.raises(results.ResultsError, match="reciprocity") as info:
        results.read_probes(str(mixed))
    assert "specimen" not in str(info.value)


def _with_column(out, hashes):
    header, rows = _table(os.path.join(COMMITTED, "probes.csv"))
    _write(out / "probes.csv", header + ["specimen"], [r + [h] for r, h in zip(rows, hashes(len(rows)))])


def test_the_report_on_a_full_study_with_the_column(tmp_path):
    """The committed 39-state study reports as it is (no column), and with the column holding its
    own checksum; with another checksum in its second half it is refused at the first such line."""
    out = tmp_path / "study"
    out.mkdir()
    shutil.copy(os.path.join(COMMITTED, "metadata.json"), out)
    shutil.copy(os.path.join(COMMITTED, "probes.csv"), out)
    proc = _module("trueaniso.analysis.report", out)
    assert proc.returncode == 0, proc.stderr
    old = (out / "report" / "report.md").read_text()
    shutil.rmtree(out / "report")
    own, other = _own(out), "f" * 64
    _with_column(out, lambda n: [own] * n)
    proc = _module("trueaniso.analysis.report", out)
    assert proc.returncode == 0, proc.stderr
    assert (out / "report" / "report.md").read_text() == old  # the column changes no number
    shutil.rmtree(out / "report")
    _with_column(out, lambda n: [own] * (n // 2) + [other] * (n - n // 2))
    n = len(_table(out / "probes.csv")[1])
    one_line_error(_module("trueaniso.analysis.report", out), "line %d" % (n // 2 + 2), own, other)
    assert not (out / "report").exists()


def test_an_old_table_is_resumed_as_it_is(study_a, specimen_300, tmp_path):
    """A table whose header lacks the column keeps it: the row a resumed run appends has none, and
    every cell equals the new-format study's (wall times apart)."""
    out = tmp_path / "old"
    shutil.copytree(study_a, out)
    header, rows = _table(out / "probes.csv")
    k = header.index("specimen")
    _write(out / "probes.csv", header[:k] + header[k + 1:], [r[:k] + r[k + 1:] for r in rows[:1]])  # state 1 x lost
    proc = run_script("run_states.py", "--specimen", specimen_300, "--out", out, "--ids", "1", "--probes", "zx")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.count("probe x  E") == 1 and "probe z  E" not in proc.stdout
    header_old, rows_old = _table(out / "probes.csv")
    assert header_old == header[:k] + header[k + 1:]
    strip = lambda rs: [{c: v for c, v in r.items() if c not in WALL | {"specimen"}} for r in rs]  # noqa: E731
    assert strip(study.read_rows(str(out / "probes.csv"))) == strip(study.read_rows(str(study_a / "probes.csv")))
    assert len(results.read_probes(str(out))) == 2  # and read as before
