import json
import os
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "pyscripts"))
sys.path.insert(0, REPO)


def run_yade(script, *args, timeout=600):
    """Run a script under yade-double and return the JSON it wrote (last argument: output path)."""
    if shutil.which("yade-double") is None:
        pytest.fail("yade-double is not installed (the test command installs it with apt-get)")
    return subprocess.run(["yade-double", "-n", "-x", script, *args], capture_output=True, text=True,
                          timeout=timeout)


@pytest.fixture
def yade_json(tmp_path):
    def go(name, *args, timeout=600):
        out = tmp_path / (name + ".json")
        proc = run_yade(os.path.join(HERE, "yade_scripts", name + ".py"), *args, str(out), timeout=timeout)
        if proc.returncode != 0 or not out.exists():
            raise AssertionError("yade-double %s failed:\n%s\n%s" % (name, proc.stdout[-3000:], proc.stderr[-3000:]))
        return json.loads(out.read_text())
    return go
