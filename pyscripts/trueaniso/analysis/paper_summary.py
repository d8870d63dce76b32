r"""The paper-size summary: each assembly's largest study against the paper, judged by the scatter
between seeds, and the departures that remain.

    /usr/bin/python3 -m trueaniso.analysis.paper_summary \
        --study docs/data/spheres-53004-s1 --seeds docs/data/spheres-4000/s1 docs/data/spheres-4000/s2 ... \
        --study docs/data/clump1-16000/s1 --seeds ... [--doc docs/report-paper-size/summary.md --block summary]

Each --study is one study directory (trueaniso.analysis.seeds reads its headlines), the --seeds after it
the same recipe's studies of other seeds, at any size. For each study a table puts its headline
numbers beside the seeds' mean +/- sample sd and the paper's value, and says how far the study is
from the paper in units of that sd (the scatter between packings of one recipe, which a single seed
cannot tell from a departure) made a difference's, below. Size is not in that sd: the size series
(docs/studies/paper-size.md) is what says whether size moves a number.

The judgement (``against_paper``): our study is one packing and the paper's number is one too, so
their difference scatters by the square root of 2 times the seeds' sd; a difference more than LIMIT
times that departs. From few seeds the sd is itself uncertain: at 95 % confidence the true sd is at most
``sd_bound`` times the sample's (the chi-square bound: 4.4 for three seeds), so a difference beyond
LIMIT times that bound departs whatever the true scatter is ("established"); one between the two is a
departure not established, of which about one in twenty numbers judged shows by chance. A paper's
range ("5.94-5.99") or bound ("<= 0.05") is judged from its nearest edge. The spheres' K and G are
shown beside the paper's Table 2 quadratics but not judged: our Zm lies below the quadratics' minima
(Zm 5.94), outside the paper's data, where the fits rise as Zm falls.
"""
import math
import re
import sys

import numpy as np

from . import seeds
from .results import ResultsError

LIMIT = 2.0  # sd of a difference of two packings: outside it, about 5 % would fall were the scatter normal
PAIR = math.sqrt(2.0)  # the sd of a difference of two packings, in the seeds' sd
CONFIDENCE = 0.95
# The paper's specimens (section 2.1). Our clump2 is four copies of one layer, so 69,532 (a multiple of 4)
# stands for its 69,531 (docs/studies/paper-size.md).
PAPER_SIZE = dict(spheres=53004, clump1=53004, clump2=69532)
_RANGE = re.compile(r"^\s*([-+0-9.eE]+)\s*-\s*([-+0-9.eE]+)")
_BOUND = re.compile(r"^\s*<=\s*([-+0-9.eE]+)")


def sd_bound(count, confidence=CONFIDENCE):
    """How many times the sample sd of `count` values the true sd may be, at `confidence`: the one-sided
    chi-square bound of a normal sample's variance, its square root. None below two values."""
    if count < 2:
        return None
    from scipy.stats import chi2
    return math.sqrt((count - 1) / chi2.ppf(1.0 - confidence, count - 1))


def _paper_interval(paper):
    """The paper's value as (low, high): a number, a range "a-b" or a bound "<= b"; None when it states none."""
    if paper is None:
        return None
    if isinstance(paper, (int, float)):
        return float(paper), float(paper)
    m = _RANGE.match(paper)
    if m:
        return float(m.group(1)), float(m.group(2))
    m = _BOUND.match(paper)
    if m:
        return -math.inf, float(m.group(1))
    return None  # words ("approximately constant"): nothing to measure against


def against_paper(ours, paper, sd=None, count=0):
    """(words, verdict) for our value against the paper's (a number, a range or a bound, module doc),
    with the seeds' sample sd over `count` seeds. verdict: None (not judged: no paper number or no sd),
    "agrees", "departs" (beyond LIMIT sd, not beyond LIMIT times sd_bound) or "departs, established"."""
    interval = _paper_interval(paper)
    if ours is None or interval is None:
        return "", None
    low, high = interval
    gap = ours - high if ours > high else (ours - low if ours < low else 0.0)
    if not (sd and sd > 0 and count >= 2):
        if gap == 0.0:
            return "inside", None
        ref = high if ours > high else low
        return ("%s %%" % _signed(100.0 * gap / abs(ref)) if ref else "%+.3g" % gap), None
    z = gap / (PAIR * sd)
    if abs(z) <= LIMIT:
        return ("inside" if gap == 0.0 and low < high else "%s sd" % _signed(z)), "agrees"
    verdict = "departs, established" if abs(z) > LIMIT * sd_bound(count) else "departs"
    return "%s sd" % _signed(z), verdict


def _signed(x):
    """+1.3, -0.4, 0.0 (no "-0.0")."""
    return "0.0" if abs(x) < 0.05 else "%+.1f" % x


def _count(n):
    """4000, 16,000: the manual's way (a comma from five digits)."""
    return "?" if not n else ("{:,}".format(n) if n >= 10000 else str(n))


def _size_said(h, assembly):
    n, paper_n = h["n"], PAPER_SIZE[assembly]
    said = "%s, seed %s" % (_count(n), h["seed"])
    return said if n == paper_n else said + "; the paper's is %s" % _count(paper_n)


def assembly_table(study, seed_heads, assembly):
    """Markdown table of one study's headlines (seeds.headlines) beside its seeds' and the paper's, and
    the list of (row label, our value, paper cell, words with the verdict) of the rows judged to depart."""
    paper = seeds.paper_values(assembly)
    sizes = sorted({h["n"] for h in seed_heads if h["n"]})
    seeds_said = ("%s, %d seed%s" % ("/".join(_count(n) for n in sizes), len(seed_heads), "s" * (len(seed_heads) > 1))
                  if seed_heads else "none given")
    out = ["| | ours (%s) | seeds (%s) | paper | ours - paper |" % (_size_said(study, assembly), seeds_said),
           "|---|---|---|---|---|"]
    departures = []
    bound = sd_bound(len(seed_heads))
    for label, key, fmt in seeds.HEADLINE_ROWS:
        ours = seeds._value(study, key)
        values = [v for v in (seeds._value(h, key) for h in seed_heads) if v is not None]
        if ours is None and not values:
            continue
        sd = float(np.std(values, ddof=1)) if len(values) >= 2 else None
        p = seeds._value(paper, key)
        paper_cell = seeds._paper_cell(paper, key, fmt)
        if key in ("K_iso", "G_iso") and ours is not None:  # Table 2's quadratics at our Zm: shown, not judged
            kg = seeds.paper_K_G(assembly, study["Zm_iso"])
            if kg:
                paper_cell = "%.1f (Table 2 at Zm %.3f, below its data)" % (kg[0 if key == "K_iso" else 1],
                                                                        study["Zm_iso"])
        words, verdict = against_paper(ours, p, sd, len(values))
        if verdict is not None:
            words = "%s: %s" % (words, verdict)
        out.append("| %s | %s | %s | %s | %s |" % (label, "-" if ours is None else fmt % ours,
                                                   seeds.mean_sd(values, fmt, count=0 < len(values) < len(seed_heads)),
                                                   paper_cell, words))
        if verdict and verdict.startswith("departs"):
            departures.append((label, fmt % ours, paper_cell, words))
    if bound:
        out.append("")
        out.append("sd: of the difference of two packings, sqrt(2) times the seeds'. %d seeds: the true sd may be up "
                   "to %.1f times theirs (%d %%), so a departure is established beyond %.1f sd."
                   % (len(seed_heads), bound, round(100 * CONFIDENCE), LIMIT * bound))
    return "\n".join(out), departures


def _paper_name(h):
    """The paper's name of a study's assembly (the scripts say "sphere", the paper "spheres")."""
    return {"sphere": "spheres"}.get(h["assembly"], h["assembly"])


def summary(groups):
    """Markdown for [(study headlines, [seed headlines])]: a section per assembly, then the departures."""
    parts, remain, unjudged, seen = [], [], [], {}
    for study, seed_heads in groups:
        assembly = _paper_name(study)
        if assembly not in PAPER_SIZE:
            raise ResultsError("%s: assembly %r has no paper values" % (study["study"], assembly))
        if assembly in seen:
            raise ResultsError("%s and %s are both of %s: one --study an assembly" % (seen[assembly], study["study"],
                                                                                    assembly))
        seen[assembly] = study["study"]
        if any(_paper_name(h) != assembly for h in seed_heads):
            raise ResultsError("%s: its --seeds are of another assembly" % study["study"])
        # The seeds' sd stands for the study's scatter only if they are packings of its recipe, each once:
        # so each must record its recipe (specimen.json), which recipe_problem compares.
        unknown = [h["study"] for h in [study] + seed_heads if not h["recipe_settings"]]
        if unknown:
            raise ResultsError("%s records no recipe (no specimen.json with its preparation's settings): its seeds "
                               "cannot be shown to be packings of one recipe" % unknown[0])
        problem = seeds.recipe_problem([study] + seed_heads)
        if problem:
            raise ResultsError("--study %s and its --seeds: %s" % (study["study"], problem))
        text, departures = assembly_table(study, seed_heads, assembly)
        parts.append("## %s\n\n%s" % (assembly, text))
        remain += [(assembly,) + d for d in departures]
        if len(seed_heads) < 2:
            unjudged.append(assembly)
    lines = ["## The departures that remain", ""]
    if unjudged:  # no sd to judge by: the table says the differences only
        lines += ["Not judged, for want of two seeds or more: %s." % ", ".join(unjudged), ""]
    if not remain and len(unjudged) < len(groups):
        lines.append("None beyond %.0f sd of the seeds%s." % (LIMIT, " among the others" if unjudged else ""))
    for assembly, label, ours, paper, words in remain:
        lines.append("- %s, %s: %s against the paper's %s (%s)" % (assembly, label.replace("\\|", "|"), ours, paper,
                                                                  words))
    return "\n\n".join(parts) + "\n\n" + "\n".join(lines)


def parse(argv):
    """([(study directory, [seed directories])], doc, block) from the command line (module doc)."""
    groups, doc, block = [], None, None
    target = None  # the list a bare directory goes to: the last --seeds', until another option
    it = iter(argv)
    for a in it:
        if a == "--seeds":
            if not groups:
                raise ResultsError("--seeds comes after the --study they belong to")
            if groups[-1][2]:
                raise ResultsError("--seeds given twice for %s" % groups[-1][0])
            groups[-1][2] = True
            target = groups[-1][1]
            continue
        if a in ("--study", "--doc", "--block"):
            value = next(it, None)
            if value is None or value.startswith("--"):
                raise ResultsError("%s needs a value" % a)
            if a == "--study":
                groups.append([value, [], False])
            elif a == "--doc":
                doc = value
            else:
                block = value
            target = None
            continue
        if a.startswith("--"):
            raise ResultsError("%s: no such option (--study, --seeds, --doc, --block)" % a)
        if target is None:
            raise ResultsError("%s: a study directory goes after --study, a seed's after --seeds (and before --doc, "
                               "--block)" % a)
        target.append(a)
    if not groups:
        raise ResultsError("no --study given")
    empty = [g[0] for g in groups if g[2] and not g[1]]
    if empty:
        raise ResultsError("--seeds names no study directory (after --study %s)" % empty[0])
    if bool(doc) != bool(block):
        raise ResultsError("--doc and --block go together")
    return [(g[0], g[1]) for g in groups], doc, block


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or any(a in ("-h", "--help") for a in argv):
        print(__doc__.strip())
        print("\nOptions: --study DIR (one an assembly) [--seeds DIR ...] ...; --doc FILE --block NAME: the text written "
              "between that block's markers in FILE instead of printed.")
        return 0 if argv else 2
    try:
        groups, doc, block = parse(argv)
        seeds.publish(summary([(seeds.headlines(study), [seeds.headlines(d) for d in dirs]) for study, dirs in groups]),
                      doc, block)
    except ResultsError as exc:
        sys.stderr.write("error: %s\n" % exc)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
