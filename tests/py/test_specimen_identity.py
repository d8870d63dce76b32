"""A specimen is what made it: its stored time step is the one its rules derive from its material
and radii (derived.time_step_problem), the recipe it names is the one its settings are
(derived.recipe_problem), and prepare_specimen.py keeps an existing file only when it was made with
the recipe asked and every setting of it. Edits here are resealed (the checksum recomputed), so
that only these checks can refuse them."""
import json
import os
import shutil

import numpy as np
import pytest
from conftest import REPO, one_line_error, run_script

from trueaniso import specimen_file

SPHERES = os.path.join(REPO, "tests", "data", "spheres-150-s4.npz")
CLUMPS = os.path.join(REPO, "tests", "data", "clump1-200-s4.npz")  # mu_prep 0, I 0.05, no unloading
# What the clump fixture was made with beyond the defaults (tests/data/README.md), as prepare_specimen.py
# takes them (its friction switched at the target: no unloading).
CLUMP_SETTINGS = ["--assembly", "clump1", "--n", "200", "--seed", "4", "--inertial-number", "0.05", "--mu-prep", "0",
                  "--switch-pressure", "100000"]


def _resealed(src, dst, edit):
    with np.load(src) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays.pop("meta")))
    edit(meta)
    meta["sha256"] = specimen_file._checksum(arrays, meta, specimen_file._names(meta))
    np.savez(dst, meta=np.array(json.dumps(meta)), **arrays)
    return dst


@pytest.mark.parametrize("edit,field", [
    (lambda m: m.update(reference_dt=1000 * m["dt"]), "reference_dt"),
    (lambda m: m.update(dt=1000 * m["dt"]), "dt"),
    (lambda m: m.update(dt=0.5 * m["dt"]), "dt"),
])
def test_an_edited_time_step_is_refused(tmp_path, edit, field):
    """reference_dt set 1000 times too large (checksum recomputed) ran state 21 to E_z 174.1 MPa
    instead of 183.2 without a word."""
    bad = _resealed(SPHERES, tmp_path / "bad.npz", edit)
    with pytest.raises(specimen_file.SpecimenFileError, match="%s: .* time step rule" % field):
        specimen_file.load(str(bad))
    proc = run_script("run_states.py", "--specimen", bad, "--ids", "21", "--out", tmp_path / "study", timeout=300)
    one_line_error(proc, "bad.npz", field, "the stored step was edited")
    assert not (tmp_path / "study").exists()


def test_the_committed_specimens_keep_their_time_steps():
    """The control: every committed specimen (spheres and clumps, a state's checkpoint) loads."""
    for name in sorted(os.listdir(os.path.join(REPO, "tests", "data"))):
        if name.endswith(".npz"):
            specimen_file.load(os.path.join(REPO, "tests", "data", name))


def test_a_scene_saved_from_elsewhere_keeps_its_own_step(tmp_path):
    """A file that names no preparation (a YADE scene, saved through the bridge) stores its host's
    dt, which the chain replaces at its first step: not held to a rule."""
    other = _resealed(SPHERES, tmp_path / "yade.npz", lambda m: m.update(parameters={}, dt=0.37 * m["dt"]))
    specimen_file.load(str(other))


@pytest.mark.parametrize("edit,words", [
    (lambda m: m["parameters"].update(recipe="fast-growth"), "fast-growth sets gain = 0.1, but parameters.gain is 0.002"),
    (lambda m: m["parameters"].update(recipe="frictionless"), "clump1 has no recipe variant 'frictionless'"),
])
def test_a_recipe_name_and_its_settings_cannot_disagree(tmp_path, edit, words):
    """A file recorded recipe 'frictionless' with mu_prep 0.3."""
    bad = _resealed(CLUMPS, tmp_path / "bad.npz", edit)
    with pytest.raises(specimen_file.SpecimenFileError, match="parameters.recipe") as info:
        specimen_file.read(str(bad))
    assert words in str(info.value)


def test_an_option_that_contradicts_the_recipe_is_refused(tmp_path):
    proc = run_script("prepare_specimen.py", "--assembly", "clump2", "--n", "200", "--recipe", "frictionless",
                      "--mu-prep", "0.3", "--out", tmp_path / "c.npz")
    one_line_error(proc, "--mu-prep 0.3 contradicts --recipe frictionless", "mu_prep = 0")
    assert not (tmp_path / "c.npz").exists()


@pytest.mark.parametrize("recipe,words", [("fast-growth", ["recipe:", "fast-growth", "gain: 0.002 there, 0.1 here"]),
                                          ("hold-deviator", ["recipe:", "hold-deviator", "hold_deviator"])])
def test_a_kept_specimen_of_another_recipe_is_refused(tmp_path, recipe, words):
    """prepare_specimen.py kept a file made with another --recipe ('kept existing specimen', exit 0),
    though the checkpoint check catches the same swap. The fixture is the quick recipe's dimers
    labelled clump1, which no command makes: without --recipe it is refused by the recipe settings it
    records (shape, orientations, stages), and with one the refusal names the recipe too."""
    out = tmp_path / "c.npz"
    shutil.copy(CLUMPS, out)
    proc = run_script("prepare_specimen.py", *CLUMP_SETTINGS, "--out", out)
    one_line_error(proc, "prepared with other settings", "shape: \"dimer-1.5\" there, \"pentamer-2.0\" here")
    assert "recipe:" not in proc.stderr  # the control: the name alone is not what differs there
    before = out.read_bytes()
    proc = run_script("prepare_specimen.py", *CLUMP_SETTINGS, "--recipe", recipe, "--out", out)
    one_line_error(proc, "prepared with other settings", *words)
    assert out.read_bytes() == before
