"""Specimen files: the checksum covers the whole content, metadata included; every field is
validated on load with one clear line; a specimen never stays without its .json summary; rotation
blocking cannot mislabel rows. A comment on a case says what the edit would do if accepted."""
import json
import os
import shutil

import numpy as np
import pytest
from conftest import one_line_error, run_script
from test_specimen_file import _rewrite

from trueaniso import specimen_file


def nan_at_first(name):
    def edit(a):
        a[name] = a[name].astype(float).copy()
        a[name].flat[0] = np.nan
    return edit


@pytest.mark.parametrize("edit_meta", [
    lambda m: m["material"].update(shear_modulus=28e9),  # accepted, E would move by 15 %
    lambda m: m.update(block_rotations=True),  # rows labelled rotations=free, the blocked answer
    lambda m: m.update(dt=m["dt"] * 2),
    lambda m: m["parameters"].update(n=5000),
], ids=["shear_modulus", "block_rotations", "dt", "parameters"])
def test_edited_metadata_fails_the_checksum(specimen_100, tmp_path, edit_meta):
    bad = tmp_path / "edited.npz"
    _rewrite(specimen_100, bad, edit_meta=edit_meta)
    with pytest.raises(specimen_file.SpecimenFileError, match="checksum mismatch"):
        specimen_file.load(str(bad))


def _pop_material(m):
    del m["material"]


def _duplicate_body(a):
    a["positions"] = a["positions"].copy()
    a["positions"][1] = a["positions"][0]


def _self_contact(a):
    a["c_member2"] = a["c_member2"].copy()
    a["c_member2"][0] = a["c_member1"][0]


def _huge_shift(a):
    a["c_shift"] = a["c_shift"].copy()
    a["c_shift"][0] += 1000


@pytest.mark.parametrize("edit_meta,edit_arrays,message", [
    (_pop_material, None, "material: missing"),  # not a KeyError traceback
    (lambda m: m["material"].update(poisson=float("nan")), None, "material.poisson"),
    (lambda m: m.update(dt=float("nan")), None, "dt: must be a finite number"),  # the field at fault named
    (lambda m: m.update(block_rotations="yes"), None, "block_rotations: must be true or false"),
    (None, nan_at_first("velocity_gradient"), "velocity_gradient: non-finite values"),  # not mid-run
    (None, lambda a: a.update(cell=a["cell"] @ np.diag([1.0, 1.0, -1.0])), "singular or inverted cell"),
    (None, nan_at_first("c_normal"), "c_normal: non-finite values"),  # not mid-run
    (None, _duplicate_body, "duplicate bodies"),  # not mid-run with another reason
    (None, _self_contact, "with itself"),  # not silently replaced
    (None, _huge_shift, "do not touch"),  # not silently replaced
])
def test_sealed_but_invalid_fields_are_refused(specimen_100, tmp_path, edit_meta, edit_arrays, message):
    """Fields that pass the checksum (resealed by whoever edited them) are validated one by one."""
    bad = tmp_path / "sealed.npz"
    _rewrite(specimen_100, bad, edit_meta=edit_meta, edit_arrays=edit_arrays, reseal=True)
    with pytest.raises(specimen_file.SpecimenFileError, match=message):
        specimen_file.load(str(bad))


def test_scripts_refuse_a_bad_specimen_in_one_line_before_work(specimen_100, tmp_path):
    bad = tmp_path / "sealed.npz"
    _rewrite(specimen_100, bad, edit_meta=_pop_material, reseal=True)
    out = tmp_path / "out"
    one_line_error(run_script("run_states.py", "--specimen", bad, "--ids", "1", "--out", out), "material")
    assert not out.exists()


def test_version_1_files_are_refused_with_the_way_out(specimen_100, tmp_path):
    old = tmp_path / "v1.npz"
    _rewrite(specimen_100, old, edit_meta=lambda m: m.update(format_version=1))
    with pytest.raises(specimen_file.SpecimenFileError, match="version-1 .* prepare the specimen again"):
        specimen_file.load(str(old))


def test_missing_summary_and_stray_temporaries_are_repaired(specimen_100, tmp_path):
    """A kill between the .npz and .json renames leaves the specimen without its .json and the
    .tmp-* files of the killed run behind: the next run writes the summary and removes them."""
    spec = tmp_path / "s.npz"
    shutil.copy(specimen_100, spec)
    strays = [tmp_path / ".tmp-k2j4-s.npz", tmp_path / ".tmp-x9a1-s.json"]
    for p in strays:
        p.write_bytes(b"half written")
    other = tmp_path / ".tmp-zz-other.npz"  # another output's temporary: not this run's to remove
    other.write_bytes(b"busy")
    proc = run_script("prepare_specimen.py", "--n", "100", "--seed", "3", "--out", spec)
    assert proc.returncode == 0, proc.stderr
    assert "kept existing specimen" in proc.stdout and "wrote the missing summary" in proc.stdout
    summary = json.loads((tmp_path / "s.json").read_text())
    assert summary["sha256"] == specimen_file.read(str(spec))[1]["sha256"]
    assert not any(p.exists() for p in strays) and other.exists()


def test_specimen_that_blocks_rotations_cannot_give_free_rows(specimen_100, tmp_path):
    scene, meta = specimen_file.load(str(specimen_100))
    scene.block_rotations = True
    blocked = tmp_path / "blocked.npz"
    specimen_file.save(str(blocked), scene, seed=3, parameters=meta["parameters"])
    out = tmp_path / "out"
    one_line_error(run_script("run_states.py", "--specimen", blocked, "--ids", "1", "--out", out),
                   "blocks rotations", "--rotations restrained")
    assert not out.exists()


def test_save_refuses_what_load_would_refuse(specimen_100, tmp_path):
    scene, meta = specimen_file.load(str(specimen_100))
    with pytest.raises(specimen_file.SpecimenFileError, match="seed: must be an integer >= 0"):
        specimen_file.save(str(tmp_path / "x.npz"), scene, seed=-1, parameters=meta["parameters"])
    assert not os.path.exists(tmp_path / "x.npz")


def test_version_2_files_are_read_as_diagonal_cells(specimen_100, tmp_path):
    """Version 2 stored an orthorhombic cell as edge lengths (cell_size, cell_ref_size,
    strain_rate); such a file, its checksum verified over those arrays, loads with the diagonal
    matrices. Written here from a current file by renaming (the specimen's tiny shear dropped; the
    volumes of version 4 dropped), and edited afterwards it fails the checksum as any file does."""
    with np.load(specimen_100) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("meta")))
    del arrays["volumes"]
    diag = {"cell": "cell_size", "cell_ref": "cell_ref_size", "velocity_gradient": "strain_rate"}
    for new, old in diag.items():
        arrays[old] = np.diag(arrays.pop(new)).copy()
    meta["format_version"] = 2
    meta["sha256"] = specimen_file._checksum(arrays, meta, specimen_file._ARRAYS_V2)
    v2 = tmp_path / "v2.npz"
    np.savez(v2, meta=np.array(json.dumps(meta)), **arrays)
    scene, loaded = specimen_file.load(str(v2))
    assert loaded["format_version"] == 2
    np.testing.assert_array_equal(scene.cell, np.diag(arrays["cell_size"]))
    np.testing.assert_array_equal(scene.cell_ref, np.diag(arrays["cell_ref_size"]))
    assert scene.orthorhombic
    arrays["cell_size"] = arrays["cell_size"] * 1.001
    np.savez(v2, meta=np.array(json.dumps(meta)), **arrays)
    with pytest.raises(specimen_file.SpecimenFileError, match="checksum mismatch"):
        specimen_file.load(str(v2))
