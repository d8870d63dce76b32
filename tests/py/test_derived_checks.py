"""Every file the analysis reads is checked for what it implies, not only for its schema: a probe
table's rows against their state's definition (Eq. 9) and the physics of an elastic packing
(analysis/row_checks.py, trueaniso/elastic_bounds.py), state ids normalised where a table is read,
a study whose metadata.json cannot be read refused, and Table B1's statics records tied to their
study (analysis/b1_checks.py). The cases are edits of the committed studies of docs/data."""
import csv
import glob
import json
import os
import shutil
import subprocess
import sys

import pytest
from conftest import REPO, one_line_error

from trueaniso import elastic_bounds, stress_states
from trueaniso.analysis import b1_checks, report, results, row_checks

DATA = os.path.join(REPO, "docs", "data")
SPHERES = os.path.join(DATA, "spheres-4000-s1")  # metadata.json, probes.csv, statics records of states 1, 21
ENV = dict(os.environ, OMP_NUM_THREADS="1")


def _report(*args):
    return subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", *map(str, args)], cwd=REPO,
                          capture_output=True, text=True, env=ENV, timeout=600)


def _copy(src, tmp_path, name=None):
    out = tmp_path / (name or os.path.basename(src))
    shutil.copytree(src, out)
    return out


def _edit_table(path, edit):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    rows = edit(rows)
    with open(path, "w", newline="") as f:
        csv.writer(f, lineterminator="\n").writerows(rows)


def _swap(a, b):
    def edit(rows):
        h = rows[0]
        i, j = h.index(a), h.index(b)
        h[i], h[j] = h[j], h[i]
        return rows
    return edit


def _scale(column, factor):
    def edit(rows):
        k = rows[0].index(column)
        for r in rows[1:]:
            if r[k]:
                r[k] = repr(float(r[k]) * factor)
        return rows
    return edit


# ---------------------------------------------------------------- the formulas against independent values

def test_eq9_in_python_is_the_engines():
    """stress_states.principal_stresses (the readers' Eq. 9) against the engines' C++ Eq. 9 and
    against Table C1 as printed (0.1 kPa)."""
    from trueaniso import engines
    for sid, sx, sy, sz, _ in stress_states.TABLE_C1:
        b = dict((i, b) for i, b, _ in stress_states.table_c1_states())[sid]
        ours = stress_states.principal_stresses(b, sz * 1e3)
        assert ours == pytest.approx(engines.true_triaxial_stresses(b, sz * 1e3, 100e3), rel=1e-14)
        assert ours == pytest.approx((sx * 1e3, sy * 1e3, sz * 1e3), abs=51.0)


def test_the_modulus_scale_is_the_simple_cubic_packing_s():
    """406.7 MPa at 100 kPa for the paper's particles (docs/departures.md, Table B1 Sphere*)."""
    assert elastic_bounds.simple_cubic_modulus(18e9, 0.15, 100e3) == pytest.approx(406.7e6, abs=0.05e6)


def test_an_isotropic_solid_passes_and_a_broken_one_does_not():
    E = dict(x=300e6, y=300e6, z=300e6)
    nu = {(a, b): 0.2 for a in "xyz" for b in "xyz" if a != b}
    assert elastic_bounds.compliance_problem(E, nu) is None
    assert "reciprocity" in elastic_bounds.compliance_problem(dict(E, x=350e6), nu)
    assert "positive definite" in elastic_bounds.compliance_problem(E, {k: 0.6 for k in nu})


def test_every_committed_probe_table_passes():
    """The bounds hold every measured table (else they refuse what a study writes)."""
    tables = [f for f in glob.glob(os.path.join(DATA, "**", "*.csv"), recursive=True)
              if "probe" in open(f).readline().split(",")]
    assert len(tables) >= 10
    for f in tables:
        assert results.read_probes(f, need=("state", "probe"))


# ---------------------------------------------------------------- probe tables

@pytest.mark.parametrize("edit,words", [
    (_swap("sigma_x", "sigma_z"), ("line 5", "state 6 probe z", "sigma_x", "Eq. (9)")),
    (_swap("E", "gamma"), ("line 2", "state 1 probe z", "gamma")),
    (_scale("E", 1e6), ("line 2", "E = 3.09585e+14", "simple cubic")),
    (_swap("nu_1", "nu_2"), ("state 8", "reciprocity")),
])
def test_an_edited_probe_table_is_refused_by_the_report(tmp_path, edit, words):
    """Two headers swapped, a column scaled: the report gave K = 136,171,562 MPa and exit 0."""
    out = _copy(SPHERES, tmp_path)
    _edit_table(out / "probes.csv", edit)
    proc = _report(out, "--out", tmp_path / "report")
    one_line_error(proc, "probes.csv", *words)
    assert not (tmp_path / "report").exists()


def test_a_scaled_shear_column_is_refused(tmp_path):
    out = _copy(os.path.join(DATA, "fig16-spheres-4000-s1"), tmp_path)
    _edit_table(out / "probes.csv", _scale("G", 1e6))
    with pytest.raises(results.ResultsError, match=r"probe yz\): G = .* simple cubic"):
        results.read_probes(str(out), need=("state", "probe"))


def test_a_row_under_another_state_s_id_is_refused(tmp_path):
    """Rows of a table without metadata.json: the id 21 is defined by Table C1 itself."""
    table = tmp_path / "t.csv"
    shutil.copy(os.path.join(DATA, "table-c1-spheres-4000.csv"), table)

    def edit(rows):
        rows = [r for r in rows if r[0] != "21"]
        for r in rows[1:]:
            if r[0] == "5":
                r[0] = "21"
        return rows
    _edit_table(table, edit)
    with pytest.raises(results.ResultsError, match="state 21 is defined with b = 0.5"):
        results.read_probes(str(table))


def test_a_state_id_is_normalised_where_it_is_read(tmp_path):
    """'21.0' (a spreadsheet's) is state 21 for every reader: the report counted the row, then said
    that state 21 had none."""
    out = _copy(SPHERES, tmp_path)

    def edit(rows):
        for r in rows[1:]:
            if r[1] == "21":
                r[1] = "21.0"
        return rows
    _edit_table(out / "probes.csv", edit)
    rows = results.read_probes(str(out))
    assert "21" in {r["state"] for r in rows} and "21.0" not in {r["state"] for r in rows}
    assert report._missing_states_line(str(out), rows) is None


@pytest.mark.parametrize("text", ["", "{\"fingerprint\": {\"assembly\": \"clump1\"", "not json"])
def test_a_study_whose_metadata_cannot_be_read_is_refused(tmp_path, text):
    """A clump1 study with metadata.json empty, truncated or corrupt was reported as spheres, against
    the paper's spheres, with exit 0; run_states.py refuses the same directory."""
    out = _copy(os.path.join(DATA, "clump1-4000-s1"), tmp_path)
    (out / "metadata.json").write_text(text)
    proc = _report(out)
    one_line_error(proc, "metadata.json", "unreadable")
    assert not (out / "report").exists()


# ---------------------------------------------------------------- Table B1's records

def _record(directory, sid):
    with open(os.path.join(directory, "statics_state-%s.json" % sid)) as f:
        return json.load(f)


def _write_record(directory, sid, rec):
    with open(os.path.join(directory, "statics_state-%s.json" % sid), "w") as f:
        json.dump(rec, f)


def test_records_of_two_states_swapped_are_refused(tmp_path):
    """Table B1 showed a 'state 21' at (100, 100, 100) kPa."""
    out = _copy(SPHERES, tmp_path)
    one, two = _record(out, "1"), _record(out, "21")
    _write_record(out, "1", two)
    _write_record(out, "21", one)
    with pytest.raises(results.ResultsError, match=r"statics_state-1.json: sigma\[y\] = 60075.6 Pa, but state 1"):
        report.b1_records(str(out))


def test_a_record_of_another_study_is_refused(tmp_path):
    """A record without identity (an older one) is tied by its stresses to its state's row: one of
    another study (the 53,004-sphere study's state 21 in the 4000-sphere study) is not its row."""
    out = _copy(SPHERES, tmp_path)
    other = _record(os.path.join(DATA, "spheres-53004-s1"), "21")
    del other["study"]  # its identity, which an older record lacks (with it, the identity refuses it first)
    _write_record(out, "21", other)
    with pytest.raises(results.ResultsError, match="not those of state 21's row of probes.csv"):
        report.b1_records(str(out))


def test_a_borrowed_record_of_another_study_is_refused(tmp_path):
    """A 1000-clump record (with its identity) in the 4000-clump directory given to --b1-data was
    labelled 4000 clumps."""
    borrowed = _copy(os.path.join(DATA, "b1-clump2-4000-s1"), tmp_path)
    _write_record(borrowed, "21", _record(os.path.join(DATA, "b1-clump2-1000-s1"), "21"))
    proc = _report(os.path.join(DATA, "clump2-4000-s1"), "--b1-data", borrowed, "--out", tmp_path / "report")
    one_line_error(proc, "statics_state-21.json", "study.specimen", "a record of another study")
    assert not (tmp_path / "report").exists()


def test_a_modulus_no_packing_has_is_refused(tmp_path):
    out = _copy(SPHERES, tmp_path)
    rec = _record(out, "21")
    rec["E_blocked"][0] = 1e30
    _write_record(out, "21", rec)
    with pytest.raises(results.ResultsError, match=r"E_blocked\[x\] = 1e\+30 Pa"):
        report.b1_records(str(out))


def _other_material(tmp_path):
    """b1-clump2-1000-s1 as a study of particles of twice the shear modulus (its metadata and its
    records' identity both say so: a consistent study of another material)."""
    out = _copy(os.path.join(DATA, "b1-clump2-1000-s1"), tmp_path, "stiffer")
    meta = json.loads((out / "metadata.json").read_text())
    meta["specimen"]["material"]["shear_modulus"] *= 2
    (out / "metadata.json").write_text(json.dumps(meta))
    for sid in ("1", "21"):
        rec = _record(out, sid)
        rec["study"]["material"]["shear_modulus"] *= 2
        _write_record(out, sid, rec)
    return out


def test_a_borrowed_study_of_another_material_is_refused_or_marked(tmp_path):
    other = _other_material(tmp_path)
    study = os.path.join(DATA, "clump2-4000-s1")
    proc = _report(study, "--b1-data", other, "--out", tmp_path / "refused")
    one_line_error(proc, "stiffer", "G = 3.6e+10 Pa", "--b1-other-material")
    assert not (tmp_path / "refused").exists()
    proc = _report(study, "--b1-data", other, "--b1-other-material", "--out", tmp_path / "marked")
    assert proc.returncode == 0, proc.stderr
    text = (tmp_path / "marked" / "report.md").read_text()
    assert "other material: G = 36 GPa" in text and "another material" in text


def test_the_committed_records_pass():
    """The control: every committed study's records are its own."""
    for d in ("spheres-4000-s1", "spheres-53004-s1", "clump1-4000-s1", "clump2-4000-s1", "b1-clump2-4000-s1",
              "b1-clump2-1000-s1", "clump1-2000/s1", "clump1-2000/s2", "clump1-2000/s3", "clump2-2000/s1",
              "clump2-2000/s2", "clump2-2000/s3", "clump1-4000/s1", "clump2-4000/s1"):
        assert report.b1_records(os.path.join(DATA, d))


def test_row_checks_name_the_file_line_and_field():
    """One line: the file (added by read_probes), the line, the state and probe, the field."""
    row = dict(state="21", probe="z", b="0.5", sigma_z_goal="140000.0", sigma_x="60000", sigma_y="100000",
               sigma_z="140000", gamma="1e-6", E="3e8")
    problem = row_checks.row_problem(7, row, results.PAPER_MATERIAL)
    assert problem.startswith("line 7 (state 21 probe z): sigma_x = 60000 Pa")


def test_a_record_s_identity_is_checked_field_by_field():
    rec = _record(os.path.join(DATA, "b1-clump2-1000-s1"), "21")
    meta = json.load(open(os.path.join(DATA, "b1-clump2-1000-s1", "metadata.json")))
    path = os.path.join(DATA, "b1-clump2-1000-s1", "statics_state-21.json")
    assert b1_checks.record_problem(path, "21", rec, os.path.dirname(path), meta) is None
    for field, value, words in (("n", 300, "study.n = 300"), ("state", dict(id="5"), "record of state 5")):
        changed = dict(rec, study=dict(rec["study"], **{field: value}))
        assert words in b1_checks.record_problem(path, "21", changed, os.path.dirname(path), meta)
