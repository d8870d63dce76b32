"""Scripts refuse bad input with one clear line and a non-zero exit, before any work, and leave
no file behind."""
import os
import subprocess
import sys

import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PREPARE = os.path.join(REPO, "pyscripts", "prepare_specimen.py")


def run(*args, timeout=120):
    return subprocess.run([sys.executable, PREPARE, *args], capture_output=True, text=True, timeout=timeout)


@pytest.mark.parametrize("args,message", [
    (["--bogus", "1"], "unrecognized arguments"),
    (["--n", "0"], "empty cell"),
    (["--d50=-1e-4"], "radius <= 0"),
    (["--d50", "0"], "radius <= 0"),
    (["--phi-cell", "0.8"], "cannot fit the box"),
    (["--n", "3"], "cannot fit the box"),
    (["--cu", "0.9"], "Cu must lie"),
    (["--pressure=-5"], "pressure must be > 0"),
    (["--assembly", "clump9"], "unknown assembly"),
    (["--assembly", "clump2", "--n", "1001"], "multiple of 4"),  # clump2 is four copies of a layer
    (["--assembly", "clump1", "--n", "4"], "cannot fit the box"),  # a clump is longer than a sphere
    (["--out", "x.txt"], ".npz"),
    (["--table", "", "--line", "2"], "--table is empty"),  # the empty value named, not '--line needs --table'
])
def test_bad_input_one_line_and_nothing_written(tmp_path, args, message):
    out = tmp_path / "s.npz"
    argv = args if "--out" in args else args + ["--out", str(out)]
    proc = run(*argv)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and message in lines[0], proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_corrupt_existing_output_is_reported_not_overwritten(tmp_path):
    out = tmp_path / "s.npz"
    out.write_bytes(b"not a zip file")
    proc = run("--n", "100", "--out", str(out))
    assert proc.returncode == 2
    assert "not usable" in proc.stderr and "corrupt" in proc.stderr
    assert out.read_bytes() == b"not a zip file"


def test_table_line_supplies_parameters(tmp_path):
    """Lines are numbered as a text editor (and yade-batch) numbers them: the heading is line 1."""
    table = tmp_path / "params.table"
    table.write_text("n seed phi_cell\n100 3 0.9\n")
    proc = run("--table", str(table), "--line", "2", "--out", str(tmp_path / "s.npz"))
    assert proc.returncode == 2 and "--phi-cell 0.9" in proc.stderr  # the table's value was used
    proc = run("--table", str(table), "--line", "1", "--out", str(tmp_path / "s.npz"))
    assert proc.returncode == 2 and "no data on line 1" in proc.stderr
    # A parameter in two columns: refused (not the last one taken without a word).
    dup = tmp_path / "dup.table"
    dup.write_text("n seed n\n100 3 200\n")
    proc = run("--table", str(dup), "--line", "2", "--out", str(tmp_path / "s.npz"))
    assert proc.returncode == 2 and "names the parameter 'n' in two columns" in proc.stderr, proc.stderr
    # A value that starts with '-' (argparse takes it for an option): the message says how to give it
    proc = run("--pressure", "-1e5", "--out", str(tmp_path / "s.npz"))
    assert proc.returncode == 2 and "goes as --option=VALUE" in proc.stderr, proc.stderr
    # A --line that is no number: one line too (argparse's usage line left out).
    proc = run("--table", str(table), "--line", "abc", "--out", str(tmp_path / "s.npz"))
    assert proc.returncode == 2 and proc.stderr == "error: argument --line: invalid int value: 'abc'\n", proc.stderr


def test_a_log_line_is_one_write(monkeypatch):
    """progress.say, the scripts' log: text and newline in one write. print() made two when Python
    runs unbuffered, as mpiexec starts it (PYTHONUNBUFFERED=1), and two workers' lines ran together."""
    import io
    from trueaniso import progress
    writes = []

    class Recorder(io.StringIO):
        def write(self, text):
            writes.append(text)
            return len(text)
    monkeypatch.setattr("sys.stdout", Recorder())
    progress.say("state 3: probe z")
    assert writes == ["state 3: probe z\n"]


@pytest.mark.parametrize("script", ["prepare_specimen", "run_study", "run_states"])
def test_every_script_reads_assembly_the_same_way(script):
    """One reading of --assembly (cli.assembly) in every script: 'spheres', the documented alias, is
    taken for 'sphere' by each of prepare_specimen.py, run_study.py and run_states.py."""
    sys.path.insert(0, os.path.join(REPO, "pyscripts"))
    module = __import__(script)
    read = module.options if script == "prepare_specimen" else lambda argv: module.parser().parse_args(argv)
    required = ["--specimen", "s.npz"] if script == "run_states" else []
    for given, taken in (("spheres", "sphere"), ("sphere", "sphere"), ("clump2", "clump2")):
        assert read(required + ["--out", "o.npz", "--assembly", given]).assembly == taken


def test_a_kept_specimen_says_what_it_was_made_with_that_this_run_asked_otherwise(tmp_path):
    """A specimen is kept when its recipe matches; a --threads or --checkpoint-every given
    otherwise (each changes its last bits) is named in a note, not passed over without a word."""
    out = tmp_path / "s.npz"
    first = run("--n", "100", "--seed", "3", "--threads", "1", "--checkpoint-every", "0", "--quiet", "--out", str(out))
    assert first.returncode == 0, first.stderr
    same = run("--n", "100", "--seed", "3", "--threads", "1", "--out", str(out))
    assert "kept existing specimen" in same.stdout and "note:" not in same.stdout
    other = run("--n", "100", "--seed", "3", "--threads", "2", "--checkpoint-every", "1000", "--out", str(out))
    assert other.returncode == 0, other.stderr
    assert ("note: it was made at 1 engine thread (this run: 2), without checkpoints (this run: checkpoints every "
            "1000 steps), each of which can change its last bits") in other.stdout
