"""The paper's analysis chain (pyscripts/trueaniso/analysis/chain.py) against hand-computed values, and the report
(pyscripts/trueaniso/analysis/report.py) built from a small fixed probe table: eight states of the committed
4000-sphere, 39-state study (docs/data/table-c1-spheres-4000.csv)."""
import csv
import json
import os
import shutil
import subprocess
import sys
import warnings

import numpy as np
import pytest

from conftest import REPO, SMALL_TABLE_STATES
from trueaniso.analysis import chain, figures, hyperelastic, report
from trueaniso.analysis.results import ResultsError

STATES = SMALL_TABLE_STATES


@pytest.fixture
def text_only(monkeypatch):
    """For the tests that read only the report's text and numbers: every figure is drawn and laid
    out as always, but an empty file stands for its PNG (rasterising is two fifths of a report's
    time). test_report_from_a_small_fixed_table, the Fig. 16 test and
    test_figures_5_to_12_plot_the_table_s_own_numbers check real PNGs."""
    monkeypatch.setattr(figures, "_save", lambda fig, path: open(path, "wb").close())


def test_eq21_22_prediction_by_hand():
    # K = 150, G = 120 MPa; a^2 = (1.1, 1.0, 1/1.1): det a = 1
    K, G, a2 = 150e6, 120e6, np.array([1.1, 1.0, 1 / 1.1])
    E, nu, Gij = hyperelastic.predicted(K, G, a2)
    E0 = 9 * K * G / (3 * K + G)  # 9*150*120/(450+120) = 284.2105 MPa
    assert E0 == pytest.approx(284.2105263e6, rel=1e-9)
    assert E == pytest.approx(E0 * a2 ** 2, rel=1e-12)
    nu0 = (3 * K - 2 * G) / (2 * (3 * K + G))  # (450-240)/(2*570) = 0.184210526
    assert nu[0, 2] == pytest.approx(0.184210526 * 1.1 * 1.1, rel=1e-8)  # a_x^2/a_z^2 = 1.21
    assert nu[2, 0] == pytest.approx(nu0 / 1.21, rel=1e-12)
    assert Gij[2] == pytest.approx(G * 1.1, rel=1e-12)  # G_xy = G a_x^2 a_y^2


def test_eq25_inverts_eq21_with_det_a_one():
    a2 = np.array([1.07, 0.96, 1 / (1.07 * 0.96)])
    E = 300e6 * a2 ** 2
    back = hyperelastic.fabric_a2(E)
    assert back == pytest.approx(a2, rel=1e-12)
    assert np.prod(back) == pytest.approx(1.0, rel=1e-12)


def test_table2_fit_recovers_known_coefficients():
    zm = np.linspace(5.6, 5.95, 12)
    c_K, c_G = (1902.7, -22607.0, 67289.1), (-10.2, 151.9, -423.7)
    tab = dict(state=[str(k) for k in range(12)], Zm=zm, K=np.polyval(c_K, zm) * 1e6, G=np.polyval(c_G, zm) * 1e6)
    fits = chain.table2(tab)
    assert fits["K"][:3] == pytest.approx(c_K, rel=1e-6) and fits["K"][3] == pytest.approx(1.0, abs=1e-12)
    assert fits["G"][:3] == pytest.approx(c_G, rel=1e-6)
    assert chain.table2(dict(tab, state=["a", "b"], Zm=zm[:2], K=tab["K"][:2], G=tab["G"][:2])) is None


def test_stress_ratio_exponent_of_an_exact_power_law():
    sig = np.array([[100e3, 60e3, 140e3], [90e3, 105e3, 105e3], [120e3, 100e3, 80e3]])
    tab = dict(sigma=sig, E=300e6 * (sig / 100e3) ** 0.45)
    exp = chain.stress_ratio_exponent(tab)
    assert exp["m"] == pytest.approx(0.45, rel=1e-12) and exp["r2"] == pytest.approx(1.0, abs=1e-12)


def test_stress_ratio_exponent_over_chosen_pairs():
    """Clumps (Fig. 4b-c): the horizontal pair alone follows the power law; pairs with z carry
    the inherent anisotropy, a factor the power law cannot take."""
    sig = np.array([[100e3, 60e3, 140e3], [90e3, 105e3, 105e3], [120e3, 100e3, 80e3]])
    E = 300e6 * (sig / 100e3) ** 0.45 * np.array([1.0, 1.0, 1.8])   # E_z 1.8 times stiffer
    h = chain.stress_ratio_exponent(dict(sigma=sig, E=E), chain.HORIZONTAL_PAIRS)
    assert h["m"] == pytest.approx(0.45, rel=1e-12) and len(h["log_sigma_ratio"]) == 6
    v = chain.stress_ratio_exponent(dict(sigma=sig, E=E), chain.VERTICAL_PAIRS)
    assert len(v["log_sigma_ratio"]) == 12 and v["r2"] < 0.9   # log 1.8 is not a power of the stress ratio


def test_rising_side_of_the_paper_s_quadratics():
    """The vertex -c2/(2 c1) by hand: spheres' K 22607/(2 x 1902.7) = 5.9408, rising above it;
    clump1's K 151.9/20.4 = 7.446, rising below it (so its data lie below 7.45)."""
    assert chain.rising_side(chain.PAPER["spheres"]["K"]) == ("above", pytest.approx(5.94077, abs=1e-5))
    assert chain.rising_side(chain.PAPER["clump1"]["K"]) == ("below", pytest.approx(7.44608, abs=1e-5))
    low, high, why = chain.rising_range({k: chain.PAPER["clump1"][k] for k in ("K", "G")})
    assert (low, high) == (-np.inf, pytest.approx(7.44608, abs=1e-5))  # G rises below 12.77: K binds
    low, high, _ = chain.rising_range({k: chain.PAPER["spheres"][k] for k in ("K", "G")})
    assert low == pytest.approx(5.94077, abs=1e-5) and high == np.inf  # G's vertex 5.9356 is lower


def test_no_exponent_from_stress_ratios_within_the_servo_s_tolerance():
    """b = 0 states hold sigma_x = sigma_y within 100 Pa: their ratio is noise, and the slope of
    noise was reported as m = 503 (clump2, seven b = 0 states). Now there is none."""
    sig = np.array([[100e3, 100.05e3, 100e3], [110e3, 109.95e3, 80e3]])
    E = np.array([[300e6, 301e6, 250e6], [310e6, 309e6, 260e6]])
    assert chain.stress_ratio_exponent(dict(sigma=sig, E=E), chain.HORIZONTAL_PAIRS) is None
    assert chain.stress_ratio_exponent(dict(sigma=sig, E=E), chain.VERTICAL_PAIRS) is not None


def test_zm_by_sign_of_q_by_hand():
    q = [0.0, -30e3, -60e3, 30e3, 60e3]
    zm = [10.2, 10.0, 9.7, 10.1, 9.95]
    s = chain.zm_by_sign_of_q(q, zm, 10.2)
    assert s["negative"] == dict(n=2, lowest=9.7, drop=pytest.approx(0.5))
    assert s["positive"] == dict(n=2, lowest=9.95, drop=pytest.approx(0.25))
    assert chain.zm_by_sign_of_q([0.0, 1.0], [6.0, 5.9], 6.0)["negative"] == dict(n=0, lowest=None, drop=None)


def test_predictions_reproduce_states_that_obey_the_model():
    """States made by Eqs. 21-22 from K(Zm), G(Zm) and known a^2 are predicted exactly (RMSE 0)."""
    zm = np.array([5.95, 5.9, 5.8, 5.7])
    fits = dict(K=(0.0, 40.0, -100.0, 1.0), G=(0.0, 30.0, -40.0, 1.0))
    a2 = np.array([[1.0, 1.0, 1.0], [1.02, 0.97, 1 / (1.02 * 0.97)], [0.95, 1.0, 1 / 0.95], [1.05, 1.05, 1 / 1.05 ** 2]])
    E = np.empty((4, 3))
    nu = np.empty((4, 3, 3))
    for k in range(4):
        E[k], nu[k], _ = hyperelastic.predicted(np.polyval(fits["K"][:3], zm[k]) * 1e6,
                                                np.polyval(fits["G"][:3], zm[k]) * 1e6, a2[k])
    p = chain.predictions(dict(Zm=zm, E=E, nu=nu), fits, a2)
    assert p["E_rel_rmse"] < 1e-14 and p["nu_rmse"] < 1e-14
    p = chain.predictions(dict(Zm=zm, E=E, nu=nu + 0.01), fits, a2)
    assert p["nu_rmse"] == pytest.approx(0.01, rel=1e-9)


def test_report_from_a_small_fixed_table(small_table, tmp_path):
    out = tmp_path / "rep"
    path, numbers = report.build(small_table, str(out), log=lambda m: None)
    text = open(path).read()
    n = numbers["free"]
    assert n["states"] == len(STATES)
    # the same numbers as the chain computes directly, in the report's tables
    tab = chain.state_table([r for r in csv.DictReader(open(small_table))])
    fits = chain.table2(tab)
    assert n["table2"]["K"] == pytest.approx(fits["K"])
    assert "| K ours | %.1f | %.1f | %.1f | %.4f |" % fits["K"] in text
    assert "| zeta = 0.552 (paper) |" in text and "| paper (spheres, 0.552) | | | | 0.003 | |" in text
    # Zm of these states spans the contact loss; zeta follows it
    assert 5.59 < n["Zm"][0] < 5.7 and 5.94 < n["Zm"][1] < 5.96
    assert 0.3 < n["m"] < 0.5
    for fig in ("fig3-E-vs-sigma.png", "fig11-K-G-vs-Zm.png", "fig13-a2.png", "fig14-E.png", "fig15-nu.png",
                "fig15-nu-parity.png", "fig4a.png", "zeta-vs-Zm.png"):
        assert (out / fig).stat().st_size > 5000 and "](%s)" % fig in text
    assert "## Departures from the paper" in text and "763.97" in text
    assert "Not in this study" in text  # no statics_isotropic.json beside a bare table


def test_report_for_a_clump_assembly_names_the_clump_paper_values(small_table, tmp_path, text_only):
    """--assembly clump1: the paper's clump1 numbers (Table 2, nu RMSE 0.036) and its statements
    (Fig. 4b: E_x/E_y alone a power law; Fig. 8: Zm falls faster at q < 0), none of the spheres'."""
    path, numbers = report.build(small_table, str(tmp_path / "c1"), assembly="clump1", log=lambda m: None)
    text = open(path).read()
    assert "| K paper | -10.2 | 151.9 | -423.7 |" in text
    # the sphere states' Zm (about 5.95) is inside clump1's rising range (below 7.45): no mark;
    # clump2's fits rise only above 6.00 (K) and 6.05 (G), so there the paper's values are marked
    assert "extrapolated" not in text
    text2 = open(report.build(small_table, str(tmp_path / "c2"), assembly="clump2", log=lambda m: None)[0]).read()
    assert "| K paper | 48.1 | -577.4 | 1841.7 | > 0.99 | (" in text2 and "extrapolated) |" in text2
    assert "K rises with Zm only above Zm = 6.00; G rises with Zm only above Zm = 6.05" in text2
    assert "| paper (clump1, its fitted zeta_h, zeta_v) | | | | 0.036 | |" in text
    assert "5.94-5.99" not in text and "paper (spheres" not in text
    assert "### Fig. 4b" in text and "| E_x/E_y against sigma_x/sigma_y | a power law |" in text
    n = numbers["free"]
    tab = chain.state_table([r for r in csv.DictReader(open(small_table))])
    assert n["m"] == pytest.approx(chain.stress_ratio_exponent(tab, chain.HORIZONTAL_PAIRS)["m"])
    assert n["m_vertical"] == pytest.approx(chain.stress_ratio_exponent(tab, chain.VERTICAL_PAIRS)["m"])
    sides = chain.zm_by_sign_of_q([float(r["q"]) for r in csv.DictReader(open(small_table)) if r["probe"] == "z"],
                                  [float(r["Zm"]) for r in csv.DictReader(open(small_table)) if r["probe"] == "z"],
                                  float(next(r["Zm"] for r in csv.DictReader(open(small_table)) if r["state"] == "1")))
    assert "faster at q < 0 | %.3f-%.3f; largest drop below the isotropic state at q < 0: %.3f, at q > 0: %.3f |" % (
        n["Zm"][0], n["Zm"][1], sides["negative"]["drop"], sides["positive"]["drop"]) in text


def test_report_refuses_a_wrong_material_and_bad_input(small_table, tmp_path):
    run = lambda *a: subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", *a], cwd=REPO,  # noqa: E731
                                    capture_output=True, text=True)
    proc = run(small_table, "--out", str(tmp_path / "r"), "--shear-modulus", "28e9")
    assert proc.returncode == 2 and proc.stderr.startswith("error:") and "mic_E" in proc.stderr
    proc = run(str(tmp_path / "missing.csv"))
    assert proc.returncode == 2 and "does not exist" in proc.stderr
    assert not (tmp_path / "r" / "report.md").exists()


def test_shear_probe_rows_leave_the_axial_chain_alone(small_table, tmp_path, text_only):
    """Rows of shear probes (yz, xz, xy: G_ij, no E_i) are skipped, not read as axial probes
    ("yz" is a substring of "xyz": a test on `in "xyz"` took it for y)."""
    with open(small_table) as f:
        rows = list(csv.reader(f))
    k = rows[0].index("probe")
    extra = []
    for r in rows[1:]:
        if r[k] == "x":
            for shear in ("yz", "xz", "xy"):
                extra.append(r[:k] + [shear] + r[k + 1:])
    path = tmp_path / "probes.csv"
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows + extra)
    _, plain = report.build(small_table, str(tmp_path / "a"), log=lambda m: None)
    _, mixed = report.build(str(path), str(tmp_path / "b"), log=lambda m: None)
    assert mixed["free"]["table2"] == plain["free"]["table2"] and mixed["free"]["zeta"] == plain["free"]["zeta"]


def test_table_b1_at_the_isotropic_state_and_state_21(specimen_100, tmp_path):
    """`--statics` solves states 1 and 21 from their checkpoints, once; Table B1 shows both beside
    the paper's; each record's blocked E equals a static solve of the checkpoint done here."""
    from conftest import run_script, one_line_error
    from trueaniso import specimen_file, statics
    out = tmp_path / "study"
    proc = run_script("run_states.py", "--specimen", specimen_100, "--out", out, "--ids", "1,21", "--probes", "z")
    assert proc.returncode == 0, proc.stderr
    env = dict(os.environ, OMP_NUM_THREADS="1")
    cmd = [sys.executable, "-m", "trueaniso.analysis.report", str(out), "--statics", "--out", str(tmp_path / "rep")]
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.count("solving the contact network") == 2
    text = (tmp_path / "rep" / "report.md").read_text()
    for sid in ("1", "21"):
        rec = json.loads((out / ("statics_state-%s.json" % sid)).read_text())
        scene, _ = specimen_file.load(str(out / "states" / ("%s.npz" % sid)))
        E = statics.static_stiffness(scene, rotations=False)["E"] / 1e6
        assert np.allclose(rec["E_blocked"], E * 1e6, rtol=1e-12)
        assert "| ours static solve, rotations blocked | %s | %s | %s | | |" % report._b1_cells(E) in text
    assert "| 21 (b = 0.5, sigma_z = 140 kPa) | paper predicted (zeta = 1) | 455.4 (1.009) | 400.8 (0.947) | 489.7 " \
           "(1.047) |" in text  # the paper prints 1.01, 0.95, 1.05
    assert "Study: 100 spheres (seed 3)" in text and "rolling resistance off (the paper's contact law)" in text
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0 and "solving" not in proc.stderr  # kept, not solved again
    # A table alone (no study beside it) has no checkpoints to solve; the study's own probes.csv
    # stands for its directory (its metadata applies).
    (tmp_path / "bare").mkdir()
    shutil.copy(out / "probes.csv", tmp_path / "bare" / "probes.csv")
    bare = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", str(tmp_path / "bare" / "probes.csv"), "--statics"],
                          cwd=REPO, capture_output=True, text=True, env=env, timeout=300)
    one_line_error(bare, "--statics", "state checkpoints")
    given = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", str(out / "probes.csv"), "--out",
                            str(tmp_path / "rep2")], cwd=REPO, capture_output=True, text=True, env=env, timeout=300)
    assert given.returncode == 0, given.stderr
    assert "Study: 100 spheres (seed 3)" in (tmp_path / "rep2" / "report.md").read_text()  # the study line, from the table alone


B1_OTHER = os.path.join(REPO, "docs", "data", "b1-clump2-1000-s1")


def test_table_b1_takes_state_21_from_a_study_of_another_size(tmp_path):
    """The 4000-clump clump2 study keeps no record of state 21: --b1-data's 1000-clump records
    stand for it, named by their size, beside that specimen's own isotropic state, with the ratios
    state 21 / isotropic of that specimen and of the paper. Expected values from the recipe study's
    own statics.json (clump_recipe_variants.py --study) and from the paper's printed Table B1."""
    study = os.path.join(REPO, "docs", "data", "clump2-4000-s1")
    paper = chain.PAPER["clump2"]
    with open(os.path.join(REPO, "docs", "data", "clump-recipes", "state21-recipe-s1", "statics.json")) as f:
        measured = json.load(f)
    text = "\n".join(report.table_b1(study, paper, "4000 clump2 clumps", B1_OTHER))
    assert "These are 1000 clump2 clumps, not this report's 4000 clump2 clumps." in text
    assert "(1000 clump2 clumps: e 0.6479, Zm 5.532 as prepared)" in text  # the specimen's, docs/studies/clumps.md 5b
    assert "| isotropic, 1000 clump2 clumps | | | | | | |" in text
    blocked = ["| | ours static solve, rotations blocked | %s | %s | %s | | |"
               % report._b1_cells(np.array(measured[s]["E_restrained"]) / 1e6) for s in ("1", "21")]
    state21 = text.index("| 21 (b = 0.5, sigma_z = 140 kPa), 1000 clump2 clumps | paper predicted (zeta = 1) | "
                         "488.5 (1.034) | 441.6 (0.983) | 442.1 (0.984) |")
    assert text.index("| isotropic, 1000 clump2 clumps") < text.index(blocked[0]) < state21 < text.index(blocked[1])
    assert "| 306.7 (1.034) | 235.8 (0.907) | 326.4 (1.067) |" in blocked[1]  # E_i and Eq. 25 of them
    ratios = ", ".join("%.3f" % r for r in measured["ratio_restrained"])
    assert ratios == "0.855, 0.657, 1.064"
    # the paper: 399.9/405.1, 356.6/405.1, 371.2/346.2
    assert "ours %s (1000 clump2 clumps), the paper's 0.987, 0.880, 1.072." % ratios in text
    assert "no statics record" not in text
    # The study's own isotropic row is still its own, once, with the paper's beside it.
    assert text.count("| isotropic | paper predicted (zeta = 1) |") == 1
    assert "| | ours static solve, rotations blocked | 309.3 (1.019) | 313.5 (1.026) | 272.0 (0.956) | | |" in text


def test_table_b1_says_when_no_study_has_state_21(tmp_path):
    """Without --b1-data the clump2 study says it has no record of state 21; a study with its own
    state 21 shows its own, not the other study's, with its own ratios."""
    paper = chain.PAPER["clump2"]
    study = os.path.join(REPO, "docs", "data", "clump2-4000-s1")
    text = "\n".join(report.table_b1(study, paper, "4000 clump2 clumps"))
    assert "State 21: no statics record in this study" in text and "1000 clump2" not in text
    assert "| 21 (b = 0.5" not in text and "E_i at state 21 / E_i at the isotropic state" not in text
    own = tmp_path / "own"
    shutil.copytree(B1_OTHER, own)
    text = "\n".join(report.table_b1(str(own), paper, "1000 clump2 clumps", study))
    assert "| 21 (b = 0.5, sigma_z = 140 kPa) | paper predicted" in text and "This study has no record" not in text
    assert "ours 0.855, 0.657, 1.064 (1000 clump2 clumps)" in text and "not this report's" not in text
    # Records of another specimen of the report's own size are named as such, not as its own.
    text = "\n".join(report.table_b1(study, paper, "1000 clump2 clumps", B1_OTHER))
    assert "| 21 (b = 0.5, sigma_z = 140 kPa), another specimen of 1000 clump2 clumps | paper predicted" in text
    assert "It is not this report's specimen." in text and "| isotropic, another specimen of 1000 clump2" in text
    # Two other studies: each named by its size with its own ratios; the paper's rows once.
    second = tmp_path / "second"
    shutil.copytree(B1_OTHER, second)
    meta = json.loads((second / "metadata.json").read_text())
    meta["specimen"]["summary"]["n"] = 2000
    (second / "metadata.json").write_text(json.dumps(meta))
    for sid in ("1", "21"):  # its records name their study's size too (b1_checks refuses a record of another)
        rec = json.loads((second / ("statics_state-%s.json" % sid)).read_text())
        rec["study"]["n"] = 2000
        (second / ("statics_state-%s.json" % sid)).write_text(json.dumps(rec))
    assert report.study_size(str(second)) == "2000 clump2 clumps"
    text = "\n".join(report.table_b1(study, paper, "4000 clump2 clumps", [B1_OTHER, str(second)]))
    assert text.count("| paper predicted (zeta = 1) |") == 2  # isotropic and state 21
    for size in ("1000", "2000"):
        assert "| 21 (b = 0.5, sigma_z = 140 kPa), %s clump2 clumps |" % size in text
        assert "ours 0.855, 0.657, 1.064 (%s clump2 clumps)" % size in text


def test_b1_data_is_refused_before_anything_is_written(tmp_path):
    """--b1-data without a record of state 21, or of another assembly: one line, no report."""
    from conftest import one_line_error
    env = dict(os.environ, OMP_NUM_THREADS="1")
    no21 = tmp_path / "no21"
    no21.mkdir()
    shutil.copy(os.path.join(B1_OTHER, "statics_state-1.json"), no21)
    shutil.copy(os.path.join(B1_OTHER, "metadata.json"), no21)
    for args, words in (([os.path.join(REPO, "docs", "data", "clump2-4000-s1"), "--b1-data", str(no21)],
                         ("no statics record of state 21",)),
                        ([os.path.join(REPO, "docs", "data", "clump1-4000-s1"), "--b1-data", B1_OTHER],
                         ("is of clump2, not clump1",))):
        proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", *args, "--out", str(tmp_path / "rep")],
                              cwd=REPO, capture_output=True, text=True, env=env, timeout=300)
        one_line_error(proc, *words)
        assert not (tmp_path / "rep").exists()


def test_b1_records_of_a_recipe_study_are_the_committed_ones(tmp_path):
    """b1_records.py converts clump_recipe_variants.py's statics.json: its kinematic prediction
    (the probes row's fabric at the counted density) equals a study's own static-solve record
    (affine stiffness, zeta = 1) to round-off (rtol 1e-12; they agree to 2e-15), and the committed
    docs/data/b1-clump2-1000-s1 is what it writes from the committed recipe study."""
    sys.path.insert(0, os.path.join(REPO, "bench"))
    import b1_records
    study = os.path.join(REPO, "docs", "data", "clump2-4000-s1")
    row = next(r for r in csv.DictReader(open(os.path.join(study, "probes.csv"))) if r["state"] == "1")
    rec = json.load(open(os.path.join(study, "statics_state-1.json")))
    material, _ = report._material(study)
    assert np.allclose(b1_records.kinematic_moduli(row, material), rec["E_kinematic"], rtol=1e-12, atol=0)
    b1_records.main([os.path.join(REPO, "docs", "data", "clump-recipes", "state21-recipe-s1"), "--out",
                     str(tmp_path / "b1")])
    for name in ("statics_state-1.json", "statics_state-21.json", "metadata.json"):
        assert json.load(open(tmp_path / "b1" / name)) == json.load(open(os.path.join(B1_OTHER, name)))


def test_fig16_section_from_the_committed_cross_anisotropic_data(small_table, tmp_path):
    """The Fig. 16 section: its rows are the JSON's ratios, its largest difference computed here."""
    src = os.path.join(REPO, "docs", "data", "fig16-spheres-1000.json")
    path, numbers = report.build(small_table, str(tmp_path), log=lambda m: None, fig16=src)
    text = open(path).read()
    rows = json.load(open(src))
    worst = max(abs(m["G_ratio"] / m["E_ratio_root"] - 1) for m in rows)
    assert numbers["fig16_worst"] == pytest.approx(worst) and 0.03 < worst < 0.04  # 3.5 % at sigma_v/sigma_h 0.5
    m = rows[0]
    assert "| %.2f | %.3f | %.3f |" % (m["sigma_v"] / m["sigma_h"], m["G_ratio"], m["E_ratio_root"]) in text
    assert (tmp_path / "fig16.png").stat().st_size > 5000 and "![Fig. 16](fig16.png)" in text


def test_clump_section_from_the_committed_anisotropy_data(small_table, tmp_path, text_only):
    """E_z/E_x of each clump assembly against the paper's Table B1 DEM row, computed here."""
    src = os.path.join(REPO, "docs", "data", "anisotropy-clumps-4000.json")
    path, numbers = report.build(small_table, str(tmp_path), log=lambda m: None, clumps=src)
    text = open(path).read()
    for m in json.load(open(src)):
        E = m["probe_restrained"]
        paper = chain.PAPER[m["assembly"]]["B1"]["isotropic"]["dem"]
        assert numbers["clump_ratios"][m["assembly"]] == pytest.approx(E[2] / E[0])
        assert "| %.3f | %+.1f %% |" % (E[2] / E[0], 100 * (E[2] / E[0] / (paper[2] / paper[0]) - 1)) in text
    assert numbers["clump_ratios"]["clump1"] > 1.5 and numbers["clump_ratios"]["clump2"] < 1  # the paper's signs


def test_figures_5_to_12_plot_the_table_s_own_numbers(small_table, tmp_path):
    """Figs 5, 6, 8, 9, 10 and 12: what each plots is the probe table's column, state by state, and
    the report's ranges are those of the table."""
    from trueaniso.analysis import figures
    rows = list(csv.DictReader(open(small_table)))
    z = {r["state"]: r for r in rows if r["probe"] == "z"}
    zm = figures.zm_vs_q(rows, str(tmp_path / "f8.png"))
    got = {(round(q, 6), v) for b, (qs, vs) in zm.items() for q, v in zip(qs, vs)}
    assert got == {(round(float(r["q"]) / 1e3, 6), float(r["Zm"])) for r in z.values()}
    ratios = figures.stress_ratios_vs_q(rows, str(tmp_path / "f6.png"))
    got = {(round(q, 6), round(r[0], 12), round(r[2], 12)) for qs, rs in ratios.values() for q, r in zip(qs, rs)}
    assert got == {(round(float(r["q"]) / 1e3, 6), round(float(r["sigma_z"]) / float(r["sigma_x"]), 12),
                    round(float(r["sigma_x"]) / float(r["sigma_y"]), 12)) for r in z.values()}
    R = figures.fabric_vs_stress(rows, str(tmp_path / "f9.png"), "R")
    assert sorted(R["z"][1]) == sorted(float(r["R_zz"]) for r in z.values())
    M = figures.fabric_vs_stress(rows, str(tmp_path / "f12.png"), "M")
    assert sorted(M["x"][1]) == sorted(float(r["M_xxxx"]) for r in z.values())
    nu = figures.poisson_vs_q(rows, str(tmp_path / "f5.png"))
    assert sum(len(q) for q, _ in nu.values()) == len(STATES)
    path, _ = report.build(small_table, str(tmp_path / "rep"), log=lambda m: None)
    text = open(path).read()
    zms = [float(r["Zm"]) for r in z.values()]
    assert "| Fig. 8: Zm against q | 5.94-5.99, falls at large \\|q\\|, alike at q < 0 and q > 0 | %.3f-%.3f;" % (
        min(zms), max(zms)) in text
    for name in ("fig5-nu-vs-q.png", "fig6-stress-ratios.png", "fig8-Zm-vs-q.png", "fig9-R.png", "fig10-H.png",
                 "fig12-B.png", "fig12-M.png"):
        assert (tmp_path / "rep" / name).stat().st_size > 5000 and "](%s)" % name in text


def test_bad_optional_inputs_are_refused_before_anything_is_written(small_table, tmp_path):
    """--fig16 and --clumps given the wrong file, a missing one or a study without shear probes:
    one line of error before the figures, and no output directory."""
    from conftest import one_line_error
    fig16 = os.path.join(REPO, "docs", "data", "fig16-spheres-1000.json")
    clumps = os.path.join(REPO, "docs", "data", "anisotropy-clumps-4000.json")
    for args, words in ((["--clumps", fig16], ("anisotropy_clumps.py", "assembly")),
                        (["--fig16", clumps], ("cross_anisotropy.py", "G_ratio")),
                        (["--fig16", str(tmp_path / "missing.json")], ("cannot read",)),
                        (["--fig16", small_table], ("lacks the columns", "G")),
                        # argparse's choices printed the whole usage, and 'sphere' (the study
                        # scripts' word) was among the refused
                        (["--assembly", "clump3"], ("--assembly", "clump3", "clump1, clump2, spheres"))):
        out = tmp_path / "rep"
        proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", small_table, "--out", str(out), *args],
                              cwd=REPO, capture_output=True, text=True, timeout=300)
        one_line_error(proc, *words)
        assert not out.exists()


def test_no_quadratic_through_two_distinct_zm(small_table, tmp_path):
    """States of one contact network share Zm exactly: three states with two distinct Zm get no
    Table 2 (a fit would warn RankWarning and give an R^2 of 0.87 for what is any parabola through
    two points, as a short cross-anisotropic path can give); the report and the figures say there
    is no fit."""
    with open(small_table) as f:
        rows = list(csv.reader(f))
    s, z = rows[0].index("state"), rows[0].index("Zm")
    keep = [r for r in rows[1:] if r[s] in ("1", "5", "9")]
    shared = next(r[z] for r in keep if r[s] == "5")
    for r in keep:
        if r[s] == "9":
            r[z] = shared
    path = tmp_path / "probes.csv"
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows([rows[0]] + keep)
    with open(path) as f:
        dict_rows = list(csv.DictReader(f))
    with warnings.catch_warnings():
        warnings.simplefilter("error", np.RankWarning)  # numpy's warning of the old fit fails the test
        report_path, numbers = report.build(str(path), str(tmp_path / "rep"), log=lambda m: None)
        assert figures.scalar_moduli_vs_zm(dict_rows, str(tmp_path / "f.png")) is None
    assert "Fewer than 3 distinct Zm among the 3 states" in open(report_path).read()
    assert "table2" not in numbers.get("free", {})
    with pytest.raises(ValueError, match="3 distinct Zm"):
        hyperelastic.quadratic_fit([5.9, 5.8, 5.8], [1.0, 2.0, 3.0])


def test_states_without_rows_are_named(small_table, tmp_path, text_only):
    """A study whose run stopped at states it could not reach gets a report that names the states
    without rows, not only a count of those it has."""
    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(small_table, study / "probes.csv")
    with open(small_table) as f:  # the states as the rows define them: rows of other definitions are refused
        defined = {r["state"]: dict(b=float(r["b"]), sigma_z=float(r["sigma_z_goal"])) for r in csv.DictReader(f)}
    defined.update({sid: dict(b=0.0, sigma_z=1e5) for sid in ("30", "sv50")})
    (study / "metadata.json").write_text(json.dumps(dict(states=defined)))
    path, _ = report.build(str(study), str(tmp_path / "rep"), log=lambda m: None)
    assert "States 30 and sv50 of this study have no row in its table (not reached" in open(path).read()
    del defined["30"], defined["sv50"]
    (study / "metadata.json").write_text(json.dumps(dict(states=defined)))
    path, _ = report.build(str(study), str(tmp_path / "rep2"), log=lambda m: None)
    assert "without a row" not in open(path).read()


def test_a_study_is_compared_with_its_own_assembly(tmp_path, text_only):
    """A report compares a study with the paper's values for its own assembly, not the spheres'
    unless told (the sphere fit would read 36,627 MPa at clump1's Zm 10.3)."""
    study = os.path.join(REPO, "docs", "data", "clump1-4000-s1")
    assert report.study_assembly(study) == "clump1"
    path, _ = report.build(study, str(tmp_path / "rep"), log=lambda m: None)
    assert open(path).read().startswith("# Report: clump1")
    with pytest.raises(ResultsError, match="a study of clump1, not spheres"):
        report.build(study, str(tmp_path / "other"), assembly="spheres", log=lambda m: None)


def test_the_study_line_names_the_path_rate(small_table, tmp_path, text_only):
    """A study made with --path-rate gets a report that says so, telling it from the default's."""
    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(small_table, study / "probes.csv")
    for rate, words in ((2.0, "states reached at the default 2 Pa per step"), (20.0, "states reached at 20.0 Pa per step"),
                        ("inf", "states reached with the whole load at once (--path-rate inf)")):
        (study / "metadata.json").write_text(json.dumps(dict(fingerprint=dict(state=dict(path_rate=rate)))))
        path, _ = report.build(str(study), str(tmp_path / ("rep%s" % rate)), log=lambda m: None)
        assert words in open(path).read()


def test_the_study_line_names_the_time_step_rule(small_table, tmp_path, text_only):
    """A study whose states took the per-axis time step says so; one without the field (every study
    made before the option) or with the default reads as before."""
    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(small_table, study / "probes.csv")
    said = {}
    for rule in (None, "smallest-inertia", "per-axis"):
        state = dict(path_rate=2.0, **({} if rule is None else dict(time_step=rule)))
        (study / "metadata.json").write_text(json.dumps(dict(fingerprint=dict(state=state))))
        path, _ = report.build(str(study), str(tmp_path / ("rep-%s" % rule)), log=lambda m: None)
        said[rule] = "--time-step per-axis" in open(path).read()
    assert said == {None: False, "smallest-inertia": False, "per-axis": True}


def test_the_study_line_names_the_probe_settings(small_table, tmp_path, text_only):
    """A study probed with --skip-detection or rotations restrained does not read like any other in
    its report: the probes' strain, rotations, detection and time step rule are said."""
    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(small_table, study / "probes.csv")
    for probe, words in ((dict(gamma=1e-6, rotations="free", detection="on"),
                          "probes of strain 1e-06, rotations free, contact detection on, time step "
                          "smallest-inertia."),  # a study that records no rule was made with it
                         (dict(gamma=2e-6, rotations="restrained", detection="off", time_step="per-axis"),
                          "probes of strain 2e-06, rotations restrained (--rotations restrained), "
                          "contact detection off (--skip-detection), time step per-axis.")):
        (study / "metadata.json").write_text(json.dumps(dict(fingerprint=dict(state={}, probe=probe))))
        path, _ = report.build(str(study), str(tmp_path / ("rep" + probe["detection"])), log=lambda m: None)
        assert words in open(path).read()


def test_a_zeta_at_its_bound_is_said_to_be_undetermined(tmp_path, text_only):
    """clump2 (docs/data/clump2-4000-s1): the contrast fit stops at zeta_v = 0 and every state's own
    fit at 0: the report says zeta is undetermined, not 'zeta_h = 0.051, zeta_v = 0.000 (fitted)'
    like a result, nor a Spearman correlation over per-state values of 1e-20."""
    from trueaniso.analysis import report
    path, _ = report.build(os.path.join(REPO, "docs", "data", "clump2-4000-s1"), str(tmp_path / "r"), "clump2",
                           log=lambda m: None)
    text = open(path).read()
    assert "zeta_v = 0.000 (fitted, at a bound)" in text
    assert "at a bound of the search (0-5): not determined by these states" in text
    assert "| Spearman rank correlation of zeta with Zm | (zeta independent of state) | n/a |" in text
    assert "or a contrast that does not depend on zeta) | | 37 of 37 |" in text
    # ... and why: a failure of the model, with its evidence (an independent reading of docs/data
    # found per-direction slopes 0.79-0.82 at zeta = 0 and a median per-state zeta of -0.27)
    assert "**The fit stops at a bound: a failure of the model, not noise.**" in text
    assert "with slopes 0.821, 0.820, 0.793 on them" in text
    assert "is negative in 37 of 37 states (median -0.27)" in text
    # Its Table 2 quadratics explain R^2 0.24 (K) and 0.59 (G) over a Zm range of 0.121: the
    # slopes are said to be undetermined there, rather than compared as a factor against the paper's.
    assert ("Over a Zm range of 0.121 the quadratics explain R^2 = 0.24 of K's and 0.59 of G's variation "
            "(below 0.9): these slopes are undetermined by our states") in text


def test_slopes_are_said_undetermined_only_below_the_r2_floor():
    zm = np.array([5.0, 5.1, 5.3])
    strong = dict(K=(1.0, 2.0, 3.0, 0.95), G=(1.0, 2.0, 3.0, 0.999))
    assert report._slopes_undetermined(strong, zm) == []
    weak = dict(K=(1.0, 2.0, 3.0, 0.95), G=(1.0, 2.0, 3.0, 0.899))
    blank, line = report._slopes_undetermined(weak, zm)
    assert blank == "" and "Zm range of 0.300" in line and "R^2 = 0.95 of K's and 0.90 of G's" in line


def test_sphere_and_spheres_name_one_assembly(small_table, tmp_path):
    """prepare_specimen.py and run_study.py say --assembly sphere; the report took only 'spheres'."""
    proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", small_table, "--out", str(tmp_path / "r"),
                           "--assembly", "sphere"], cwd=REPO, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "r" / "report.md").read_text().startswith("# Report: spheres")


def test_three_states_say_their_r2_is_one_by_construction(small_table, tmp_path, text_only):
    """A quadratic through three points fits exactly; the report printed R^2 1.0000 as if a test."""
    path = tmp_path / "probes.csv"
    with open(small_table) as f:
        rows = list(csv.reader(f))
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows([rows[0]] + [r for r in rows[1:] if r[0] in ("1", "9", "21")])
    out, _ = report.build(str(path), str(tmp_path / "r"), log=lambda m: None)
    text = open(out).read()
    assert "## Probes with rotations free: 3 complete states" in text
    assert "Three states: each quadratic of Table 2 passes through its three points" in text
    out, _ = report.build(small_table, str(tmp_path / "r8"), log=lambda m: None)
    assert "Three states" not in open(out).read()


def test_counts_of_states_are_said_in_good_english():
    """'1 state', not '1 states', in the sphere report's zeta rows."""
    assert [report._states(n) for n in (0, 1, 2)] == ["0 states", "1 state", "2 states"]


SMALL_TABLE = os.path.join(REPO, "docs", "data", "table-c1-spheres-4000.csv")


def _edited(tmp_path, edit):
    with open(SMALL_TABLE, newline="") as f:
        rows = list(csv.reader(f))[:7]  # header and the first two states' probes
    edit(rows)
    path = tmp_path / "probes.csv"
    with open(path, "w", newline="") as f:
        csv.writer(f).writerows(rows)
    return str(path)


def _restate(row, state):
    def edit(rows):
        copy = list(rows[row])
        copy[rows[0].index("state")] = state
        rows.append(copy)
    return edit


def _set_E(value):
    def edit(rows):
        rows[2][rows[0].index("E")] = value
    return edit


@pytest.mark.parametrize("edit,words", [
    (lambda rows: rows.extend(rows[1:3]), ["state 1 probe z", "lines 2 and 8", "one row a probe"]),
    # the same state written '1.0' (by hand, or a spreadsheet) is the same state, not another
    (_restate(1, "1.0"), ["state 1 probe z", "lines 2 and 8", "one row a probe"]),
    (_set_E("nan"), ["E = 'nan', not a positive number (line 3)"]),
    (_set_E("-1e8"), ["E = '-1e8', not a positive number"]),
    (_set_E("inf"), ["not a positive number"]),
    (_set_E(""), ["E = '', not a number (line 3)"]),  # the line named
    (lambda rows: rows[2].__setitem__(rows[0].index("nu_1"), "nan"), ["nu_1 = 'nan', not a finite number (line 3)"]),
])
def test_every_analysis_refuses_a_bad_row_the_same_way(tmp_path, edit, words):
    """The shared reader (pyscripts/trueaniso/analysis/results.py) refuses a table appended twice and a modulus that is
    not a positive number, naming the row: figures and path_fidelity used them without a word (a
    NaN E moved the K r^2 from 0.976 to 0.950), the report refused without naming the row."""
    from trueaniso.analysis import results
    path = _edited(tmp_path, edit)
    with pytest.raises(ResultsError) as exc:
        results.read_probes(path)
    assert all(w in str(exc.value) for w in words), str(exc.value)
    for tool in (["trueaniso.analysis.figures", path, "--out", str(tmp_path / "f")], ["trueaniso.analysis.path_fidelity", path],
                 ["trueaniso.analysis.report", path, "--out", str(tmp_path / "r")]):
        proc = subprocess.run([sys.executable, "-m"] + tool, capture_output=True, text=True, cwd=REPO, timeout=120)
        assert proc.returncode == 2 and proc.stderr.strip().startswith("error:") and words[-1] in proc.stderr, \
            (tool, proc.stderr)


def test_a_study_directory_is_taken_for_its_probe_table(tmp_path):
    """trueaniso.analysis.figures, path_fidelity and cross_anisotropy said a study directory 'does not
    exist'; report took it. Each now reads DIR/probes.csv; a directory without one is named so."""
    from trueaniso.analysis import results
    path = _edited(tmp_path, lambda rows: None)
    assert results.read_probes(str(tmp_path)) == results.read_probes(path)
    (tmp_path / "empty").mkdir()
    with pytest.raises(ResultsError, match="is a directory without probes.csv"):
        results.read_probes(str(tmp_path / "empty"))


def test_study_line_of_a_specimen_saved_without_summary(specimen_100, tmp_path):
    """A specimen saved from a YADE scene (specimen_file.save with no summary) gave the report's
    header: e and Zm are taken from state 1's row, and said so, not '? spheres (seed None),
    e = nan and Zm = nan'."""
    from conftest import run_script
    from trueaniso import specimen_file
    scene, _ = specimen_file.load(str(specimen_100))
    bare = tmp_path / "bare.npz"
    specimen_file.save(str(bare), scene)
    out = tmp_path / "study"
    proc = run_script("run_states.py", "--specimen", bare, "--ids", "1", "--probes", "zxy", "--out", out, timeout=300)
    assert proc.returncode == 0, proc.stderr
    line = report._study_line(str(out), list(csv.DictReader(open(out / "probes.csv"))))
    assert line.startswith("Study: 100 spheres (seed not recorded), e = 0.")
    assert "nan" not in line and "from state 1's row" in line


def test_an_os_error_is_said_by_its_file_and_reason(tmp_path):
    """An output the tools cannot write is said by its file and the reason, not '[Errno 30]
    Read-only file system: ...', also through the figures tool."""
    from trueaniso.analysis.results import said
    assert said(OSError(30, "Read-only file system", "/x/report")) == "/x/report: Read-only file system"
    assert said(ResultsError("no rows")) == "no rows"
    blocker = tmp_path / "a-file"
    blocker.write_text("")
    proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.figures", SMALL_TABLE, "--out", str(blocker / "figs")],
                          capture_output=True, text=True, cwd=REPO, timeout=120)
    # (checked before any work, by the scripts' --out check)
    assert proc.returncode == 2 and proc.stderr == "error: --out %s: %s is a file, not a directory\n" % (
        blocker / "figs", blocker), proc.stderr


def test_zeta_contrast_runs_as_a_command_on_a_committed_study(tmp_path):
    """`python3 -m trueaniso.analysis.zeta_contrast DIR` ran nothing and exited 0, --help included (an outside
    check). It prints run_study.py's line, the material from the study's metadata; the committed
    4000-sphere study gives the values its report quotes (docs/report-spheres: zeta 0.116 and 0.111)."""
    def tool(*args):
        return subprocess.run([sys.executable, "-m", "trueaniso.analysis.zeta_contrast", *args], capture_output=True,
                              text=True, cwd=REPO, timeout=120)
    proc = tool(os.path.join("docs", "data", "spheres-4000-s1"))
    assert proc.returncode == 0, proc.stderr
    assert "over 39 states" in proc.stdout and "zeta_h = 0.116 +/- 0.015, zeta_v = 0.111 +/- 0.015" in proc.stdout
    assert tool("--help").stdout.startswith("usage:")
    bare = tmp_path / "probes.csv"
    shutil.copy(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "probes.csv"), bare)
    proc = tool(str(bare))  # no metadata.json beside it: the material must be given
    assert proc.returncode == 2 and "records no particle material" in proc.stderr
    # a file that is no probe table is named as such first (it was asked for the material, then refused)
    spec = tmp_path / "spec.npz"
    spec.write_bytes(b"PK\x03\x04" + bytes(range(200, 256)))
    proc = tool(str(spec))
    assert proc.returncode == 2 and "is not a readable probe table" in proc.stderr, proc.stderr
    # a table with both rotations settings: one at a time, chosen with --rotations
    rows = list(csv.reader(open(bare)))
    col = rows[0].index("rotations")
    mixed = rows + [r[:col] + ["restrained"] + r[col + 1:] for r in rows[1:]]
    with open(bare, "w", newline="") as f:
        csv.writer(f).writerows(mixed)
    material = ["--shear-modulus", "18e9", "--poisson", "0.15"]
    proc = tool(str(bare), *material)
    assert proc.returncode == 2 and "mixes rotations" in proc.stderr and "--rotations" in proc.stderr
    proc = tool(str(bare), *material, "--rotations", "free")
    assert proc.returncode == 0 and "zeta_h = 0.116 +/- 0.015, zeta_v = 0.111 +/- 0.015" in proc.stdout, proc.stderr
    # a torn last row (a run killed mid-write) is left out of the fit, and the command says so
    torn = tmp_path / "torn.csv"
    text = open(os.path.join(REPO, "docs", "data", "spheres-4000-s1", "probes.csv")).read()
    torn.write_text(text + text.splitlines()[1][:40])
    proc = tool(str(torn), *material)
    assert proc.returncode == 0 and "zeta_h = 0.116 +/- 0.015" in proc.stdout, proc.stderr
    assert proc.stderr.startswith("note: %s: the last row was cut short" % torn), proc.stderr


def test_report_says_in_itself_that_a_torn_row_was_left_out(tmp_path):
    """A torn last row (a run killed mid-write) is left out, and report.md itself says so, not the
    terminal only (it would count one complete state fewer without saying why)."""
    study = tmp_path / "study"
    study.mkdir()
    src = os.path.join(REPO, "docs", "data", "spheres-4000-s1")
    shutil.copy(os.path.join(src, "metadata.json"), study / "metadata.json")
    lines = open(os.path.join(src, "probes.csv")).read().splitlines(keepends=True)
    (study / "probes.csv").write_text("".join(lines[:-1]) + lines[-1][:40])
    proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", str(study), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, cwd=REPO, timeout=300)
    assert proc.returncode == 0, proc.stderr
    report = (tmp_path / "out" / "report.md").read_text()
    assert "Left out: %s: the last row was cut short" % (study / "probes.csv") in report
    assert "38 complete states" in report


def test_a_refused_material_leaves_no_output_directory(tmp_path):
    """--shear-modulus -1 is refused before report/ is made: the material is checked first, so no
    empty directory stays behind."""
    for args, words in ((["--shear-modulus", "-1"], "argument --shear-modulus: '-1' is not > 0"),
                        (["--poisson", "0.7"], "argument --poisson: '0.7' is not in (-1, 0.5)")):
        out = tmp_path / "out"
        proc = subprocess.run([sys.executable, "-m", "trueaniso.analysis.report", os.path.join("docs", "data", "spheres-4000-s1"),
                               "--out", str(out), *args], capture_output=True, text=True, cwd=REPO, timeout=120)
        assert proc.returncode == 2 and proc.stderr.startswith("error: " + words), proc.stderr
        assert not out.exists()
