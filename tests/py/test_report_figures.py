"""What the report's figures and its claims rest on: every figure the report makes has labelled
axes with units and text that renders; the nu floor, the a_i^2 regression, the per-state zeta
below 0 and the slopes of Table 2 against values computed here by hand; Table B1's a_i^2; Fig. 16
at the calibrated zeta and at 1; D50 and Cu in the specimen. No simulation: committed data only."""
import csv
import json
import os
import re
import shutil

import numpy as np
import pytest

from conftest import REPO
from trueaniso.analysis import chain, cross_anisotropy, figures, hyperelastic, report

DATA = os.path.join(REPO, "docs", "data")
# The units an axis may carry; "-" marks a dimensionless quantity (a ratio, Zm, a state's index).
UNITS = {"-", "kPa", "MPa", "m$^{7/3}$ N$^{1/3}$"}


def _plain(text):
    """The text outside mathtext ($...$): where a raw _ or ^ shows as itself, unrendered."""
    return re.sub(r"\$[^$]*\$", "", text)


def _figure_problems(fig, name):
    """Every axis labelled with a unit, no raw sub- or superscript, no two axes' boxes (labels,
    ticks, titles, legends) overlapping, nothing outside the figure."""
    fig.canvas.draw()  # parses every mathtext string: a bad one raises here
    renderer = fig.canvas.get_renderer()
    problems = []
    axes = fig.axes
    for ax in axes:
        colorbar = ax.get_label() == "<colorbar>"
        labels = [ax.get_ylabel() or ax.get_xlabel()] if colorbar else [ax.get_xlabel(), ax.get_ylabel()]
        for label in labels:
            unit = re.search(r"\(([^()]*)\)$", label)
            if not label or not unit or unit.group(1) not in UNITS:
                problems.append("%s: axis label %r has no unit in %s" % (name, label, sorted(UNITS)))
        texts = [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        if ax.get_legend():
            texts += [t.get_text() for t in ax.get_legend().get_texts()]
        texts += [t.get_text() for t in ax.get_xticklabels() + ax.get_yticklabels()]
        for t in texts:
            if "_" in _plain(t) or "^" in _plain(t):
                problems.append("%s: %r shows a raw subscript or superscript" % (name, t))
    if fig._suptitle is not None and ("_" in _plain(fig._suptitle.get_text())):
        problems.append("%s: suptitle %r" % (name, fig._suptitle.get_text()))
    boxes = [ax.get_tightbbox(renderer) for ax in axes]
    whole = fig.bbox
    for k, b in enumerate(boxes):
        if b.x0 < whole.x0 - 1 or b.y0 < whole.y0 - 1 or b.x1 > whole.x1 + 1 or b.y1 > whole.y1 + 1:
            problems.append("%s: axes %d reaches outside the figure" % (name, k))
        for m in range(k):
            o = boxes[m]
            if min(b.x1, o.x1) - max(b.x0, o.x0) > 1 and min(b.y1, o.y1) - max(b.y0, o.y0) > 1:
                problems.append("%s: axes %d and %d overlap" % (name, m, k))
    return problems


def test_every_report_figure_has_units_and_readable_labels(small_table, tmp_path, monkeypatch):
    """Every figure the report writes (captured where they are all saved, figures._save) is
    checked before it is written: the set checked is the set of PNG files in the report."""
    seen, problems = [], []
    save = figures._save

    def checked(fig, path):
        seen.append(os.path.basename(path))
        problems.extend(_figure_problems(fig, os.path.basename(path)))
        save(fig, path)
    monkeypatch.setattr(figures, "_save", checked)
    out = tmp_path / "rep"
    report.build(small_table, str(out), log=lambda m: None, fig16=os.path.join(DATA, "fig16-spheres-4000-s1"),
                 clumps=os.path.join(DATA, "anisotropy-clumps-4000.json"))
    assert problems == []
    pngs = sorted(p.name for p in out.glob("*.png"))
    assert sorted(seen) == pngs and len(pngs) == 16  # Figs 3-6, 8-16 (two of 12), the parity plot, zeta-Zm


def test_the_unit_check_catches_a_bare_axis():
    """The check above can fail: an axis without a unit, a raw subscript, two overlapping axes."""
    plt = figures._plt()
    fig, (a, b) = plt.subplots(1, 2, figsize=(3, 2))
    a.set_xlabel("q (kPa)")
    a.set_ylabel("E_i")
    b.set_xlabel("q (kPa)")
    b.set_ylabel("a very long label that runs into the other axes (MPa)", fontsize=20)
    problems = _figure_problems(fig, "bad")
    plt.close(fig)
    assert any("no unit" in p for p in problems) and any("raw subscript" in p for p in problems)
    assert any("overlap" in p or "outside" in p for p in problems)


def test_fig10_plots_the_share_the_table_names(small_table, tmp_path):
    """Fig. 10 plots H_ii / tr H, state by state, and the report's range for it is that of the plot."""
    rows = list(csv.DictReader(open(small_table)))
    z = [r for r in rows if r["probe"] == "z"]
    H = figures.fabric_vs_stress(rows, str(tmp_path / "f10.png"), "H")
    want = sorted(float(r["H_yy"]) / sum(float(r["H_" + a * 2]) for a in "xyz") for r in z)
    assert np.allclose(sorted(H["y"][1]), want, rtol=1e-12)
    text = open(report.build(small_table, str(tmp_path / "rep"), log=lambda m: None)[0]).read()
    vals = np.concatenate([H[a][1] for a in "xyz"])
    assert "| Fig. 10: H_ii / tr H against sigma_i | almost identical, vary slightly | %.3f-%.3f |" % (
        vals.min(), vals.max()) in text


def test_fig15_against_the_state_id_beside_its_parity_plot(small_table, tmp_path):
    text = open(report.build(small_table, str(tmp_path), log=lambda m: None)[0]).read()
    assert "![Fig. 15](fig15-nu.png)" in text and "![Fig. 15, parity](fig15-nu-parity.png)" in text
    assert report._state_order(["10", "2", "1", "x"]) == [2, 1, 0, 3]  # 1, 2, 10, then names


def test_nu_floor_on_a_fixed_table():
    """Two states: one obeys Eq. 22 exactly (anisotropic), the other has nu_xy 0.26 where the
    other five are 0.2 with a_i^2 = 1: nu0 = (5 x 0.2 + 0.26)/6 = 0.21, errors 0.01 five times and
    0.05 once, so RMSE = sqrt((5e-4 + 25e-4) / 12) = 0.0158114, mean |nu| = (0.21 x 6 + ...)/12."""
    a2 = np.array([1.1, 0.95, 1 / (1.1 * 0.95)])
    E_exact = 3e8 * a2 ** 2
    nu_exact = 0.2 * a2[:, None] / a2[None, :]
    nu_bad = np.full((3, 3), 0.2)
    nu_bad[0, 1] = 0.26
    tab = dict(E=np.array([E_exact, np.full(3, 3e8)]), nu=np.array([nu_exact, nu_bad]))
    floor = chain.nu_floor(tab)
    assert floor["rmse"] == pytest.approx(np.sqrt(30e-4 / 12), rel=1e-12)
    off = ~np.eye(3, dtype=bool)
    mean_abs = (nu_exact[off].sum() + 5 * 0.2 + 0.26) / 12
    assert floor["mean_abs"] == pytest.approx(mean_abs, rel=1e-12)
    assert floor["relative"] == pytest.approx(np.sqrt(30e-4 / 12) / mean_abs, rel=1e-12)
    assert chain.relative_nu_rmse(tab, 0.01) == pytest.approx(0.01 / mean_abs, rel=1e-12)


@pytest.mark.parametrize("study, floor", [("spheres-4000-s1", 0.0049), ("clump1-4000-s1", 0.0040),
                                          ("clump2-4000-s1", 0.0156)])
def test_nu_floor_of_the_committed_studies(study, floor):
    """The floors an independent reading of docs/data found, to their printed digits (5e-5)."""
    tab = chain.state_table(list(csv.DictReader(open(os.path.join(DATA, study, "probes.csv")))))
    assert chain.nu_floor(tab)["rmse"] == pytest.approx(floor, abs=5e-5)


def test_a2_regression_and_table2_slopes_by_hand():
    x = np.array([[0.9, 1.0, 1.1], [0.8, 1.05, 1.2]])
    reg = chain.a2_regression(x, 0.8 * x + 0.2)
    assert reg["slope"] == pytest.approx(0.8, rel=1e-12) and reg["intercept"] == pytest.approx(0.2, rel=1e-11)
    assert reg["r"] == pytest.approx(1.0, abs=1e-12)
    # K = Zm^2 + 2 Zm + 3 (ours), paper 2 Zm^2 - 1 Zm: at Zm = 2, 6 against 7; the straight line
    # through (1, 6), (2, 11), (3, 18) has slope 6
    tab = dict(Zm=np.array([1.0, 2.0, 3.0]), K=np.array([6.0, 11.0, 18.0]) * 1e6, G=np.array([6.0, 11.0, 18.0]) * 1e6)
    fits = dict(K=(1.0, 2.0, 3.0, 1.0), G=(1.0, 2.0, 3.0, 1.0))
    sl = chain.table2_slopes(tab, fits, dict(K=(2.0, -1.0, 0.0), G=(2.0, -1.0, 0.0)), 2.0)
    assert sl["K"]["ours"] == pytest.approx(6.0) and sl["K"]["paper"] == pytest.approx(7.0)
    assert sl["K"]["ours_line"] == pytest.approx(6.0) and sl["G"]["ratio"] == pytest.approx(7.0 / 6.0)


def test_a_contrast_beyond_zeta_zero_gives_a_negative_zeta():
    """DEM moduli made by C = A_n + zeta A_s at zeta = -0.2: the bounded per-state fit stops at its
    bound (None), the search below 0 finds -0.2."""
    rng = np.random.default_rng(5)
    A_s = np.array([[1.0, 0.2, 0.2], [0.2, 1.0, 0.2], [0.2, 0.2, 1.0]]) * 1e8
    ref_n = np.array([[3.0, 1.0, 1.0], [1.0, 3.0, 1.0], [1.0, 1.0, 3.0]]) * 1e8
    An, As, E = [ref_n], [A_s], []
    for k in range(3):
        d = np.diag(1 + 0.3 * rng.random(3))
        An.append(d @ ref_n @ d)
        As.append(A_s)
    An, As = np.array(An), np.array(As)
    for n_, s_ in zip(An, As):
        E.append(chain._young_one(n_, s_, -0.2))
    tab = dict(state=["1", "2", "3", "4"], E=np.array(E), a2_dem=hyperelastic.fabric_a2(np.array(E)))
    below = chain.zeta_below_zero(tab, (An, As), 0)
    assert set(below) == {"2", "3", "4"}
    for v in below.values():
        assert v == pytest.approx(-0.2, abs=1e-5)
    assert all(v is None for v in chain.zeta_per_state(tab, (An, As), 0).values())


def test_table_b1_prints_each_e_with_its_a2(tmp_path):
    """The committed 4000-sphere study's statics records: each E_i with a_i^2 = (E_i^2 / (E_j E_k))^(1/6)."""
    src = os.path.join(DATA, "spheres-4000-s1")
    lines = report.table_b1(src, chain.PAPER["spheres"], "4000 spheres")
    text = "\n".join(lines)
    rec = json.load(open(os.path.join(src, "statics_state-21.json")))
    E = np.array(rec["E_blocked"]) / 1e6
    a2 = [(E[i] ** 2 / (E[(i + 1) % 3] * E[(i + 2) % 3])) ** (1 / 6) for i in range(3)]
    assert "| | ours static solve, rotations blocked | %.1f (%.3f) | %.1f (%.3f) | %.1f (%.3f) | | |" % (
        E[0], a2[0], E[1], a2[1], E[2], a2[2]) in text
    # the paper's own a_i^2 of Table B1 (printed to two decimals) from its E_i: clump2 state 21's DEM row
    paper = chain.PAPER["clump2"]["B1"]["21"]["dem"]
    assert [round(v, 2) for v in hyperelastic.fabric_a2(paper)] == [1.03, 0.97, 0.99]
    assert "(4000 spheres)" in text
    # clump2 has no state-21 record: said so
    assert "State 21: no statics record" in "\n".join(report.table_b1(os.path.join(DATA, "clump2-4000-s1"),
                                                                      chain.PAPER["clump2"]))


def test_fig16_at_the_calibrated_zeta_the_papers_and_one(small_table, tmp_path, monkeypatch):
    """Recomputed from the fabric columns at zeta = 1 the prediction is the table's own (its rows'
    mic_E at mic_zeta 1); at the calibrated zeta it differs; the figure is also given the curve at
    the paper's zeta 0.552 (its Fig. 16a), and its title names the cross-anisotropic study's size
    and seed: all three curves in the report's table and in the data the figure draws."""
    src = os.path.join(DATA, "fig16-spheres-4000-s1")
    rows = cross_anisotropy.states(src + "/probes.csv")
    at1 = cross_anisotropy.predicted_ratios(src + "/probes.csv", 18e9, 0.15, 1.0, 1.0)
    for m in rows:
        assert m["predicted_zeta"] == 1.0
        assert at1[m["state"]] == pytest.approx(m["predicted_ratio"], rel=1e-9)
    drawn = {}
    figure = cross_anisotropy.figure

    def kept(rows_, path, predictions=None, who=None):
        drawn.update(predictions=predictions, who=who)
        figure(rows_, path, predictions, who)
    monkeypatch.setattr(cross_anisotropy, "figure", kept)
    path, numbers = report.build(small_table, str(tmp_path), log=lambda m: None, fig16=src)
    text = open(path).read()
    zh, zv = numbers["free"]["zeta"]
    calibrated = cross_anisotropy.predicted_ratios(src + "/probes.csv", 18e9, 0.15, zh, zv)
    paper = cross_anisotropy.predicted_ratios(src + "/probes.csv", 18e9, 0.15, 0.552, 0.552)
    assert "predicted a_h^2/a_v^2, zeta_h = %.3f, zeta_v = %.3f (calibrated on this report's study)" % (zh, zv) in text
    assert "predicted a_h^2/a_v^2, zeta = 0.552 (the paper's)" in text
    assert "predicted a_h^2/a_v^2, zeta = 1 (unmodified)" in text
    first = rows[0]
    assert "| %.3f | %.3f | %.3f |" % (calibrated[first["state"]], paper[first["state"]],
                                       first["predicted_ratio"]) in text
    assert "From `%s`, 4000 spheres." % src in text
    curve = next(c for c in drawn["predictions"] if "0.552" in c[0])
    assert curve[1] == pytest.approx([paper[m["state"]] for m in rows], rel=1e-12)
    assert drawn["who"] == "4000 spheres, seed 1"


def test_d50_and_cu_are_stored_and_old_files_still_load(tmp_path):
    """specimen.state stores D50 and Cu by mass of the equal-volume diameters; a committed file
    written before has neither and still loads; the schema refuses a D50 that is not > 0; the
    report says "not stored" for a study whose specimen lacks them."""
    from trueaniso import psd, specimen, specimen_file, validate
    old = os.path.join(REPO, "tests", "data", "spheres-150-s6.npz")
    scene, meta = specimen_file.load(old)
    assert "d50" not in meta["summary"]
    d50, cu = specimen.d50_cu(scene)
    d = 2 * np.asarray(scene.radii)  # spheres: the equal-volume diameter is the diameter
    w = np.sort(d) ** 3
    cum = (np.cumsum(w) - 0.5 * w) / w.sum()
    assert d50 == pytest.approx(np.interp(0.5, cum, np.sort(d)), rel=1e-12)
    assert cu == pytest.approx(np.interp(0.6, cum, np.sort(d)) / np.interp(0.1, cum, np.sort(d)), rel=1e-12)
    assert 0.18e-3 < d50 < 0.21e-3 and 1.1 < cu < 1.4  # drawn from the paper's 0.195 mm, 1.25
    new = tmp_path / "new.npz"
    saved = specimen_file.save(str(new), scene, seed=6, summary=dict(meta["summary"], d50=d50, cu=cu))
    assert specimen_file.load(str(new))[1]["summary"]["d50"] == d50 == saved["summary"]["d50"]
    bad = dict(meta, summary=dict(meta["summary"], d50=-1.0))
    with pytest.raises(ValueError, match="d50"):
        validate.check(bad, "specimen", "x.npz", ValueError)
    assert psd.PAPER_D50_CU["clump2"] == (0.216e-3, 1.43)
    study = tmp_path / "study"
    shutil.copytree(os.path.join(DATA, "clump2-4000-s1"), study)
    assert "D50 and Cu not stored in the specimen (paper: 0.216 mm, 1.43)" in report._study_line(str(study))
    m = json.load(open(study / "metadata.json"))
    m["specimen"]["summary"].update(d50=0.2161e-3, cu=1.4312)
    json.dump(m, open(study / "metadata.json", "w"))
    assert "D50 = 0.216 mm and Cu = 1.43 (paper: 0.216 mm, 1.43)" in report._study_line(str(study))


def test_fig16b_on_clump2_names_its_size(tmp_path):
    """The committed clump2 cross-anisotropic study (1000 clumps) in a report of another size says
    so; its largest G_hh/G_vh against (E_h/E_v)^0.5 difference is computed here."""
    src = os.path.join(DATA, "fig16-clump2-1000-s1")
    rows = report.fig16_rows(src)
    lines, worst = report.fig16_section(rows, src, str(tmp_path), (0.05, 0.0), dict(shear_modulus=18e9, poisson=0.15),
                                        "4000 clump2 clumps")
    text = "\n".join(lines)
    assert "1000 clump2 clumps. These are 1000 clump2 clumps, not this report's 4000 clump2 clumps." in text
    assert worst == pytest.approx(max(abs(m["G_ratio"] / m["E_ratio_root"] - 1) for m in rows))
    assert 0.13 < worst < 0.14 and len(rows) == 11
    assert (tmp_path / "fig16.png").stat().st_size > 5000


def _marker_and_colour(artist):
    """(the marker's outline in points, its RGBA face colour) of a scatter's series or of a legend
    entry (a scatter's own PathCollection, or a Line2D drawn with a marker)."""
    from matplotlib.collections import PathCollection
    from matplotlib.markers import MarkerStyle
    if isinstance(artist, PathCollection):
        return artist.get_paths()[0].vertices, [tuple(c) for c in artist.get_facecolors()]
    style = MarkerStyle(artist.get_marker())
    rgba = figures._plt().matplotlib.colors.to_rgba(artist.get_markerfacecolor())
    return style.get_path().transformed(style.get_transform()).vertices, [rgba]


def test_fig13_legend_tells_each_axis_by_its_marker_in_no_zm_colour(tmp_path, monkeypatch):
    """Fig. 13 colours every point by its Zm, so a legend entry must show its series' marker and a
    colour no point has: a Zm colour would stand for one Zm, and the three a_i^2 entries in the same
    one could only be told apart by their outline."""
    caught = []
    monkeypatch.setattr(figures, "_save", lambda fig, path: caught.append(fig))
    plt = figures._plt()
    monkeypatch.setattr(plt, "close", lambda fig=None: None)  # the figure is read below, after _save
    a2 = np.array([[1.05, 0.97, 0.98], [0.95, 1.02, 1.03], [1.0, 1.0, 1.0]])
    tab = dict(a2_dem=a2, Zm=np.array([5.6, 5.8, 6.0]))
    report.fig13(tab, [("zeta = 1", a2 * 1.01), ("zeta = 0.5", a2 * 0.99)], str(tmp_path / "f13.png"))
    (fig,) = caught
    fig.canvas.draw()  # the points take their Zm colours when drawn
    # One legend for the panels, beside the last (off the data); its entries hold for each panel.
    (legend,) = [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    assert legend is fig.axes[1].get_legend()
    for ax in fig.axes[:2]:
        series = ax.collections[:3]
        point_colours = {c for s in series for c in _marker_and_colour(s)[1]}
        handles = getattr(legend, "legend_handles", None) or legend.legendHandles
        entries = dict(zip([t.get_text() for t in legend.get_texts()], handles))
        for a, s in zip("xyz", series):
            outline, colours = _marker_and_colour(entries["$a_%s^2$" % a])
            np.testing.assert_allclose(outline, _marker_and_colour(s)[0], atol=1e-12)  # the series' own marker
            assert not point_colours & set(colours), "legend entry a_%s^2 is drawn in a Zm colour" % a
    plt.close(fig)
