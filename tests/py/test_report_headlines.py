"""The report's headline table over seeds (--seeds) and what every figure says of itself: its
assembly, particle count and seed and its question in the title, the paper's values drawn (Fig. 11's
quadratics), legends that cover no point, at least three labelled ticks per axis (Fig. 4's log axes),
and Table B1's N_c/V said. Committed studies cut to a few states: no simulation."""
import csv
import json
import os
import shutil
import statistics

import numpy as np
import pytest

from conftest import REPO, SMALL_TABLE_STATES
from trueaniso.analysis import chain, figures, report
from trueaniso.analysis.results import ResultsError

DATA = os.path.join(REPO, "docs", "data")


def _cut_study(src, dst, keep=("metadata.json", "specimen.json", "statics_state-1.json", "statics_state-21.json")):
    """A copy of the committed study `src` with the probe rows of SMALL_TABLE_STATES only (a report
    in seconds) and its files named in `keep` where it has them."""
    os.makedirs(dst)
    for name in keep:
        if os.path.exists(os.path.join(src, name)):
            shutil.copy(os.path.join(src, name), dst)
    with open(os.path.join(src, "probes.csv")) as f:
        rows = list(csv.reader(f))
    with open(os.path.join(dst, "probes.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(rows[0])
        at = rows[0].index("state")
        w.writerows(r for r in rows[1:] if r[at] in SMALL_TABLE_STATES)
    return dst


@pytest.fixture(scope="module")
def three_seeds(tmp_path_factory):
    """The three committed 1000-sphere seeds of one recipe (docs/data/seeds/sphere-1000-s1..3).
    Their statics records predate the records' study identity, which the report refuses, so they are
    left out: the table's Table B1 rows are then absent, the others of three seeds."""
    base = tmp_path_factory.mktemp("seeds")
    return [_cut_study(os.path.join(DATA, "seeds", "sphere-1000-s%d" % k), str(base / ("s%d" % k)),
                       keep=("metadata.json", "specimen.json")) for k in (1, 2, 3)]


def _section(text, title):
    return text.split(title, 1)[1].split("\n## ", 1)[0]


def _cells(section, label):
    line = next(x for x in section.splitlines() if x.startswith("| %s |" % label))
    return [c.strip() for c in line.strip("|").split("|")]


def test_the_headline_table_is_first_with_mean_and_sd_over_three_seeds(three_seeds, tmp_path):
    path, _ = report.build(three_seeds[0], str(tmp_path / "rep"), log=lambda m: None, seeds=three_seeds[1:])
    text = open(path).read()
    sections = [x for x in text.splitlines() if x.startswith("## ")]
    assert sections[0] == "## Headlines against the paper (spheres)"
    head = _section(text, "## Headlines against the paper (spheres)")
    assert "over 3 seeds of one recipe" in head and "| | ours (1000, seeds 1, 2, 3) | paper |" in head
    # e and Zm of the three specimens as their own summaries record them; sample sd (n - 1).
    summaries = [json.load(open(os.path.join(d, "specimen.json")))["summary"] for d in three_seeds]
    for label, key, fmt, paper in (("e", "void_ratio", "%.4f", "0.5840"), ("Zm", "Zm", "%.3f", "5.94-5.99")):
        v = [s[key] for s in summaries]
        want = "%s +/- %s (3 seeds)" % (fmt % statistics.mean(v), fmt % statistics.stdev(v))
        assert _cells(head, label)[1:] == [want, paper]
    for label in ("zeta fitted (one zeta)", "nu RMSE at the fitted zeta", "E relative RMSE at the fitted zeta",
                  "K at the isotropic state (MPa)", "G at the isotropic state (MPa)"):
        assert " +/- " in _cells(head, label)[1] and _cells(head, label)[1].endswith("(3 seeds)")
    assert _cells(head, "zeta fitted (one zeta)")[2] == "0.552"
    # The figures and the other tables stay the first study's, and say so.
    assert "of 1000 spheres" in text.split("## Probes with rotations free", 1)[1].splitlines()[0]


def test_one_study_has_a_headline_table_of_one_seed(three_seeds, tmp_path):
    text = open(report.build(three_seeds[1], str(tmp_path / "rep"), log=lambda m: None)[0]).read()
    head = _section(text, "## Headlines against the paper (spheres)")
    assert "One seed" in head and _cells(head, "Zm")[1].endswith("(1 seed)") and "+/-" not in _cells(head, "Zm")[1]


@pytest.mark.parametrize("case", ["same seed twice", "other recipe", "other assembly"])
def test_seeds_not_of_one_recipe_are_refused_before_anything_is_written(three_seeds, tmp_path, case):
    other = {"same seed twice": three_seeds[0],
             "other recipe": _cut_study(os.path.join(DATA, "switch-pressure", "spheres-1000-s1-switch5kpa"),
                                        str(tmp_path / "switched")),
             "other assembly": _cut_study(os.path.join(DATA, "clump1-4000-s1"), str(tmp_path / "clump1"),
                                          keep=("metadata.json",))}[case]
    out = tmp_path / "rep"
    with pytest.raises(ResultsError, match="--seeds: .*(counted twice|not one recipe|one assembly)"):
        report.build(three_seeds[0], str(out), log=lambda m: None, seeds=[three_seeds[1], other])
    assert not out.exists()


def _data_points(fig):
    """Every plotted point of the figure's axes, in display coordinates."""
    from matplotlib.collections import PathCollection
    pts = []
    for ax in fig.axes:
        for line in ax.get_lines():
            if line.get_marker() not in (None, "", "None", " ") or line.get_linestyle() not in ("None", ""):
                xy = np.asarray(line.get_xydata(), dtype=float)
                pts.append(line.get_transform().transform(xy[np.all(np.isfinite(xy), axis=1)]))
        for c in ax.collections:
            if isinstance(c, PathCollection) and len(c.get_offsets()):
                pts.append(c.get_offset_transform().transform(np.asarray(c.get_offsets(), dtype=float)))
    return np.concatenate(pts) if pts else np.zeros((0, 2))


def _covered(fig):
    """How many plotted points of the (drawn) figure lie under one of its legends."""
    pts, n = _data_points(fig), 0
    for ax in fig.axes:
        if ax.get_legend():
            box = ax.get_legend().get_window_extent()
            n += int(np.sum((pts[:, 0] > box.x0) & (pts[:, 0] < box.x1) & (pts[:, 1] > box.y0) & (pts[:, 1] < box.y1)))
    return n


def _labelled_ticks(axis):
    lo, hi = sorted(axis.get_view_interval())
    return [t.get_text() for t, loc in zip(axis.get_ticklabels(), axis.get_ticklocs())
            if t.get_text() and lo <= loc <= hi]


def _capture(monkeypatch):
    """The figures the report writes, each with its title, legends' boxes, the points under them and
    its axes' labelled ticks, read where every figure is saved (figures._save)."""
    seen = {}
    save = figures._save

    def kept(fig, path):
        fig.canvas.draw()
        covered = _covered(fig)
        ticks = {(k, name): _labelled_ticks(getattr(ax, name)) for k, ax in enumerate(fig.axes)
                 if ax.get_label() != "<colorbar>" for name in ("xaxis", "yaxis")}
        lines = {ln.get_label(): (ln.get_xdata(), ln.get_ydata()) for ax in fig.axes for ln in ax.get_lines()}
        title = fig._suptitle.get_window_extent() if fig._suptitle else None
        inside = title is not None and title.x0 >= 0 and title.x1 <= fig.bbox.x1 and title.y1 <= fig.bbox.y1
        seen[os.path.basename(path)] = dict(title=fig._suptitle.get_text() if fig._suptitle else "",
                                            inside=inside, covered=covered, ticks=ticks, lines=lines)
        save(fig, path)
    monkeypatch.setattr(figures, "_save", kept)
    return seen


@pytest.fixture(scope="module")
def small_spheres(tmp_path_factory):
    """The committed 4000-sphere study (seed 1) at eight states, with its Table B1 records."""
    return _cut_study(os.path.join(DATA, "spheres-4000-s1"), str(tmp_path_factory.mktemp("sph") / "study"))


def test_every_figure_names_its_study_asks_its_question_and_keeps_its_legend_off_the_data(
        small_spheres, tmp_path, monkeypatch):
    seen = _capture(monkeypatch)
    out = tmp_path / "rep"
    report.build(small_spheres, str(out), log=lambda m: None, fig16=os.path.join(DATA, "fig16-spheres-4000-s1"))
    assert sorted(seen) == sorted(p.name for p in out.glob("*.png")) and len(seen) == 16
    for name, f in seen.items():
        assert "4000 spheres, seed 1" in f["title"], (name, f["title"])
        assert "?" in f["title"].splitlines()[0], (name, f["title"])  # the question, on its first line
        assert f["inside"], "%s: its title runs out of the figure" % name
        assert f["covered"] == 0, "%s: %d points under a legend" % (name, f["covered"])
        for (k, axis), labels in f["ticks"].items():
            assert len(labels) >= 3, (name, k, axis, labels)
    # Fig. 4a: log axes over a ratio of about 0.4-2.5, whose log ticks left one labelled tick.
    assert all(len(v) >= 3 for v in seen["fig4a.png"]["ticks"].values())
    # Fig. 11: the paper's Table 2 quadratics drawn, over the paper's Zm (Fig. 8a).
    for name in ("K", "G"):
        x, y = seen["fig11-K-G-vs-Zm.png"]["lines"]["$%s$, paper's Table 2" % name]
        assert x.min() == pytest.approx(5.94) and x.max() == pytest.approx(5.99)
        assert np.allclose(y, np.polyval(chain.PAPER["spheres"][name], x), rtol=1e-12)
    # Fig. 16: the cross-anisotropic study's own size and seed, and the paper's zeta drawn.
    assert any("0.552" in label for label in seen["fig16.png"]["lines"])


def test_a_clump_report_names_its_clumps_and_draws_the_papers_quadratics(tmp_path, monkeypatch):
    study = _cut_study(os.path.join(DATA, "clump1-4000-s1"), str(tmp_path / "clump1"))
    seen = _capture(monkeypatch)
    report.build(study, str(tmp_path / "rep"), log=lambda m: None)
    assert seen and all("4000 clump1 clumps, seed 1" in f["title"] and f["inside"] for f in seen.values())
    assert all(f["covered"] == 0 for f in seen.values())
    x, y = seen["fig11-K-G-vs-Zm.png"]["lines"]["$K$, paper's Table 2"]
    assert np.allclose(y, np.polyval(chain.PAPER["clump1"]["K"], x), rtol=1e-12)
    assert "extrapolated" in seen["fig11-K-G-vs-Zm.png"]["title"]  # our Zm is past the vertex of its fit


def test_the_quick_figures_of_a_clump_study_name_its_clumps(tmp_path, monkeypatch):
    """run_study.py's figures/ and `python3 -m trueaniso.analysis.figures` title their figures as the
    report does: the assembly, particle count and seed of the study's metadata.json (they said
    "sphere assembly" whatever the study was)."""
    study = _cut_study(os.path.join(DATA, "clump2-4000", "s1"), str(tmp_path / "clump2"))
    seen = _capture(monkeypatch)
    assert figures.main([os.path.join(study, "probes.csv"), "--out", str(tmp_path / "f")]) == 0
    assert sorted(seen) == ["E_vs_sigma.png", "K_G_vs_Zm.png"]
    assert all("4000 clump2 clumps, seed 1" in f["title"] and "sphere" not in f["title"] for f in seen.values())
    seen.clear()
    assert figures.main([os.path.join(study, "probes.csv"), "--out", str(tmp_path / "g"), "--title", "my packing"]) == 0
    assert all(f["title"].endswith("my packing") for f in seen.values())


def test_a_bare_table_says_what_it_does_not_record(small_table, tmp_path, monkeypatch):
    seen = _capture(monkeypatch)
    text = open(report.build(small_table, str(tmp_path / "rep"), log=lambda m: None)[0]).read()
    assert "Not for a bare probe table" in _section(text, "## Headlines against the paper (spheres)")
    assert all("spheres (particle count not recorded), seed not recorded" in f["title"] for f in seen.values())
    with pytest.raises(ResultsError, match="--seeds needs"):
        report.build(small_table, str(tmp_path / "rep2"), log=lambda m: None, seeds=[small_table])


def test_table_b1_says_which_contact_density_its_prediction_uses(small_spheres, tmp_path):
    text = open(report.build(small_spheres, str(tmp_path / "rep"), log=lambda m: None)[0]).read()
    b1 = _section(text, "## Table B1")
    assert report.B1_DENSITY in b1 and "counted N_c/V" in report.B1_DENSITY
    assert "Eq. (36)" in report.B1_DENSITY  # and which it is not


def test_fig4_ticks_are_plain_on_a_narrow_log_axis(tmp_path):
    """The check above can fail: a log axis over 0.5-2 left to its own ticks labels one tick."""
    plt = figures._plt()
    fig, ax = plt.subplots()
    ax.loglog([0.5, 2.0], [0.7, 1.4])
    fig.canvas.draw()
    assert len(_labelled_ticks(ax.yaxis)) < 3
    figures.plain_ticks(ax.yaxis)
    fig.canvas.draw()
    assert len(_labelled_ticks(ax.yaxis)) >= 3
    plt.close(fig)


def test_the_legend_check_sees_points_under_a_legend():
    """The check above can fail: a legend in the middle of a diagonal of points covers some."""
    plt = figures._plt()
    fig, ax = plt.subplots()
    x = np.linspace(0.0, 1.0, 200)
    ax.scatter(x, x, label="a")
    ax.plot(x, 1.0 - x, "o", label="b")
    ax.legend(loc="center")
    fig.canvas.draw()
    assert _covered(fig) > 0
    figures.legend_outside(ax)
    fig.canvas.draw()
    assert _covered(fig) == 0
    plt.close(fig)


def test_a_study_without_its_specimen_summary_says_so_and_refuses_seeds(small_table, three_seeds, tmp_path):
    """A study whose metadata.json records no specimen (written by hand, or saved without its
    summary) still gets its report, whose headline section says why it has none; asked for the
    table over seeds, it is refused before anything is written."""
    study = tmp_path / "study"
    study.mkdir()
    shutil.copy(small_table, study / "probes.csv")
    with open(small_table) as f:
        defined = {r["state"]: dict(b=float(r["b"]), sigma_z=float(r["sigma_z_goal"])) for r in csv.DictReader(f)}
    (study / "metadata.json").write_text(json.dumps(dict(states=defined)))
    text = open(report.build(str(study), str(tmp_path / "rep"), log=lambda m: None)[0]).read()
    assert "Not computed for this study: %s: its metadata.json records no specimen n, void_ratio, Zm, material" \
        % study in _section(text, "## Headlines against the paper (spheres)")
    with pytest.raises(ResultsError, match="records no specimen"):
        report.build(str(study), str(tmp_path / "rep2"), log=lambda m: None, seeds=three_seeds[1:])
    assert not (tmp_path / "rep2").exists()
