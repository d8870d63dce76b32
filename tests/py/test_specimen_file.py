"""Specimen files that must be refused: corrupt, wrong version, not a specimen."""
import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

from trueaniso import specimen, specimen_file


@pytest.fixture(scope="module")
def saved(tmp_path_factory):
    scene, log = specimen.prepare_spheres(100, seed=2, unbalanced=1e-2)
    path = tmp_path_factory.mktemp("spec") / "s.npz"
    specimen_file.save(str(path), scene, seed=2, parameters=log)
    return path


def test_truncated_file_is_refused(saved, tmp_path):
    bad = tmp_path / "bad.npz"
    data = saved.read_bytes()
    bad.write_bytes(data[: len(data) // 2])
    with pytest.raises(specimen_file.SpecimenFileError, match="corrupt"):
        specimen_file.load(str(bad))


def test_flipped_bytes_are_refused(saved, tmp_path):
    bad = tmp_path / "bad.npz"
    data = bytearray(saved.read_bytes())
    for k in range(2000, 2010):
        data[k] ^= 0xFF
    bad.write_bytes(bytes(data))
    with pytest.raises(specimen_file.SpecimenFileError, match="corrupt"):
        specimen_file.load(str(bad))


def _rewrite(src, dst, edit_meta=None, edit_arrays=None, reseal=False):
    """A copy of src with edited metadata or arrays; reseal recomputes the checksum, so that
    only the contents check can refuse the edited arrays."""
    with np.load(src) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("meta")))
    if edit_meta:
        edit_meta(meta)
    if edit_arrays:
        edit_arrays(arrays)
    if reseal:
        meta["sha256"] = specimen_file._checksum(arrays, meta)
    np.savez(dst, meta=np.array(json.dumps(meta)), **arrays)


def test_wrong_version_is_refused(saved, tmp_path):
    bad = tmp_path / "v9.npz"
    _rewrite(saved, bad, edit_meta=lambda m: m.update(format_version=9))
    with pytest.raises(specimen_file.SpecimenFileError, match="version 9"):
        specimen_file.load(str(bad))


def test_edited_array_fails_checksum(saved, tmp_path):
    bad = tmp_path / "edited.npz"

    def edit(a):
        a["radii"] = a["radii"] * 1.01
    _rewrite(saved, bad, edit_arrays=edit)
    with pytest.raises(specimen_file.SpecimenFileError, match="checksum"):
        specimen_file.load(str(bad))


def test_other_npz_is_refused(tmp_path):
    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(specimen_file.SpecimenFileError, match="not a trueaniso specimen"):
        specimen_file.load(str(other))


def test_missing_file_is_refused(tmp_path):
    with pytest.raises(specimen_file.SpecimenFileError, match="not found"):
        specimen_file.load(str(tmp_path / "none.npz"))


def test_what_is_not_a_specimen_file_is_named(tmp_path):
    """A directory, an empty file or a text file is named as what it is, not 'not found' or numpy's
    'Cannot load file containing pickled data when allow_pickle=False' (numpy reads what is no zip
    as a pickle)."""
    (tmp_path / "empty.npz").write_bytes(b"")
    (tmp_path / "text.npz").write_text("positions 1 2 3\n")
    for name, message in (("", "is a directory, not a specimen file"), ("empty.npz", "(.npz, a zip archive): it is empty"),
                          ("text.npz", "is not a specimen file (.npz, a zip archive)")):
        with pytest.raises(specimen_file.SpecimenFileError, match=re.escape(message)):
            specimen_file.read(str(tmp_path / name))


def test_save_replaces_atomically(saved, tmp_path):
    target = tmp_path / "t.npz"
    shutil.copy(saved, target)
    scene, _ = specimen_file.load(str(target))
    specimen_file.save(str(target), scene, seed=2)
    specimen_file.load(str(target))
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".tmp-")] == []


@pytest.mark.parametrize("edit,message", [
    (lambda a: a.update(radii=np.where(np.arange(a["radii"].size) == 3, 0.0, a["radii"])), "radius <= 0"),
    (lambda a: a.update(positions=a["positions"][:0], member_begin=a["member_begin"][:1]), "no bodies"),
    (lambda a: a.update(cell=a["cell"] * np.array([1.0, 0.0, 1.0])), "singular or inverted cell"),
    (lambda a: a.update(cell=a["cell"] * np.array([1.0, 1.0, -1.0])), "singular or inverted cell"),
    (lambda a: a.update(velocity_gradient=np.zeros(3)), "3x3"),
    (lambda a: a.update(positions=np.where(a["positions"] > 0, np.nan, a["positions"])), "non-finite"),
    (lambda a: a.update(c_member2=a["c_member2"] + 10**6), "out of range"),
])
def test_sealed_but_invalid_contents_are_refused(saved, tmp_path, edit, message):
    bad = tmp_path / "sealed.npz"
    _rewrite(saved, bad, edit_arrays=edit, reseal=True)
    with pytest.raises(specimen_file.SpecimenFileError, match=message):
        specimen_file.load(str(bad))


def test_script_refuses_invalid_specimen_in_one_line(saved, tmp_path):
    bad = tmp_path / "sealed.npz"
    _rewrite(saved, bad, edit_arrays=lambda a: a.update(radii=a["radii"] * 0.0), reseal=True)
    script = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                          "pyscripts", "run_states.py")
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, script, "--specimen", str(bad), "--ids", "1", "--out", str(out)],
                          capture_output=True, text=True, timeout=120)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and "radius <= 0" in lines[0], proc.stderr
    assert not out.exists()
