"""The YADE plugin (engines/yade, docs/yade-peer.md): our law, servo, probe and fabric recorder as
YADE classes in Debian's yade-double, loaded through YADE_PREFIX=build/yade-prefix.

The plugin is built by ./setup.sh when the YADE source can be had; without it these tests skip
with the reason setup wrote to build/yade-plugin.status (and fail where TRUEANISO_YADE_SOURCE is
set, as in CI: there the plugin must be there)."""
import json
import math
import os
import shutil
import subprocess

import numpy as np
import pytest
from conftest import HERE, REPO

BUILD = os.environ.get("TRUEANISO_BUILD", os.path.join(REPO, "build"))
PREFIX = os.path.join(BUILD, "yade-prefix")
STATUS = os.path.join(BUILD, "yade-plugin.status")
LIBDIR = "lib/x86_64-linux-gnu/yade-double"


def plugin_status():
    try:
        with open(STATUS) as f:
            return f.read().strip()
    except OSError:
        return "absent: ./setup.sh has not built it (build/yade-plugin.status missing)"


@pytest.fixture(scope="module")
def plugin():
    status = plugin_status()
    if status != "installed" or not os.path.exists(os.path.join(PREFIX, LIBDIR, "libtrueanisoYade.so")):
        if os.environ.get("TRUEANISO_YADE_SOURCE"):
            pytest.fail("TRUEANISO_YADE_SOURCE is set but the YADE plugin is not installed: " + status)
        pytest.skip("the YADE plugin is not installed: " + status)
    return PREFIX


def run_plugin(name, *args, threads=1, timeout=1800, prefix=PREFIX, cwd=None):
    """yade-double [-jN] -n -x yade_scripts/<name>.py args OUT.json with the plugin; the JSON."""
    out = os.path.join(cwd or os.getcwd(), "%s-%d.json" % (name, os.getpid()))
    env = dict(os.environ, YADE_PREFIX=prefix, OMP_NUM_THREADS=str(threads))
    cmd = ["yade-double", "-j%d" % threads, "-n", "-x", os.path.join(HERE, "yade_scripts", name + ".py"),
           *map(str, args), out]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env, cwd=cwd)
    if proc.returncode != 0 or not os.path.exists(out):
        raise AssertionError("yade-double %s failed:\n%s\n%s" % (name, proc.stdout[-3000:], proc.stderr[-3000:]))
    with open(out) as f:
        data = json.load(f)
    os.remove(out)
    return data


# ---------------------------------------------------------------------------------------------
# The law on a loaded pair.

def paper_constants(G, nu):
    """C_n and C_s of Eqs. (5)-(6), written as printed."""
    Cn = 0.75 * (8 * G / (3 * (1 - nu))) ** (2 / 3)
    Cs = 2 * (3 * G ** 2 * (1 - nu)) ** (1 / 3) / (2 - nu)
    return Cn, Cs


def test_law_against_the_equations_and_yade_mindlin(plugin, tmp_path):
    r = run_plugin("plugin_law", cwd=tmp_path)
    ours, yade = r["ours"], r["yade"]
    assert len(ours) == len(yade) == 250
    assert {s["phys"] for s in ours} == {"SimplifiedMindlinPhys"} and {s["phys"] for s in yade} == {"MindlinPhys"}
    G, nu, young, R, dt = r["G"], r["nu"], r["young"], r["r"], r["dt"]
    Cn, Cs = paper_constants(G, nu)
    Estar = young / (2 * (1 - nu ** 2))  # Hertz's contact modulus of two spheres of one material
    shear_sum = 0.0
    for k, s in enumerate(ours):
        p1, p2, n = np.array(s["p1"]), np.array(s["p2"]), np.array(s["normal"])
        delta = 2 * R - np.linalg.norm(p2 - p1)
        N = np.linalg.norm(s["N"])
        # Hertz in closed form, R* = R/2 (Eq. 7: rbar = R for equal spheres). delta from the
        # positions carries 1e-13 of round-off (2 mm minus 2 mm less 2 um).
        assert N == pytest.approx(4 / 3 * Estar * math.sqrt(R / 2) * delta ** 1.5, rel=1e-10)
        # Eqs. (5) and (6): tangent stiffnesses from the force, to round-off
        assert s["kn"] == pytest.approx(Cn * (R * N) ** (1 / 3), rel=1e-12)
        assert s["ks"] == pytest.approx(Cs * (R * N) ** (1 / 3), rel=1e-12)
        if k < 200:
            v = np.array(s["v"]) * dt
            shear_sum += s["ks"] * np.linalg.norm(v - n.dot(v) * n)
    # Elastic shear: |Fs| = sum of k_s |du| (the increments keep one direction while the normal turns
    # by 2e-4 rad: their misalignment enters at 4e-8), opposite to the motion.
    fs = np.array(ours[199]["Fs"])
    assert np.linalg.norm(fs) == pytest.approx(shear_sum, rel=1e-6)
    assert np.linalg.norm(fs) > 0.2 * np.linalg.norm(ours[199]["N"])  # a real shear load
    assert fs.dot(ours[199]["v"]) < 0
    # Friction lowered to 0.1 at run time: the pair slides at the new cap.
    last = ours[-1]
    assert np.linalg.norm(last["Fs"]) == pytest.approx(0.1 * np.linalg.norm(last["N"]), rel=1e-12)
    # YADE's packaged law on the same path: the same Hertz force to round-off; the shear force
    # differs by YADE's small-angle turning of it, O(angle^2) = 1e-8 over this path.
    for a, b in zip(ours, yade):
        Na, Nb = np.array(a["N"]), np.array(b["N"])
        assert np.linalg.norm(Na - Nb) <= 1e-12 * np.linalg.norm(Nb)
        Fa, Fb = np.array(a["Fs"]), np.array(b["Fs"])
        assert np.linalg.norm(Fa - Fb) <= 1e-6 * np.linalg.norm(Fb)
        assert a["ks"] == pytest.approx(b["ks"], rel=1e-12)

