"""How long the engines' OpenMP team spins at a barrier before it sleeps (trueaniso.TEAM_SPIN_COUNT):
the package sets libgomp's GOMP_SPINCOUNT before the engines load, unless the user set it or a wait
policy, which are kept. libgomp prints what it took with OMP_DISPLAY_ENV=verbose. Why the value:
docs/studies/benchmarks.md, "Two threads"."""
import os
import subprocess
import sys

import pytest

from conftest import REPO

LOAD = "import trueaniso; trueaniso.engines"


def gomp_settings(**env):
    e = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    e.update(env, OMP_DISPLAY_ENV="verbose", PYTHONPATH=os.path.join(REPO, "pyscripts"))
    out = subprocess.run([sys.executable, "-c", LOAD], env=e, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    lines = [ln.strip() for ln in out.stderr.splitlines()]
    return {k: ln.split("=", 1)[1].strip().strip("'") for ln in lines if "=" in ln
            for k in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY") if ln.startswith(k + " ")}


def test_the_engines_team_spins_briefly_by_default():
    import trueaniso
    assert gomp_settings()["GOMP_SPINCOUNT"] == trueaniso.TEAM_SPIN_COUNT


@pytest.mark.parametrize("env, expected", [({"GOMP_SPINCOUNT": "777"}, "777"),
                                           ({"OMP_WAIT_POLICY": "active"}, "30000000000")])
def test_a_users_own_setting_is_kept(env, expected):
    assert gomp_settings(**env)["GOMP_SPINCOUNT"] == expected
