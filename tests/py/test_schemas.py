"""One schema per file trueaniso reads (pyscripts/trueaniso/schemas, trueaniso/validate.py): a file
that parses but has the wrong shape is refused in one line naming the file and the field, never
with a traceback: each case is a file that parses (JSON, npz, CSV) but would otherwise reach the
code that uses it as a value of the wrong kind, where it fails as a TypeError or AttributeError
far from the file."""
import json
import os
import shutil

import numpy as np
import pytest
from conftest import REPO, one_line_error, run_script
from test_specimen_file import _rewrite

from trueaniso import param_table, specimen_file, validate


def test_every_schema_is_valid_draft7_and_every_property_has_a_description():
    """The manual's reference pages are made from the schemas: a property without words is a gap
    there (and a schema that is not valid JSON Schema checks nothing)."""
    import jsonschema

    def walk(node, where):
        if isinstance(node, dict):
            for name, sub in (node.get("properties") or {}).items():
                assert "description" in sub, "%s.%s has no description" % (where, name)
            for k, v in node.items():
                walk(v, "%s.%s" % (where, k))
        elif isinstance(node, list):
            for k, v in enumerate(node):
                walk(v, "%s[%d]" % (where, k))
    for name in validate.NAMES:
        s = validate.schema(name)
        jsonschema.Draft7Validator.check_schema(s)
        assert s.get("description"), name
        walk(s, name)
    arrays = validate.schema("specimen_arrays")["arrays"]
    assert all(spec.get("description") and spec["kind"] in ("float", "int") for spec in arrays.values())
    # every array a specimen file holds is in the table
    assert set(specimen_file._ARRAYS) | set(specimen_file._ARRAYS_V2) | {specimen_file._ROLLING} <= set(arrays)


def test_a_number_is_finite_and_not_a_boolean():
    assert validate.problem({"E_kinematic": [1.0, 2.0, 3.0], "E_blocked": [1, 2, 3]}, "statics_record") is None
    for bad in (float("nan"), float("inf"), True, "1"):
        field, what = validate.problem({"E_kinematic": [1.0, bad, 3.0], "E_blocked": [1, 2, 3]}, "statics_record")
        assert field == "E_kinematic.1" and what.startswith("must be a finite number > 0"), (bad, field, what)


def _meta_of(path):
    with np.load(path) as z:
        return json.loads(str(z["meta"]))


@pytest.mark.parametrize("edit,field", [
    (lambda m: m.update(material=None), "material"),  # refused by the schema, not a TypeError in the material check
    (lambda m: m.update(material=["G", 1]), "material"),
    (lambda m: m["material"].update(density="2650"), "material.density"),  # a string where a number belongs
    (lambda m: m.update(step=1.5), "step"),
    (lambda m: m.update(parameters="none"), "parameters"),
    (lambda m: m.update(parameters=dict(assembly=5)), "parameters.assembly"),
    (lambda m: m.pop("created"), "created"),
])
def test_specimen_metadata_of_the_wrong_shape_is_refused_naming_the_field(specimen_100, tmp_path, edit, field):
    bad = tmp_path / "bad.npz"
    _rewrite(specimen_100, bad, edit_meta=edit, reseal=True)
    with pytest.raises(specimen_file.SpecimenFileError) as exc:
        specimen_file.read(str(bad))
    assert str(exc.value).startswith("%s: %s: " % (bad, field)), str(exc.value)


def test_specimen_metadata_that_is_a_list_is_refused(specimen_100, tmp_path):
    """Metadata that is valid JSON but not an object is refused as the file's whole metadata, in one
    line from the library and from a script (not an AttributeError on the list)."""
    with np.load(specimen_100) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["meta"] = np.array(json.dumps([1, 2]))
    bad = tmp_path / "list.npz"
    np.savez(bad, **arrays)
    with pytest.raises(specimen_file.SpecimenFileError, match="metadata: must be a table"):
        specimen_file.read(str(bad))
    out = tmp_path / "out"
    one_line_error(run_script("run_states.py", "--specimen", bad, "--ids", "1", "--out", out), str(bad), "metadata")


@pytest.mark.parametrize("edit,words", [
    # the kind of number is checked before any array is used as an index (a float member_begin
    # would fail as a TypeError inside the contents check)
    (lambda a: a.update(member_begin=a["member_begin"].astype(float)), "member_begin: must hold integers, not float64"),
    (lambda a: a.update(c_shift=a["c_shift"].astype(float)), "c_shift: must hold integers"),
    (lambda a: a.update(radii=a["radii"][:-1]), "radii: has shape"),
    (lambda a: a.update(masses=a["masses"].astype(np.float32) * np.nan), "masses: non-finite values"),
    (lambda a: a.update(orientations=a["orientations"][:, :3]), "orientations: has shape"),
])
def test_arrays_are_checked_against_their_table(specimen_100, tmp_path, edit, words):
    bad = tmp_path / "bad.npz"
    _rewrite(specimen_100, bad, edit_arrays=edit, reseal=True)
    with pytest.raises(specimen_file.SpecimenFileError) as exc:
        specimen_file.read(str(bad))
    assert str(exc.value).startswith(str(bad) + ": ") and words in str(exc.value), str(exc.value)


def _study(tmp_path, specimen, edit):
    """A study directory whose metadata.json (copied from a committed study) is edited."""
    out = tmp_path / "study"
    out.mkdir()
    meta = json.loads(open(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "metadata.json")).read())
    edit(meta)
    (out / "metadata.json").write_text(json.dumps(meta))
    return out


@pytest.mark.parametrize("edit,field", [
    (lambda m: m.update(states=[1, 2]), "states"),  # a list where a table of states belongs
    (lambda m: m["states"]["5"].update(sigma_z="high"), "states.5.sigma_z"),
    (lambda m: m.update(fingerprint=None), "fingerprint"),
    (lambda m: m["fingerprint"].update(threads=1.5), "fingerprint.threads"),
    (lambda m: m["fingerprint"].pop("specimen"), "fingerprint.specimen"),
])
def test_study_metadata_of_the_wrong_shape_is_refused_by_the_scripts(specimen_100, tmp_path, edit, field):
    out = _study(tmp_path, specimen_100, edit)
    line = one_line_error(run_script("run_states.py", "--specimen", specimen_100, "--ids", "1", "--out", out),
                          "metadata.json: %s: " % field)
    assert "--force-new" in line
    if field == "fingerprint.specimen":  # the analysis takes every field as optional, typed
        return
    shutil.copy(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "probes.csv"), out / "probes.csv")
    from trueaniso.analysis import results
    with pytest.raises(results.ResultsError, match="metadata.json: %s: " % field.replace(".", r"\.")):
        results.read_metadata(str(out))


def test_study_metadata_that_is_a_list_is_refused_by_the_report(tmp_path):
    """trueaniso.analysis.report reads metadata.json through its schema: a file that is a list is one line
    naming the file, not an AttributeError traceback."""
    import subprocess
    import sys
    out = tmp_path / "study"
    out.mkdir()
    shutil.copy(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "probes.csv"), out / "probes.csv")
    (out / "metadata.json").write_text("[]")
    proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", str(out)], capture_output=True, text=True,
                          cwd=REPO, timeout=120)
    one_line_error(proc, "metadata.json: (whole file): must be a table")


@pytest.mark.parametrize("cell,column,what", [
    ("E", "probe", "must be one of"),  # an unknown probe axis
    ("abc", "sigma_x", "must be a finite number"),  # a text where a number belongs
    ("1.5", "probe_steps", "must be an integer"),
])
def test_probe_table_cells_of_the_wrong_type_are_refused_naming_line_and_column(tmp_path, cell, column, what):
    from trueaniso.analysis import results
    src = os.path.join(REPO, "docs", "data", "table-c1-spheres-4000.csv")
    lines = open(src).read().splitlines()
    head = lines[0].split(",")
    row = lines[3].split(",")
    row[head.index(column)] = cell
    lines[3] = ",".join(row)
    path = tmp_path / "t.csv"
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(results.ResultsError) as exc:
        results.read_probes(str(path), need=("state", "probe"))
    assert "line 4: %s: %s" % (column, what) in str(exc.value), str(exc.value)


def test_a_parameter_table_value_of_the_wrong_kind_is_refused(tmp_path):
    """A table value that YADE evaluates to a dict is refused naming the line and the column: it
    would otherwise go on to argparse as the text '--out={'a': 1}'. 'inf' stays a value."""
    table = tmp_path / "t.txt"
    table.write_text("ids out\n'1' {'a':1}\n'1' inf\n")
    with pytest.raises(param_table.InputError, match="line 2: column out: must be"):
        param_table.read_line(str(table), 2)
    assert param_table.read_line(str(table), 3)["out"] == float("inf")  # --path-rate inf is a table's value too
    out = tmp_path / "o"
    one_line_error(run_script("run_states.py", "--table", table, "--line", "2", "--specimen", "x.npz"),
                   "column out")
    assert not out.exists()


def test_a_statics_record_of_the_wrong_shape_is_refused_by_the_report(tmp_path):
    """Table B1 reads each statics record through its schema: too few moduli, or a file that is a
    list, is refused naming the file and the field (not a TypeError or KeyError in the table)."""
    from trueaniso.analysis import chain, report
    from trueaniso.analysis.results import ResultsError
    (tmp_path / "statics_isotropic.json").write_text(json.dumps({"E_kinematic": [1, 2], "E_blocked": [1, 2, 3]}))
    with pytest.raises(ResultsError, match="statics_isotropic.json: E_kinematic: must have at least 3 items"):
        report.table_b1(str(tmp_path), chain.PAPER["spheres"])
    (tmp_path / "statics_isotropic.json").write_text("[]")
    with pytest.raises(ResultsError, match="must be a table"):
        report.table_b1(str(tmp_path), chain.PAPER["spheres"])


@pytest.mark.parametrize("name,source,edit,words", [
    # a text where a number belongs is refused by the schema, before the Fig. 16 section formats it
    ("fig16.json", "fig16-spheres-4000.json", lambda rows: rows[1].update(sigma_v="50e3"), "1.sigma_v: must be"),
    ("fig16.json", "fig16-spheres-4000.json", lambda rows: rows[0].update(nu_ratio=[1]), "0.nu_ratio: must be"),
    ("clumps.json", "anisotropy-clumps-4000.json", lambda rows: rows[0].update(probe_restrained=[1e8, 1e8]),
     "0.probe_restrained: must have at least 3 items"),
    ("clumps.json", "anisotropy-clumps-4000.json", lambda rows: rows[1].update(n="4000"), "1.n: must be an integer"),
])
def test_the_report_s_optional_json_inputs_are_checked_by_their_schemas(tmp_path, name, source, edit, words):
    from trueaniso.analysis import report
    from trueaniso.analysis.results import ResultsError
    rows = json.loads(open(os.path.join(REPO, "docs", "data", source)).read())
    read = report.fig16_rows if name == "fig16.json" else report.clump_entries
    assert read(os.path.join(REPO, "docs", "data", source))  # the committed files fit
    edit(rows)
    path = tmp_path / name
    path.write_text(json.dumps(rows))
    with pytest.raises(ResultsError) as exc:
        read(str(path))
    assert str(exc.value).startswith("%s: %s" % (path, words)), str(exc.value)
