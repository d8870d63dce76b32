"""docs/report-paper-size/summary.md: its tables are what trueaniso.analysis.paper_summary writes from the
committed studies, the judgement against the paper is the one its page states, and what its
reading says of the departures holds."""
import math
import os
import re
import subprocess
import sys

import pytest

from conftest import REPO, assert_page_is_its_data
from trueaniso.analysis import paper_summary, seeds

DATA = os.path.join(REPO, "docs", "data")
STUDIES = (("spheres-53004-s1", "spheres-4000"), ("clump1-16000/s1", "clump1-2000"), ("clump2-16000/s1", "clump2-2000"))


def argv():
    out = []
    for study, seed_dir in STUDIES:
        out += ["--study", os.path.join(DATA, study), "--seeds"] + [os.path.join(DATA, seed_dir, "s%d" % k) for k in (1, 2, 3)]
    return out


def test_the_page_is_its_data(tmp_path):
    assert_page_is_its_data(tmp_path, "report-paper-size/summary.md",
                            lambda doc: paper_summary.main(argv() + ["--doc", doc, "--block", "summary"]))


def test_the_sd_bound_of_three_seeds_is_the_closed_form():
    """Two degrees of freedom: chi2's 5 % quantile is -2 ln 0.95, so the bound is sqrt(2 / that)."""
    assert paper_summary.sd_bound(3) == pytest.approx(math.sqrt(2.0 / (-2.0 * math.log(0.95))), rel=1e-12)
    assert paper_summary.sd_bound(3) == pytest.approx(4.415, abs=5e-4)  # the page's 4.4 and 8.8
    assert paper_summary.sd_bound(1) is None


def test_the_judgement_against_the_paper():
    """In the sd of a difference of two packings, sqrt(2) times the seeds'."""
    judge = paper_summary.against_paper
    r2 = math.sqrt(2.0)
    assert judge(1.0, 1.0 + 1.9e-3 * r2, 1e-3, 3) == ("-1.9 sd", "agrees")
    assert judge(1.0, 1.0 + 2.1e-3 * r2, 1e-3, 3) == ("-2.1 sd", "departs")
    assert judge(1.0, 1.0 + 9e-3 * r2, 1e-3, 3) == ("-9.0 sd", "departs, established")  # beyond 2 x 4.415
    assert judge(1.0, 1.0 + 8.5e-3 * r2, 1e-3, 3)[1] == "departs"
    assert judge(1.0, 1.0 + 9e-3 * r2, 1e-3, 30)[1] == "departs, established"  # more seeds, a tighter bound
    assert judge(1.0, 1.0 + 1e-6, 1e-3, 3) == ("0.0 sd", "agrees")  # no "-0.0"
    # A range is judged from its nearest edge, a bound from its one edge.
    assert judge(5.95, "5.94-5.99", 0.01, 3) == ("inside", "agrees")
    assert judge(5.94 - 0.04 * r2, "5.94-5.99", 0.01, 3) == ("-4.0 sd", "departs")
    assert judge(5.99 + 0.06 * r2, "5.94-5.99", 0.01, 3) == ("+6.0 sd", "departs")
    assert judge(0.04, "<= 0.05 (over the states)", 0.005, 3) == ("inside", "agrees")
    assert judge(0.05 + 0.02 * r2, "<= 0.05 (over the states)", 0.005, 3) == ("+4.0 sd", "departs")
    # Without a scatter, only the difference is said; words are not judged.
    assert judge(1.1, 1.0, None, 1) == ("+10.0 %", None)
    assert judge(1.1, 1.0, 0.0, 3) == ("+10.0 %", None)
    assert judge(0.1, "approximately constant", 0.01, 3) == ("", None)
    assert judge(None, 1.0, 0.01, 3) == ("", None)


def test_what_the_reading_says_of_the_departures_holds():
    """Predicted / DEM: ours 4-9 % above 1, the paper's 9-22 %; times each state's Zm/Z, clump2's
    meets the paper's at the isotropic state (1.209 against 1.206) and overshoots at state 21 (1.247
    against 1.217), the spheres' and clump1's stay 0.02 and 0.07 short. The spheres' K and G 1.7 % and
    4.5 % above Table 2 at Zm 5.925, below the quadratics' minima at 5.94; 27 numbers judged."""
    import csv
    ours, theirs, scaled = [], [], {}
    for study, _ in STUDIES:
        h = seeds.headlines(os.path.join(DATA, study))
        assembly = {"sphere": "spheres"}.get(h["assembly"], h["assembly"])
        p = seeds.paper_values(assembly)
        with open(os.path.join(DATA, study, "probes.csv")) as f:
            rows = {r["state"]: r for r in csv.DictReader(f)}
        for state, key in (("1", "B1_pred_dem_iso"), ("21", "B1_pred_dem_21")):
            ours.append(h[key])
            theirs.append(p[key])
            r = rows[state]
            zm_over_z = float(r["Zm"]) / (2.0 * float(r["Nc"]) / float(r["Np"]))
            scaled[assembly, state] = (round(h[key] * zm_over_z, 3), round(p[key], 3))
        if assembly == "spheres":
            k, g = seeds.paper_K_G("spheres", h["Zm_iso"])
            assert round(100 * (h["K_iso"] / k - 1), 1) == 1.7 and round(100 * (h["G_iso"] / g - 1), 1) == 4.5
            assert round(h["Zm_iso"], 3) == 5.925
            for c in (chain_coefficients("K"), chain_coefficients("G")):
                assert round(-c[1] / (2 * c[0]), 2) == 5.94
    assert scaled["clump2", "1"] == (1.209, 1.206) and scaled["clump2", "21"] == (1.247, 1.217)
    assert scaled["spheres", "1"] == (1.070, 1.091) and scaled["clump1", "1"] == (1.048, 1.114)
    assert 0.04 <= min(ours) - 1 and max(ours) - 1 < 0.095
    assert 0.09 <= min(theirs) - 1 and max(theirs) - 1 < 0.22
    with open(os.path.join(REPO, "docs", "report-paper-size", "summary.md")) as f:
        page = f.read()
    table = page.split("<!-- summary:begin -->")[1].split("## The departures that remain")[0]
    assert len(re.findall(r": (agrees|departs)", table)) == 27


def chain_coefficients(key):
    from trueaniso.analysis import chain
    return chain.PAPER["spheres"][key]


def test_bad_arguments_are_refused_in_a_line():
    script = [sys.executable, "-m", "trueaniso.analysis.paper_summary"]
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO, "pyscripts"))
    for args, said in ((["--seeds", os.path.join(DATA, "spheres-4000", "s1")], "--seeds comes after the --study"),
                       ([os.path.join(DATA, "spheres-4000", "s1")], "a study directory goes after --study"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds",
                         os.path.join(DATA, "clump1-2000", "s1")], "its --seeds are of another assembly"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--doc", "x.md"], "--doc and --block go together"),
                       (["--study"], "--study needs a value"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds"], "--seeds names no study directory"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds", os.path.join(DATA, "spheres-4000", "s1"),
                         "--seeds"], "--seeds given twice"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--doc", os.path.join(DATA, "none.md"),
                         "--block", "summary"], "none.md: cannot read it"),
                       # a study without its specimen's record (fig16-s1, of s1's specimen), a seed twice
                       (["--study", os.path.join(DATA, "spheres-4000", "fig16-s1"), "--seeds",
                         os.path.join(DATA, "spheres-4000", "s1"), os.path.join(DATA, "spheres-4000", "s2")],
                        "fig16-s1 records no recipe"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds"] +
                        [os.path.join(DATA, "spheres-4000", "s1")] * 2, "one specimen counted twice"),
                       (["--study", os.path.join(DATA, "clump1-16000", "s1"), "--seeds",
                         os.path.join(DATA, "clump1-recipes", "mu-prep-0.01"),
                         os.path.join(DATA, "clump1-recipes", "mu-prep-0.01-s2")], "mu-prep-0.01 records no recipe"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds",
                         os.path.join(DATA, "switch-pressure", "spheres-4000-s1-switch5kpa"),
                         os.path.join(DATA, "spheres-4000", "s2")], "not one recipe"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--study",
                         os.path.join(DATA, "spheres-16000", "s1")], "one --study an assembly"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds", os.path.join(DATA, "spheres-4000", "s1"),
                         "--doc", "x.md", "--block", "b", os.path.join(DATA, "spheres-4000", "s2")],
                        "a study directory goes after --study"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--seeds", "--study",
                         os.path.join(DATA, "clump1-16000", "s1")], "--seeds names no study directory"),
                       (["--study", os.path.join(DATA, "spheres-53004-s1"), "--sead"], "--sead: no such option")):
        proc = subprocess.run(script + args, capture_output=True, text=True, env=env)
        assert proc.returncode == 2 and said in proc.stderr and "Traceback" not in proc.stderr, (args, proc.stderr)


def test_a_read_only_page_is_not_rewritten(tmp_path):
    doc = tmp_path / "page.md"
    doc.write_text("<!-- b:begin -->\nold\n<!-- b:end -->\n")
    doc.chmod(0o444)  # refused by its mode, for root too (who may write it)
    with pytest.raises(seeds.ResultsError, match="read-only"):
        seeds.write_block(str(doc), "b", "new")
    assert doc.read_text() == "<!-- b:begin -->\nold\n<!-- b:end -->\n"


def test_one_seed_or_none_is_not_judged():
    """Without two seeds there is no sd: the table gives the difference in per cent, no verdict, and
    the departures say which assembly was not judged."""
    one = seeds.headlines(os.path.join(DATA, "spheres-4000", "s1"))
    study = seeds.headlines(os.path.join(DATA, "spheres-53004-s1"))
    for seed_heads, said in (([one], "4000, 1 seed"), ([], "none given")):
        text = paper_summary.summary([(study, seed_heads)])
        assert "seeds (%s)" % said in text and "departs" not in text and "agrees" not in text
        assert "| e | 0.5795 | %s | 0.5840 | -0.8 %% |" % ("0.5770" if seed_heads else "-") in text
        assert text.endswith("Not judged, for want of two seeds or more: spheres.\n")
