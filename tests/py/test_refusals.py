"""Refusals that write nothing, resources before work, I/O errors mid-run as one line, derived
quantities of a clump specimen, and a packing far beyond the study's stresses refused before
stepping. Each docstring says what the check guards against: a traceback, a file written by a
run that is then refused, work spent before a refusal, or a wrong number given without a word."""
import errno
import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from conftest import REPO, SCRIPTS, one_line_error, run_script
from test_specimen_file import _rewrite

from trueaniso import clump_shapes, engines, specimen_file


def _far_contact(a):
    """A contact whose members do not touch: the file reads (its arrays are consistent), its load
    refuses (specimen_file.contacts_problem)."""
    a["c_shift"] = a["c_shift"].copy()
    a["c_shift"][0] += 1000


def test_a_refused_run_into_a_new_out_leaves_nothing_behind(specimen_100, tmp_path):
    """A specimen refused when it is loaded leaves no metadata.json and no states/ in the new
    results directory: left there, they would make the next correct run into it refused as
    'another study'."""
    bad = tmp_path / "bad.npz"
    _rewrite(specimen_100, bad, edit_arrays=_far_contact, reseal=True)
    out = tmp_path / "out"
    one_line_error(run_script("run_states.py", "--specimen", bad, "--ids", "1", "--probes", "z", "--out", out),
                   "do not touch")
    assert not (out / "metadata.json").exists() and not (out / "states").exists()


def test_force_new_moves_the_old_study_aside_only_after_the_new_inputs_passed(specimen_100, tmp_path):
    """--force-new with a specimen that is refused leaves the old study in place: it is moved into
    superseded/ only once the new inputs passed."""
    out = tmp_path / "out"
    (out / "states").mkdir(parents=True)
    shutil.copy(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "metadata.json"), out / "metadata.json")
    shutil.copy(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "probes.csv"), out / "probes.csv")
    bad = tmp_path / "bad.npz"
    _rewrite(specimen_100, bad, edit_arrays=_far_contact, reseal=True)
    one_line_error(run_script("run_states.py", "--specimen", bad, "--ids", "1", "--probes", "z", "--out", out,
                              "--force-new"), "do not touch")
    assert (out / "metadata.json").exists() and (out / "probes.csv").exists() and not (out / "superseded").exists()


def test_a_study_that_fails_before_saving_anything_is_undone(specimen_100, tmp_path):
    """study_dir.undone_if_nothing_saved: an error after metadata.json was written (here the first
    state's save, made to fail) removes what the new study wrote; an existing study is left as it is."""
    from trueaniso import study, study_dir
    out = tmp_path / "out"

    class Boom(RuntimeError):
        pass

    def fail(*args, **kw):
        raise Boom("made to fail")
    saved = specimen_file.save
    specimen_file.save = fail
    try:
        with pytest.raises(Boom):
            study.run_states(str(specimen_100), [(1, 0.0, 100e3)], str(out), probes=(2,), log=lambda m: None)
    finally:
        specimen_file.save = saved
    assert sorted(os.listdir(out)) == [".lock"], os.listdir(out)
    assert study_dir.read_metadata(str(out)) is None


def test_a_lock_or_states_of_the_wrong_kind_is_refused_in_one_line(specimen_100, tmp_path):
    """A .lock that is a directory and a states that is a file are refused in one line naming
    them, not as IsADirectoryError or FileExistsError tracebacks."""
    out = tmp_path / "a"
    (out / ".lock").mkdir(parents=True)
    one_line_error(run_script("run_states.py", "--specimen", specimen_100, "--ids", "1", "--out", out), ".lock",
                   "cannot be locked")
    out = tmp_path / "b"
    out.mkdir()
    (out / "states").write_text("not a directory")
    one_line_error(run_script("run_states.py", "--specimen", specimen_100, "--ids", "1", "--out", out),
                   "states is not a directory")


@pytest.mark.parametrize("assembly", ["clump1", "clump2"])
def test_a_huge_clump_preparation_is_refused_before_anything_is_drawn(tmp_path, assembly):
    """The memory a clump preparation needs is estimated before any clump is drawn, as for
    spheres. Under a 2 GB address-space limit a run that draws anything of that size dies of it
    instead of being refused."""
    import resource
    n = 1000000000  # a multiple of either recipe's layers

    def limit():
        resource.setrlimit(resource.RLIMIT_AS, (2 * 1024 ** 3, 2 * 1024 ** 3))
    proc = subprocess.run([sys.executable, os.path.join(SCRIPTS, "prepare_specimen.py"), "--assembly", assembly,
                           "--n", str(n), "--out", str(tmp_path / "s.npz")], capture_output=True, text=True,
                          timeout=120, preexec_fn=limit, env=dict(os.environ, OMP_NUM_THREADS="1"))
    one_line_error(proc, "needs about", "of memory")
    proc = run_script("run_study.py", "--assembly", assembly, "--n", n, "--out", tmp_path / "study")
    one_line_error(proc, "needs about", "of memory")


def _run_with_failing_writes(args, error, target):
    """run_states.py with every write of `target` ('csv': the probe table's appends, 'atomic': the
    atomic writes) failing with `error`, as a full disk or a file system turned read-only does."""
    code = textwrap.dedent("""
        import os, sys, types, runpy
        sys.path.insert(0, %r)
        from trueaniso import atomic, results_csv
        def failing(*a, **k):
            raise OSError(%d, os.strerror(%d))
        if %r == "csv":
            results_csv.os = types.SimpleNamespace(**dict(vars(os), write=failing))
        else:
            atomic.os = types.SimpleNamespace(**dict(vars(os), fsync=failing))
        sys.argv = [%r] + %r
        runpy.run_path(sys.argv[0], run_name="__main__")
    """) % (SCRIPTS, error, error, target, os.path.join(SCRIPTS, "run_states.py"), [str(a) for a in args])
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))


@pytest.mark.parametrize("error,target,fix", [
    (errno.ENOSPC, "csv", "free space there"),
    (errno.EROFS, "atomic", "make that file system writable"),
    (errno.EACCES, "atomic", "make it writable for this user"),
])
def test_an_io_error_mid_run_is_one_line_and_the_run_resumes(specimen_100, tmp_path, error, target, fix):
    """A full disk, a read-only file system or a permission taken away ends the run in one line
    naming the file and how to go on, not a traceback; the same command then finishes the study."""
    out = tmp_path / "out"
    args = ["--specimen", specimen_100, "--ids", "1", "--probes", "z", "--out", out]
    proc = _run_with_failing_writes(args, error, target)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 1 and len(lines) == 1 and lines[0].startswith("error: ") and fix in lines[0] \
        and os.strerror(error) in lines[0] and str(out) in lines[0] and "Traceback" not in proc.stderr, proc.stderr
    proc = run_script("run_states.py", *args)
    assert proc.returncode == 0, proc.stderr
    with open(out / "probes.csv") as f:
        assert len(f.read().splitlines()) == 2


def test_a_read_only_results_directory_is_refused_before_work(specimen_100, tmp_path):
    out = tmp_path / "ro"
    out.mkdir()
    os.chmod(out, 0o555)
    try:
        if os.access(out, os.W_OK):
            pytest.skip("this user writes into read-only directories (root)")
        one_line_error(run_script("run_states.py", "--specimen", specimen_100, "--ids", "1", "--out", out),
                       str(out))
    finally:
        os.chmod(out, 0o755)


@pytest.fixture(scope="module")
def clump_file(tmp_path_factory):
    """Eight clump1 clumps (the recipe's template) in a loose cell, saved as prepare_specimen.py
    labels them: no preparation, only what a file holds."""
    from trueaniso import clump_specimen, dem
    t = clump_shapes.template(clump_specimen.recipe("clump1")["shape"])
    rng = np.random.default_rng(2)
    s = engines.Scene()
    d = 0.2e-3 * (0.9 + 0.2 * rng.random(8))
    side = 8 * d.max()
    s.cell_size = s.cell_ref_size = [side] * 3
    grid = (np.indices((2, 2, 2)).reshape(3, -1).T + 0.5) * side / 2
    engines.add_clumps(s, t, grid, np.tile([1.0, 0, 0, 0], (8, 1)), d)
    s.dt = 1e-9
    dem.refresh(s)
    path = tmp_path_factory.mktemp("clumps") / "c.npz"
    specimen_file.save(str(path), s, seed=2, parameters=dict(assembly="clump1"))
    return path


def test_a_clump_file_as_written_passes_its_derived_checks(clump_file):
    specimen_file.load(str(clump_file))


def _scaled(name, k, factor):
    def edit(a):
        a[name] = a[name].copy()
        a[name][k] *= factor
    return edit


@pytest.mark.parametrize("edit_meta,edit_arrays,words", [
    # an inertia x1000, accepted, would change E_z by 2.25 % without a word
    (None, _scaled("inertia", 3, 1000.0), "body 3: its principal moments of inertia"),
    (None, _scaled("masses", 5, 1.01), "body 5: its mass"),
    (lambda m: m["material"].update(density=2000.0), None, r"body \d+: its mass"),
    # a clump1 file labelled clump2 would be reported as clump2
    (lambda m: m["parameters"].update(assembly="clump2"), None, "a clump of clump2"),
    (lambda m: m["parameters"].update(assembly="clump2", shape="pentamer-2.0", orientation_weights=[1.0, 1.0, 10.0],
                                      layers=1), None, "parameters record the clump1 recipe"),
    (None, _scaled("member_offsets", 0, 1.01), "body 0: its members are not the clump1 template"),
])
def test_clump_mass_inertia_and_label_are_checked_against_the_members(clump_file, tmp_path, edit_meta, edit_arrays,
                                                                      words):
    bad = tmp_path / "bad.npz"
    _rewrite(clump_file, bad, edit_meta=edit_meta, edit_arrays=edit_arrays, reseal=True)
    with pytest.raises(specimen_file.SpecimenFileError, match=words):
        specimen_file.read(str(bad))


def test_an_exploded_packing_is_refused_before_stepping(specimen_100, tmp_path):
    """Every length shrunk by 3 %: the contacts carry hundreds of MPa. Refused before the first
    step: the servo would otherwise step toward 100 kPa for its 3,000,000 steps, then give up."""
    def shrink(a):
        for k in ("positions", "cell", "cell_ref"):
            a[k] = a[k] * 0.97
        a["member_offsets"] = a["member_offsets"] * 0.97
    bad = tmp_path / "exploded.npz"
    _rewrite(specimen_100, bad, edit_arrays=shrink, reseal=True)
    out = tmp_path / "out"
    proc = run_script("run_states.py", "--specimen", bad, "--ids", "1", "--probes", "z", "--out", out,
                      "--path-rate", "inf", timeout=120)
    one_line_error(proc, "exploded or over-compressed", "times the largest stress")
    assert not out.exists()


def test_damping_0_is_refused_at_once_with_the_reason(specimen_100, tmp_path):
    """Refused before any step: with no damping, Table C1's state 5 is held 200,000 steps without
    settling (the unbalanced force stays above the servo's tolerance with nothing to dissipate it)."""
    out = tmp_path / "out"
    one_line_error(run_script("run_states.py", "--specimen", specimen_100, "--ids", "5", "--damping", "0",
                              "--out", out), "--damping 0", "no viscous damping")
    assert not out.exists()
