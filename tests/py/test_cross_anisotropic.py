"""Fig. 16's cross-anisotropic path: sigma_h held at 100 kPa while sigma_v varies, shear
probes, and the paper's G_vh and G_hh; run_states.py --path cross-anisotropic with its input
checks and a fingerprint that covers the path. Two states of the committed 150-sphere specimen
(tests/data/spheres-150-s6.npz): its ratios of Eq. (24) agree to 2 % (1.8 and 2.1 %; 1.7 and 2.3 %
on spheres-300-s3.npz), where a 100-sphere packing's own anisotropy puts them 17 % apart (seed 3),
so the agreement is checked on a packing that does not change with the recipe."""
import csv
import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import REPO, one_line_error, run_script

from trueaniso.analysis import cross_anisotropy
from trueaniso import triaxial


def rows(out):
    with open(os.path.join(out, "probes.csv"), newline="") as f:
        return list(csv.DictReader(f))


SPECIMEN = os.path.join(REPO, "tests", "data", "spheres-150-s6.npz")


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("cross") / "study"
    proc = run_script("run_states.py", "--specimen", SPECIMEN, "--out", out, "--path", "cross-anisotropic",
                      "--sigma-v", "70e3,130e3")
    assert proc.returncode == 0, proc.stderr
    return out


def test_path_holds_sigma_h_and_reports_the_whole_stress(study):
    """Every state: sigma_x = sigma_y = 100 kPa and sigma_z = sigma_v, the principal values those
    goals and the shear stresses zero, all within 0.5 kPa; one row per state and each
    of the six probes."""
    r = rows(study)
    assert sorted((x["state"], x["probe"]) for x in r) == sorted(
        (s, a) for s in ("sv70", "sv130") for a in ("x", "y", "z", "yz", "xz", "xy"))
    for x in r:
        sv = float(x["sigma_z_goal"])
        assert x["path"] == "cross-anisotropic"
        assert abs(float(x["sigma_x"]) - 100e3) < 500 and abs(float(x["sigma_y"]) - 100e3) < 500
        assert abs(float(x["sigma_z"]) - sv) < 500
        principal = sorted([float(x["sigma_%d" % k]) for k in (1, 2, 3)])
        np.testing.assert_allclose(principal, sorted([100e3, 100e3, sv]), atol=500)
        assert float(x["tau_max"]) == max(abs(float(x[k])) for k in ("sigma_yz", "sigma_xz", "sigma_xy")) < 500
        # a shear probe row has G and no E; a normal probe row E and no G
        shear = x["probe"] in ("yz", "xz", "xy")
        assert (x["G"] != "") == shear and (x["E"] != "") == (not shear)
        if shear:
            k = 3 + ("yz", "xz", "xy").index(x["probe"])
            d_tau = float(x["d_sigma_" + x["probe"]])
            d_gamma = float(x["d_gamma_" + x["probe"]])
            # G_ij = d tau_ij / d gamma_ij, recomputed here from the row's own increments
            assert float(x["G"]) == pytest.approx(d_tau / d_gamma, rel=1e-9), k
            assert abs(d_gamma) >= 1e-6
    meta = json.loads((study / "metadata.json").read_text())
    assert meta["fingerprint"]["path"] == "cross-anisotropic"
    assert meta["probes"] == ["x", "y", "z", "yz", "xz", "xy"]


def test_g_vh_and_g_hh_follow_the_papers_definitions(study):
    """G_vh = (G_yz + G_xz) / 2, G_hh = G_xy, E_h = (E_x + E_y) / 2 (z vertical), written out here
    from the rows; the measures of Eq. (24) from them. Then the physics: a vertical load makes the
    vertical stiffer, so (E_h/E_v)^0.5 and G_hh/G_vh both fall from sv70 to sv130 (the specimen is
    near isotropic), and the two ratios agree to 10 % (Eqs. 23-24 hold only approximately)."""
    measures = {m["state"]: m for m in cross_anisotropy.states(str(study / "probes.csv"))}
    by = {}
    for x in rows(study):
        by.setdefault(x["state"], {})[x["probe"]] = x
    for sid, p in by.items():
        m = measures[sid]
        G_vh = 0.5 * (float(p["yz"]["G"]) + float(p["xz"]["G"]))
        assert m["G_vh"] == pytest.approx(G_vh, rel=1e-12)
        assert m["G_hh"] == pytest.approx(float(p["xy"]["G"]), rel=1e-12)
        E_h = 0.5 * (float(p["x"]["E"]) + float(p["y"]["E"]))
        assert m["E_ratio_root"] == pytest.approx(math.sqrt(E_h / float(p["z"]["E"])), rel=1e-12)
        assert m["G_ratio"] == pytest.approx(float(p["xy"]["G"]) / G_vh, rel=1e-12)
        assert m["G_ratio"] == pytest.approx(m["E_ratio_root"], rel=0.1)
    lo, hi = measures["sv70"], measures["sv130"]
    assert lo["E_ratio_root"] > 1 > hi["E_ratio_root"]
    assert lo["G_ratio"] > hi["G_ratio"]


def test_rerun_on_another_path_is_refused(study):
    """The fingerprint covers the path: the same directory asked for Table C1 states refuses in
    one line naming the path, and writes nothing."""
    before = (study / "probes.csv").read_text()
    proc = run_script("run_states.py", "--specimen", SPECIMEN, "--out", study, "--ids", "1")
    one_line_error(proc, "path", "cross-anisotropic", "true-triaxial")
    assert (study / "probes.csv").read_text() == before


@pytest.mark.parametrize("args,words", [
    (["--path", "cross-anisotropic", "--ids", "1"], ["--sigma-v", "not from"]),
    (["--ids", "1", "--sigma-v", "80e3"], ["--sigma-v belongs to --path cross-anisotropic"]),
    (["--path", "cross-anisotropic", "--sigma-v", "80e3,-5"], ["sigma_v must be a finite stress > 0"]),
    (["--path", "cross-anisotropic", "--sigma-v", "80e3,8e4"], ["given twice"]),
    (["--path", "cross-anisotropic", "--sigma-v", "100e3,"], ["'100e3,' has an empty item"]),  # not one state alone
    (["--path", "cross-anisotropic", "--sigma-v", "60e3,,140e3"], ["has an empty item"]),
    (["--path", "cross-anisotropic", "--sigma-v", "80e3,1e9"], ["state sv1000000", "of a radius"]),
    # 0.01 Pa apart: one name (ids keep 0.1 Pa), and the message shows both values
    (["--path", "cross-anisotropic", "--sigma-v", "100050,100049.99"], ["sv100.05 is given twice (100050, 100049.99 Pa"]),
    (["--path", "cross-anisotropic", "--sigma-v", "eighty"], ["expected stresses in Pa"]),
    (["--path", "cross-anisotropic", "--probes", "z,yz,yz"], ["--probes 'z,yz,yz' names yz more than once"]),
    (["--ids", "1", "--probes", "z,zz"], ["--probes 'z,zz': 'zz' is no probe's name"]),
    # 'yx,' repeats nothing: named as no probe, not as a repeat
    (["--ids", "1", "--probes", "yx,"], ["--probes 'yx,': 'yx' is no probe's name", "yz, xz, xy"]),
    (["--ids", "1", "--probes", "z,,x"], ["--probes 'z,,x': an empty item"]),
    (["--path", "diagonal", "--ids", "1"], ["--path", "invalid choice"]),
])
def test_bad_path_input_is_refused_before_work(specimen_100, tmp_path, args, words):
    out = tmp_path / "out"
    proc = run_script("run_states.py", "--specimen", specimen_100, "--out", out, *args, timeout=120)
    one_line_error(proc, *words)
    assert not out.exists()


def test_path_state_checks():
    """The library refuses what the script would, with the reason."""
    assert triaxial.path_mean_stress("cross-anisotropic", 0.0, 250e3) == pytest.approx(150e3, rel=1e-15)
    np.testing.assert_allclose(triaxial.path_stresses("cross-anisotropic", 0.0, 40e3), [100e3, 100e3, 40e3],
                               rtol=1e-14)
    with pytest.raises(ValueError, match="b = 0"):
        triaxial.validate_path_state("cross-anisotropic", 0.5, 80e3)
    with pytest.raises(ValueError, match="unknown path"):
        triaxial.path_mean_stress("orthotropic", 0.0, 80e3)
    assert [i for i, _, _ in triaxial.cross_anisotropic_states([60e3, 112.5e3])] == ["sv60", "sv112.5"]


def test_outputs_go_where_asked_or_are_refused_first(tmp_path):
    """--out and --figure in directories that do not exist yet: made, as for every other output; a
    place that cannot be written is one line before any work, not a traceback after it."""
    table = os.path.join(REPO, "docs", "data", "fig16-spheres-4000-s1", "probes.csv")
    out, fig = tmp_path / "new" / "ca.json", tmp_path / "other" / "ca.png"
    assert cross_anisotropy.main([table, "--out", str(out), "--figure", str(fig)]) == 0
    assert {m["state"] for m in json.loads(out.read_text())} >= {"sv100", "sv200"} and fig.stat().st_size > 0
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    for option in ("--out", "--figure"):
        proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.cross_anisotropy", table, option, str(blocker / "x")],
                              capture_output=True, text=True, cwd=REPO, timeout=120)
        assert proc.returncode == 2 and proc.stdout == "", proc.stderr
        assert proc.stderr.startswith("error: %s" % option) and len(proc.stderr.splitlines()) == 1, proc.stderr


def test_a_state_with_two_horizontal_stresses_is_not_fig16(tmp_path):
    """A true-triaxial state (21: sigma_x 100, sigma_y 60 kPa) probed with the six probes was shown
    is not Fig. 16 (whose sigma_h would be the mean of the two): refused, naming the state."""
    import csv as _csv
    from trueaniso.analysis import cross_anisotropy
    from trueaniso.analysis.results import ResultsError
    src = os.path.join(REPO, "docs", "data", "fig16-spheres-4000-s1", "probes.csv")
    with open(src, newline="") as f:
        rows = list(_csv.DictReader(f))
    # The first state made state 21 of Table C1, its rows consistent with that definition (the
    # table's reader refuses a row whose stresses are not its state's: test_derived_checks), so that
    # only the Fig. 16 analysis can refuse it.
    first = rows[0]["state"]
    for r in rows:
        if r["state"] == first:
            r.update(path="true-triaxial", state="21", b="0.5", sigma_z_goal="140000.0", sigma_x="100000.0",
                     sigma_y="60000.0", sigma_z="140000.0")
    first = "21"
    path = tmp_path / "probes.csv"
    with open(path, "w", newline="") as f:
        w = _csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with pytest.raises(ResultsError, match="state %s is not cross-anisotropic" % first):
        cross_anisotropy.states(str(path))
    assert len(cross_anisotropy.states(src)) >= 3  # the real study passes
