"""docs/studies/paper-size.md, "Size series, seed 1": the three tables are what trueaniso.analysis.seeds
writes from the committed studies (one column a size, seed 1), and what the readings say of them holds."""
import os

from conftest import REPO, assert_page_is_its_data
from trueaniso.analysis import seeds

DATA = os.path.join(REPO, "docs", "data")
SERIES = {"size-series-spheres": ("spheres", ["spheres-1000/s1", "spheres-4000/s1", "spheres-16000/s1",
                                             "spheres-53004-s1"]),
          "size-series-clump2": ("clump2", ["clump2-1000/s1", "clump2-2000/s1", "clump2-4000/s1",
                                            "clump2-16000/s1"]),
          "size-series-clump1": ("clump1", ["clump1-2000/s1", "clump1-4000/s1", "clump1-16000/s1"])}


def headlines(block):
    return [seeds.headlines(os.path.join(DATA, d)) for d in SERIES[block][1]]


def test_the_size_series_tables_are_those_of_their_data(tmp_path):
    for block, (assembly, dirs) in SERIES.items():
        text = seeds.table([("", [h]) for h in headlines(block)], assembly)
        assert_page_is_its_data(tmp_path, "studies/paper-size.md", lambda doc: seeds.write_block(doc, block, text))


def test_what_the_readings_say_of_clump2_holds():
    """e does not keep falling with size (16,000 above 4000, within 0.005 of the paper's 0.636); the nu
    RMSE is lowest at 16,000; the departures hold at every size."""
    h = headlines("size-series-clump2")
    e = [x["e"] for x in h]
    assert e[0] > e[1] > e[2] < e[3] and abs(e[3] - 0.636) < 0.005
    rmse = [x["nu_rmse"] for x in h]
    assert rmse[3] == min(rmse) and rmse[3] < 0.008 < min(rmse[:3])
    assert all(0.45 < x["Zm_drop"] < 0.6 for x in h)


def test_what_the_readings_say_of_clump1_holds():
    """Size moves nothing beyond the 2000-clump seeds' scatter (e within 0.004 of each other and of the
    paper's 0.445, E_z/E_x within 0.05, Table B1's ratios within 0.002); the preparation's steps grow
    with size."""
    h = headlines("size-series-clump1")
    e = [x["e"] for x in h]
    assert max(e) - min(e) < 0.004 and all(abs(x - 0.445) < 0.004 for x in e)
    ez = [x["Ez_Ex"] for x in h]
    assert max(ez) - min(ez) < 0.05 and all(x < 1.9 for x in ez)
    for i in range(3):
        r = [x["B1_ratio"][i] for x in h]
        assert max(r) - min(r) <= 0.002
    steps = [x["prep_steps"] for x in h]
    assert steps[0] < steps[1] < steps[2]


def test_the_cost_table_is_that_of_its_data(tmp_path):
    from trueaniso.analysis import cost
    studies = [os.path.join(REPO, "docs", "data", d) for d in ("spheres-16000/s1", "spheres-53004-s1", "clump2-16000/s1",
                                                                 "clump1-16000/s1")]
    assert_page_is_its_data(tmp_path, "studies/paper-size.md",
                            lambda doc: cost.main(studies + ["--doc", doc, "--block", "paper-size-cost"]))
    # What the reading says: the longest path and the static solves' growth.
    c = {cost.name(s): cost.study_cost(s) for s in studies}
    assert round(c["spheres-53004-s1"]["paths"][0] / 60) == 46
    assert round(c["spheres-53004-s1"]["statics"][0] / c["spheres-16000/s1"]["statics"][0]) == 77


def test_what_the_creep_paragraph_says_holds():
    """The clump2-69532 free expansion stepped on from its checkpoint: below the target in every sample,
    by 180-245 Pa (mean 209), the radii growing by 1.09e-9 a step (bench/expansion_creep.py's record)."""
    import json
    with open(os.path.join(DATA, "expansion-creep", "clump2-69532-s1-at-222000.jsonl")) as f:
        lines = [json.loads(x) for x in f]
    samples, summary = lines[:-1], lines[-1]
    errors = [s["error"] for s in samples]
    assert len(samples) == 32 and all(e > 0 for e in errors) and summary["one_sign"]
    assert round(min(errors)) == 180 and round(max(errors)) == 245 and round(summary["error_mean"]) == 209
    assert round(summary["growth_per_step"], 11) == 1.09e-9 and summary["expansion_steps_before"] == 222000
    assert summary["gain"] == 0.002 and summary["stress_tolerance"] == 100.0 and summary["target"] == 1e5
    assert round(summary["trend_per_1000_steps"], 1) == -2.9 and summary["criterion_met_at"] is None


def test_what_the_fig16_section_says_holds():
    """Fig. 16 at 53,004 spheres: the Table C1 study's packing (e and Zm of the specimen the same to the
    last digit), eleven states each reached within 17 steps of the 4000-sphere count, G_hh/G_vh within
    1.2 % of (E_h/E_v)^0.5 (4000: 2.4 %), the calibrated prediction within 0.3 % (0.4 %)."""
    import json
    from trueaniso.analysis import cross_anisotropy, results
    big, small = os.path.join(DATA, "fig16-spheres-53004-s1"), os.path.join(DATA, "spheres-4000", "fig16-s1")
    with open(os.path.join(DATA, "spheres-53004-s1", "specimen.json")) as f:
        table_c1 = json.load(f)["summary"]
    fig16 = results.read_metadata(big, required=True)["specimen"]["summary"]
    assert (fig16["void_ratio"], fig16["Zm"], fig16["Nc"]) == (table_c1["void_ratio"], table_c1["Zm"], table_c1["Nc"])

    def steps(d):
        return {r["state"]: int(r["state_steps"]) for r in results.read_probes(os.path.join(d, "probes.csv"),
                                                                             ("state", "state_steps"))}
    a, b = steps(big), steps(small)
    assert sorted(a) == sorted(b) and len(a) == 11 and a["sv90"] == b["sv90"] == 3323
    assert max(abs(a[k] - b[k]) for k in a) == 17

    def worst(d, study):
        """G_hh/G_vh's and the prediction's largest gaps to (E_h/E_v)^0.5, at the zeta_h and zeta_v
        calibrated on the Table C1 study of the same size (as the report's Fig. 16 section)."""
        rows = cross_anisotropy.states(d)
        h = seeds.headlines(os.path.join(DATA, study))
        pred = cross_anisotropy.predicted_ratios(d, 18e9, 0.15, h["zeta_h"], h["zeta_v"])
        return (max(abs(r["G_ratio"] / r["E_ratio_root"] - 1) for r in rows),
                max(abs(pred[r["state"]] / r["E_ratio_root"] - 1) for r in rows))
    g_big, p_big = worst(big, "spheres-53004-s1")
    g_small, p_small = worst(small, "spheres-4000/s1")
    assert round(100 * g_big, 1) == 1.2 and round(100 * g_small, 1) == 2.4
    assert round(100 * p_big, 1) == 0.3 and round(100 * p_small, 1) == 0.4


def test_what_the_clump2_69532_preparation_says_holds():
    """334,000 steps in all (302,000 of them the free expansion after 30,000 of the first stages), 1.5
    times the 4000-clump count the estimate takes; 34,165 s of wall time; e 0.6278, Zm 6.280."""
    import json
    from trueaniso import resources
    with open(os.path.join(DATA, "clump2-69532", "s1", "specimen.json")) as f:
        rec = json.load(f)
    p, s = rec["parameters"], rec["summary"]
    assert p["n"] == 69532 and p["seed"] == 1 and p["steps_expansion"] == 332000 and p["steps_consolidation"] == 2000
    assert round((p["steps_expansion"] + p["steps_consolidation"]) / resources.PREPARATION_STEPS["clump2"], 1) == 1.5
    assert round(p["wall_time"]) == 34165
    assert (round(s["void_ratio"], 4), round(s["Zm"], 3), s["Np0"]) == (0.6278, 6.280, 8226)
