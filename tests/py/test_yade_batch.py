"""YADE habits: a real yade-batch run of a two-line table through
run_states.py; importing a script inside a YADE session runs nothing; our table reader and
YADE's agree on YADE's conventions (editor line numbers, '#', '=', '!' columns, evaluated values)."""
import csv
import json
import os
import shutil
import subprocess

import pytest
from conftest import SCRIPTS

TABLE = """# one study, two states: both lines queue on the results directory's lock
specimen   out      ids  probes  wait  progress_every  description
'S.npz'    'study'  1    'z'     True  0               iso

'S.npz'    =        6    =       =     =               extension   # '=' repeats the line above
"""


def test_yade_batch_runs_a_two_line_table(specimen_100, tmp_path):
    if shutil.which("yade-batch") is None:
        pytest.fail("yade-batch is not installed (the yade package provides it)")
    shutil.copy(specimen_100, tmp_path / "S.npz")
    (tmp_path / "states.table").write_text(TABLE)
    proc = subprocess.run(["yade-batch", "--job-threads", "1", "-j", "2", "--log", "%.log", "--disable-pynotify",
                           "states.table", os.path.join(SCRIPTS, "run_states.py")],
                          cwd=tmp_path, capture_output=True, text=True, timeout=600)
    logs = {n: (tmp_path / ("%d.log" % n)).read_text() for n in (3, 5) if (tmp_path / ("%d.log" % n)).exists()}
    assert proc.returncode == 0 and len(logs) == 2, proc.stdout[-2000:] + "\n".join(logs.values())
    assert "done    (exit status 0)" in proc.stdout and "failed" not in proc.stdout, proc.stdout[-2000:]
    with open(tmp_path / "study" / "probes.csv") as f:
        rows = list(csv.DictReader(f))
    assert sorted((r["state"], r["probe"]) for r in rows) == [("1", "z"), ("6", "z")]
    meta = json.loads((tmp_path / "study" / "metadata.json").read_text())
    assert sorted(run["table"] for run in meta["runs"]) == ["states.table:3", "states.table:5"]
    assert meta["fingerprint"]["threads"] == 1  # yade-batch's --job-threads reached the engines
    assert "state 6 probe z: step" in logs[5]  # progress lines (every chunk: progress_every 0) in the job's log


def test_import_inside_yade_and_table_readers_agree(yade_json, tmp_path):
    table = tmp_path / "t.table"
    table.write_text("# YADE's conventions, all of them\n"
                     "n!    seed  pressure  quiet  out       !THREADS\n"
                     "100   1     100e3     False  'a.npz'   1\n"
                     "\n"
                     "# a comment line between data lines\n"
                     "=     2     =         True   'b.npz'   =\n"
                     "300   =     2*50e3    =      =         2    # a trailing comment\n")
    got = yade_json("import_and_tables", SCRIPTS, str(table))
    assert got["imported"]  # the import does not run main(), which would end the session with an error
    assert sorted(got["lines"]) == ["3", "6", "7"]  # numbered as a text editor shows them
    for line, d in got["lines"].items():
        assert d["raw_equal"], d
        assert d["ours"] == d["yade"], d  # our evaluation = readParamsFromTable's
    assert got["lines"]["6"]["ours"] == dict(n=100, seed=2, pressure=100e3, quiet=True, out="b.npz")
    assert got["lines"]["7"]["ours"] == dict(n=300, seed=2, pressure=100e3, quiet=True, out="b.npz")
