"""The manual (docs/, Sphinx with myst-parser): it builds with no warning, its reference covers every
script, module and input schema, the benchmark tables are where the scripts write them, no table
is clipped in a browser, and the tutorial's commands, run as written, give what the tutorial says."""
import glob
import html as html_text
import json
import os
import re
import shlex
import subprocess

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
DOCS = os.path.join(REPO, "docs")
PYTHON = "/usr/bin/python3"


@pytest.fixture(scope="module")
def manual(tmp_path_factory):
    """The manual built as docs/build.sh builds it (warnings as errors), into a temporary directory."""
    out = tmp_path_factory.mktemp("manual")
    proc = subprocess.run([PYTHON, "-m", "sphinx", "-E", "-W", "--keep-going", "-q", "-b", "html", DOCS, str(out)],
                          cwd=REPO, capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    return proc, out


def test_the_manual_builds_with_no_warning(manual):
    proc, out = manual
    assert proc.returncode == 0, "sphinx -W failed:\n%s\n%s" % (proc.stdout[-3000:], proc.stderr[-5000:])
    assert proc.stderr.strip() == "", proc.stderr
    assert os.path.exists(os.path.join(out, "index.html"))


def _html(out, page):
    with open(os.path.join(out, page)) as f:
        return f.read()


def _text(out, page):
    """A built page's text, tags left out."""
    return re.sub(r"<[^>]+>", "", _html(out, page))


def test_the_script_reference_holds_every_script_s_help(manual):
    """Every user script (pyscripts/*.py) and analysis tool (python3 -m trueaniso.analysis.X) has
    its --help in the scripts reference, as the script prints it, and no benchmark script does: the
    product's entry points only. Every benchmark script (bench/*.py) has its --help on the studies'
    page of them. A new script is picked up without an edit of either page."""
    proc, out = manual
    assert proc.returncode == 0
    html = _text(out, os.path.join("reference", "scripts.html"))
    bench_html = _text(out, os.path.join("studies", "bench-scripts.html"))
    scripts = sorted(glob.glob(os.path.join(REPO, "pyscripts", "*.py")))
    bench = sorted(p for p in glob.glob(os.path.join(REPO, "bench", "*.py"))
                   if not os.path.basename(p).startswith("_"))
    assert len(scripts) >= 3 and len(bench) >= 10
    for path in scripts:
        rel = os.path.relpath(path, REPO)
        assert rel in html, "%s has no section in reference/scripts" % rel
    tools = ("report", "figures", "zeta_contrast", "cross_anisotropy", "path_fidelity", "seeds")
    for tool in tools:
        assert "python3 -m trueaniso.analysis.%s" % tool in html
    assert html.count("usage:") >= len(scripts), "a section without the script's usage"  # the tools' may be prose
    for path in bench:
        rel = os.path.relpath(path, REPO)
        assert "usage: %s" % os.path.basename(path) not in html, "%s in the user's reference" % rel
        assert rel in bench_html, "%s has no section in studies/bench-scripts" % rel
    assert bench_html.count("usage:") >= len(bench), "a benchmark section without the script's usage"
    cores = os.cpu_count() or 1
    for page in (html, bench_html):
        for said in (r"all\s+%d\s+cores" % cores, r"at most\s+%d\s+\(" % (4 * cores)):
            assert not re.search(said, page), "the help names this machine's core count: %s" % said
        assert REPO not in page, "the help names this checkout's path"


def test_the_api_reference_documents_every_module(manual):
    """Every module of the trueaniso package and its trueaniso.analysis is documented by autodoc (its
    docstring imported, not only named): the page lists them from the folders, so a new module needs
    no edit."""
    proc, out = manual
    assert proc.returncode == 0
    html = _html(out, os.path.join("reference", "python-api.html"))
    for package, folder in (("trueaniso", os.path.join("pyscripts", "trueaniso")),
                            ("trueaniso.analysis", os.path.join("pyscripts", "trueaniso", "analysis"))):
        names = [package] + ["%s.%s" % (package, os.path.splitext(os.path.basename(p))[0])
                             for p in glob.glob(os.path.join(REPO, folder, "*.py"))
                             if not p.endswith("__init__.py")]
        assert len(names) > 3
        for name in names:
            assert 'id="module-%s"' % name in html, "%s is not documented" % name
    # autodoc imported them: a documented function carries its signature
    assert 'id="trueaniso.triaxial.reach_state"' in html
    assert REPO not in html, "a default value shows this checkout's path"


SCHEMAS = os.path.join(REPO, "pyscripts", "trueaniso", "schemas")


def _schema_name(path):
    name = os.path.basename(path)
    return name[:-len(".schema.json")] if name.endswith(".schema.json") else os.path.splitext(name)[0]


def _schema_pages():
    """{schema name: pages (built .html paths) whose source shows it with ```{schema-table} NAME```}."""
    pages = {}
    for source in glob.glob(os.path.join(DOCS, "**", "*.md"), recursive=True):
        with open(source) as f:
            for name in re.findall(r"^```\{schema-table\}\s+(\S+)", f.read(), flags=re.M):
                pages.setdefault(name, []).append(os.path.splitext(os.path.relpath(source, DOCS))[0] + ".html")
    return pages


def _descriptions(node, inside_definitions=False):
    """Every "description" of a schema file, those of its shared definitions left out (a definition
    is shown through the properties that use it)."""
    found = []
    if isinstance(node, dict):
        for key, value in node.items():
            if key == "description" and isinstance(value, str) and not inside_definitions:
                found.append(value)
            else:
                found += _descriptions(value, inside_definitions or key == "definitions")
    elif isinstance(node, list):
        for value in node:
            found += _descriptions(value, inside_definitions)
    return found


def _words(text):
    return " ".join(html_text.unescape(text).split())


def test_every_schema_is_shown_in_the_manual_with_its_descriptions(manual):
    """Every schema of pyscripts/trueaniso/schemas/ is rendered by a ```{schema-table}``` on some
    page, and every description it holds (each field's, the file's) is in that built page: a new
    schema, or a field, that the reference does not show fails here."""
    proc, out = manual
    assert proc.returncode == 0
    files = sorted(glob.glob(os.path.join(SCHEMAS, "*.json")))
    assert len(files) >= 9
    pages = _schema_pages()
    missing = [os.path.basename(p) for p in files if _schema_name(p) not in pages]
    assert not missing, "schemas no page of docs/ shows with a schema-table: %s" % ", ".join(missing)
    checked = 0
    for path in files:
        with open(path) as f:
            descriptions = _descriptions(json.load(f))
        assert len(descriptions) >= 3, path
        for page in pages[_schema_name(path)]:
            text = _words(_text(out, page))
            assert os.path.basename(path) in text, "%s does not name %s" % (page, path)
            for description in descriptions:
                # a formula, $x$ in the schema, is MathJax's \(x\) in the page
                description = re.sub(r"(?<!\\)\$([^$`]+)\$", r"\\(\1\\)", description)
                assert _words(description) in text, "%s: %r is not on %s" % (os.path.basename(path), description,
                                                                            page)
                checked += 1
    assert checked >= 150


def test_a_schema_table_gives_each_field_s_type_constraints_and_whether_it_is_required(manual):
    """The rows of the specimen's metadata, read from the built table: nested fields by their dotted
    path, bounds and enums as the schema states them, required or not as its lists say."""
    proc, out = manual
    assert proc.returncode == 0
    page = _html(out, os.path.join("reference", "formats", "specimen.html"))
    rows = {}
    for row in re.findall(r"<tr[^>]*>(.*?)</tr>", page, flags=re.S):
        cells = [_words(re.sub(r"<[^>]+>", "", c)) for c in re.findall(r"<td[^>]*>(.*?)</td>", row, flags=re.S)]
        if len(cells) == 5:
            rows[cells[0]] = cells[1:]
    assert rows["material.poisson"][:3] == ["number", "finite; > -1; < 0.5", "required"]
    assert rows["material.rolling_friction"][:3] == ["number", "finite; >= 0", "optional"]
    assert rows["format_version"][:3] == ["integer", "one of 2, 3, 4", "required"]
    assert rows["seed"][:3] == ["integer or null", ">= 0", "required"]
    assert rows["parameters.assembly"][2] == "optional"


def _bench_names(path):
    """The marker names a bench script writes (its literal names and the default of --block) and
    the headings it writes under."""
    with open(path) as f:
        text = f.read()
    names = set(re.findall(r'(?:replace_block|publish)\([^,]+,\s*"([\w-]+)"', text))
    names |= set(re.findall(r'"--block",\s*default="([\w-]+)"', text))
    headings = set(re.findall(r'heading="(#+ [^"]+)"', text))
    return names, headings


def test_the_benchmark_tables_are_where_the_scripts_write_them():
    """Every heading a bench script writes under is a line of a benchmarks page (docs/benchmarks.md
    or docs/studies/benchmarks.md), and every "Reproduce:" line or command under a table of the
    docs that runs a bench script with --doc names a block that page holds between markers
    (renaming a heading or a marker without the script, or the reverse, fails here)."""
    lines = []
    for page in (os.path.join(DOCS, "benchmarks.md"), os.path.join(DOCS, "studies", "benchmarks.md")):
        with open(page) as f:
            lines += f.read().split("\n")
    checked = 0
    for path in glob.glob(os.path.join(REPO, "bench", "*.py")):
        for heading in _bench_names(path)[1]:
            assert heading in lines, "%s writes under %r, which neither benchmarks page has" % (path, heading)
            checked += 1
    assert checked >= 3
    reproduced = 0
    for page in glob.glob(os.path.join(DOCS, "*.md")) + glob.glob(os.path.join(DOCS, "studies", "*.md")):
        with open(page) as f:
            text = f.read()
        commands = re.findall(r"Reproduce: `([^`]*bench/[^`]*--doc [^`]*)`", text)
        commands += re.findall(r"^ {4}(/usr/bin/python3 bench/.*--doc .*)$", re.sub(r"\\\n\s*", " ", text),
                               flags=re.M)  # a command block (under a table, or a continued line joined)
        for command in commands:
            words = shlex.split(command, comments=True)
            script = next(w for w in words if w.startswith("bench/"))
            doc = words[words.index("--doc") + 1]
            names = [words[words.index("--block") + 1]] if "--block" in words else \
                sorted(_bench_names(os.path.join(REPO, script))[0])
            with open(os.path.join(REPO, doc)) as f:
                target = f.read()
            for name in names:
                assert "<!-- %s:begin -->" % name in target and "<!-- %s:end -->" % name in target, \
                    "%s: %s writes block %r into %s, which has no such markers" % (page, script, name, doc)
                reproduced += 1
    assert reproduced >= 10


TUTORIAL = os.path.join(DOCS, "tutorial.md")


def _tutorial_commands():
    """The commands of the tutorial's ```sh blocks, in order (comments and blank lines left out)."""
    with open(TUTORIAL) as f:
        text = f.read()
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for line in block.split("\n"):
            line = line.split("  #")[0].strip()
            if line and not line.startswith("#"):
                commands.append(line)
    return text, commands


@pytest.mark.long
def test_the_tutorial_s_commands_give_what_it_says(tmp_path):
    """The tutorial's commands, run as written from the repository's root (its results directory,
    results/tutorial, moved to a temporary one), write every file the tutorial names and say that
    the study is done. Long: as written, they prepare and study 300 spheres (half a minute of a
    core); test_main_job runs the same ./main.sh on 100."""
    text, commands = _tutorial_commands()
    assert any(c.startswith("./main.sh") for c in commands), commands
    out = str(tmp_path / "tutorial")
    env = dict(os.environ, OMP_NUM_THREADS="1")
    said = ""
    for command in commands:
        proc = subprocess.run(command.replace("results/tutorial", out), shell=True, cwd=REPO, env=env,
                              capture_output=True, text=True, timeout=1200)
        assert proc.returncode == 0, "%s\n%s\n%s" % (command, proc.stdout[-3000:], proc.stderr[-3000:])
        said += proc.stdout
    named = sorted(set(re.findall(r"results/tutorial/([\w./-]+\w)", text)))
    assert "report/report.md" in named and "probes.csv" in named
    for name in named:
        assert os.path.exists(os.path.join(out, name)), "the tutorial names results/tutorial/%s" % name
    with open(os.path.join(out, "report", "report.md")) as f:
        assert f.read().startswith("# Report")
    with open(os.path.join(out, "probes.csv")) as f:
        rows = f.read().strip().split("\n")[1:]
    assert len(rows) == 12  # four states, three probes each, as the tutorial says
    assert "no state to run" in said  # its rerun, as the tutorial says


# --- the built manual in a browser: no table is clipped ------------------------------------------

CHROMIUM = ("chromium", "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            "--allow-file-access-from-files", "--window-size=1400,1000")

# A formula written as ASCII: an exponent (^(1/3), ^2), sqrt(, a Greek letter or a symbol with a
# subscript (sigma_z, nu_ij, k_n, E_i), rbar; or one that was meant to be typeset and was not (a
# role or a TeX command left in the text). The same pattern in Python and in the browser's JavaScript.
UNRENDERED = r":math:`|\{math\}`|\$\\[a-z]"
RAW_FORMULA = (r"\^\(|\^-?[0-9]|\bsqrt\(|\b(?:sigma|nu|zeta|gamma|eps|rho|eta|beta|delta|omega|theta|mu)_[A-Za-z0-9]+"
               r"|\b[A-Za-z]_(?:[a-z]{1,2}|[0-9])\b|\brbar\b|" + UNRENDERED)

# The parts of RAW_FORMULA that no identifier has: on the pages generated from the Python API's
# docstrings and the file formats' schemas, sigma_z, mu_prep or nu_ij name a parameter or a
# column, and only these count there.
RAW_FORMULA_STRUCTURE = r"\^\(|\^-?[0-9]|\bsqrt\(|\brbar\b|" + UNRENDERED


def _named_by_identifiers(page):
    return page == os.path.join("reference", "python-api.html") or \
        page.startswith(os.path.join("reference", "formats") + os.sep)


# Loads each page in turn in an iframe of the width of a laptop's browser (1280 px), waits for the
# theme's script (it wraps every table in its scrolling box) and MathJax (a formula widens its
# cell), and writes what it measures into the page, which chromium --dump-dom prints: a table
# wider than its box (the theme lets it scroll, which hides the right-hand columns), a cell
# whose content overflows it, an entry of the side menu cut off at its edge, or a formula left as
# ASCII in the text.
MEASURE = r"""<!DOCTYPE html><html><body><pre id="result">running</pre>
<iframe id="f" style="width:1280px;height:900px;border:0"></iframe>
<script>
const pages = %s, out = [], f = document.getElementById("f");
function measure(doc, page) {
  const found = [];
  doc.querySelectorAll("table").forEach((t, k) => {
    const box = t.closest(".wy-table-responsive") || t.parentElement;
    if (box.scrollWidth > box.clientWidth + 1)
      found.push("table " + k + " is " + box.scrollWidth + " px wide in a box of " + box.clientWidth);
    t.querySelectorAll("td, th").forEach(c => {
      if (c.scrollWidth > c.clientWidth + 1)
        found.push("table " + k + ": a cell overflows (" + c.scrollWidth + " px in " + c.clientWidth + "): "
                   + c.textContent.trim().slice(0, 60));
    });
  });
  // the side menu's entries wrap too (a YADE class's long name in code ran under the page)
  doc.querySelectorAll(".wy-menu-vertical a").forEach(a => {
    if (a.scrollWidth > a.clientWidth + 1)
      found.push("menu entry overflows (" + a.scrollWidth + " px in " + a.clientWidth + "): " + a.textContent.trim().slice(0, 60));
  });
  const wrapped = doc.querySelectorAll(".wy-table-responsive table").length;
  return {page: page, tables: doc.querySelectorAll("table").length, wrapped: wrapped, found: found,
          formulas: doc.querySelectorAll(".math").length, typeset: doc.querySelectorAll(".MathJax_CHTML").length,
          raw: raw_formulas(doc)};
}
// A formula left as ASCII in the text a reader sees (code, literal blocks and typeset math left
// out): RAW_FORMULA.
const RAW = new RegExp(%s, "g");
function raw_formulas(doc) {
  const main = (doc.querySelector('[role="main"]') || doc.body).cloneNode(true);
  main.querySelectorAll("code, pre, .math, .MathJax_Preview, .MathJax_CHTML, .MJX_Assistive_MathML, script, "
                        + ".highlight, .headerlink").forEach(e => e.remove());
  const text = main.textContent.replace(/\s+/g, " "), out = [];
  let m;
  while ((m = RAW.exec(text)) !== null && out.length < 5000)
    out.push([m[0], text.slice(Math.max(0, m.index - 30), m.index + m[0].length + 20)]);
  return out;
}
function when_ready(win, then, waited) {
  const doc = win.document, tables = doc.querySelectorAll("table.docutils").length;
  if (tables && !doc.querySelector(".wy-table-responsive") && waited < 3000)
    return setTimeout(() => when_ready(win, then, waited + 50), 50);
  if (win.MathJax && win.MathJax.Hub) return win.MathJax.Hub.Queue(then);
  then();
}
let i = 0;
function next() {
  if (i >= pages.length) { document.getElementById("result").textContent = JSON.stringify(out); return; }
  const page = pages[i++];
  f.onload = () => when_ready(f.contentWindow, () => {
    try { out.push(measure(f.contentDocument, page)); } catch (e) { out.push({page: page, error: String(e)}); }
    next();
  }, 0);
  f.src = page;
}
next();
</script></body></html>
"""


def _pages_with_tables(out):
    pages = []
    for path in sorted(glob.glob(os.path.join(str(out), "**", "*.html"), recursive=True)):
        rel = os.path.relpath(path, str(out))
        if rel.startswith("_") or rel in ("genindex.html", "search.html", "py-modindex.html"):
            continue
        with open(path) as f:
            if "<table" in f.read():
                pages.append(rel)
    return pages


def _user_page(rel):
    """A built page of the user manual (tutorial, how-tos, reference, explanation): not a study
    report (studies/, report-*/), which keeps its investigation's notation."""
    return not rel.startswith(("studies" + os.sep, "report-"))


def _user_pages(out):
    pages = []
    for path in sorted(glob.glob(os.path.join(str(out), "**", "*.html"), recursive=True)):
        rel = os.path.relpath(path, str(out))
        if not rel.startswith("_") and rel not in ("genindex.html", "search.html", "py-modindex.html") \
                and _user_page(rel):
            pages.append(rel)
    return pages


def test_no_table_of_the_manual_is_clipped_in_a_browser(manual, tmp_path):
    """Every table of every built page fits its column at a laptop's width (1280 px) in chromium:
    the theme keeps each cell on one line and lets a wide table scroll in its box, which hid the
    equation map's code and tests and the schemas' descriptions; docs/_static/trueaniso.css makes
    cells wrap. A table wider than its box, a cell whose content overflows, or a side-menu entry cut
    off (a long class name in code) fails here; so does a formula of these pages that MathJax
    (Debian's, copied into the manual) did not typeset, or one that a user page (the YADE classes'
    and the Python API's generated from the docstrings among them) shows as ASCII, ^(1/3) or
    sigma_z, where it should be typeset."""
    proc, out = manual
    assert proc.returncode == 0
    tables = _pages_with_tables(out)
    assert len(tables) >= 20 and "equations.html" in tables
    pages = tables + [p for p in _user_pages(out) if p not in tables]
    harness = os.path.join(str(out), "_measure_tables.html")
    with open(harness, "w") as f:
        f.write(MEASURE % (json.dumps(pages), json.dumps(RAW_FORMULA)))
    done = subprocess.run(list(CHROMIUM) + ["--user-data-dir=%s" % (tmp_path / "profile"),
                                            "--virtual-time-budget=120000", "--dump-dom", "file://" + harness],
                          capture_output=True, text=True, timeout=300)
    found = re.search(r'<pre id="result">(.*?)</pre>', done.stdout, flags=re.S)
    assert found and found.group(1) != "running", "chromium measured nothing:\n%s\n%s" % (
        done.stdout[-2000:], done.stderr[-2000:])
    results = json.loads(html_text.unescape(found.group(1)))
    assert [r["page"] for r in results] == pages
    errors = [r for r in results if "error" in r]
    assert not errors, errors
    # the theme's script ran (it wraps the tables whose overflow it would hide), so what was
    # measured is what a reader sees
    assert all(r["wrapped"] == r["tables"] or r["wrapped"] > 0 for r in results), results
    clipped = ["%s: %s" % (r["page"], line) for r in results for line in r["found"]]
    assert not clipped, "clipped at 1280 px:\n" + "\n".join(clipped)
    # the formulas are typeset by the MathJax copied into the manual (no network here)
    equations = results[pages.index("equations.html")]
    assert equations["formulas"] >= 30, equations
    assert [r["page"] for r in results if r["typeset"] < r["formulas"]] == [], \
        [(r["page"], r["formulas"], r["typeset"]) for r in results if r["typeset"] < r["formulas"]]
    # and no user page, the YADE classes' and the Python API's among them, shows one as ASCII
    raw = ["%s: ...%s..." % (r["page"], around) for r in results if _user_page(r["page"]) for hit, around in r["raw"]
           if not _named_by_identifiers(r["page"]) or re.fullmatch(RAW_FORMULA_STRUCTURE, hit)]
    assert not raw, "formulas left as ASCII (write them between $...$):\n" + "\n".join(raw)
    api = results[pages.index(os.path.join("reference", "python-api.html"))]
    assert api["formulas"] >= 40, api
    yade = results[pages.index(os.path.join("reference", "yade-classes.html"))]
    if _yade_classes().plugin_state(REPO)[0]:
        assert yade["formulas"] >= 40, yade  # the plugin's docstrings' formulas, typeset (above)


# --- the YADE classes' reference, generated from the plugin --------------------------------------

def _yade_classes():
    import sys
    sys.path.insert(0, os.path.join(DOCS, "_ext"))
    import yade_classes
    return yade_classes


def _source_docs():
    """{class: its docstring's first 60 characters} read from the plugin's YADE_CLASS_BASE_DOC*
    macros in engines/yade/*.cpp and *.hpp (the string literals after the class and base names,
    joined): the page, made from the loaded classes, must say what the source says."""
    docs = {}
    for path in glob.glob(os.path.join(REPO, "engines", "yade", "*.[ch]pp")):
        with open(path) as f:
            text = f.read()
        for name, literals in re.findall(r'YADE_CLASS_BASE_DOC\w*\(\s*(\w+)\s*,\s*\w+\s*,\s*((?:"(?:[^"\\]|\\.)*"\s*)+)',
                                         text):
            docs[name] = "".join(re.findall(r'"((?:[^"\\]|\\.)*)"', literals))[:60]
    return docs


def test_the_yade_class_reference_is_the_plugin_s_own_documentation(manual):
    """reference/yade-classes lists every class of the plugin's YADE_PLUGIN macro; where the plugin
    is built (build/yade-plugin.status: installed), each with the docstring its source gives it and
    a table of its attributes, read from yade-double when the manual is built; elsewhere the page
    says why they are not there."""
    proc, out = manual
    assert proc.returncode == 0
    yc = _yade_classes()
    names = yc.plugin_classes(REPO)
    assert {"TrueTriaxialServo", "StressProbe", "FabricRecorder", "Law2_ScGeom_SimplifiedMindlinPhys_Mindlin"} <= set(names)
    text = _words(_text(out, os.path.join("reference", "yade-classes.html"))).replace("\u2019", "'")
    for name in names:
        assert name in text, name
    installed, line = yc.plugin_state(REPO)
    if not installed:
        assert "The YADE plugin was not built where this manual was built" in text
        return
    docs = _source_docs()
    assert set(names) <= set(docs), "classes without a YADE_CLASS_BASE_DOC macro: %s" % (set(names) - set(docs))
    for name in names:
        assert _words(docs[name].replace(":yref:", "").replace("`", "")[:40]) in text, name
    for attribute in ("sigmaZ", "stressTolerance", "gammaTarget", "restrainRotations", "NcOverV"):
        assert attribute in text


def test_the_yade_class_reference_says_why_it_is_empty_where_the_plugin_is_not_built(tmp_path):
    yc = _yade_classes()
    os.makedirs(tmp_path / "engines" / "yade")
    for path in glob.glob(os.path.join(REPO, "engines", "yade", "*.cpp")):
        os.symlink(path, tmp_path / "engines" / "yade" / os.path.basename(path))
    note = yc.markdown(str(tmp_path))
    assert "was not built" in note and "build/yade-plugin.status is missing" in note
    os.makedirs(tmp_path / "build")
    (tmp_path / "build" / "yade-plugin.status").write_text("no-source: no YADE source (set TRUEANISO_YADE_SOURCE)\n")
    note = yc.markdown(str(tmp_path))
    assert "no-source: no YADE source" in note and "`StressProbe`" in note


def _plugin_docstrings():
    """{class: its docstrings (the class's, its attributes', its methods'), joined} from the string
    literals of engines/yade/*.hpp from a YADE_CLASS_BASE_DOC* macro to the `// clang-format on`
    after it, C escapes undone."""
    docs = {}
    for path in glob.glob(os.path.join(REPO, "engines", "yade", "*.hpp")):
        with open(path) as f:
            text = f.read()
        for name, body in re.findall(r"YADE_CLASS_BASE_DOC\w*\(\s*(\w+)(.*?)// clang-format on", text, flags=re.S):
            literals = re.findall(r'"((?:[^"\\]|\\.)*)"', body)
            docs[name] = re.sub(r"\\(.)", lambda m: " " if m.group(1) == "n" else m.group(1), " ".join(literals))
    return docs


def test_the_plugin_s_docstrings_write_their_formulas_between_dollars():
    """What a YADE user reads in help() and the GUI's inspector, and what the YADE classes' page is
    generated from: every formula of the plugin's docstrings is TeX between single dollars (YADE's
    own convention, which the page's generator and YADE's manual turn into math), none left as
    ASCII. Read from the source, so it holds where the plugin is not built (./test.sh)."""
    docs = _plugin_docstrings()
    assert {"SimplifiedMindlinPhys", "FabricRecorder", "StressProbe", "TrueTriaxialServo"} <= set(docs)
    raw, formulas = [], 0
    for name, text in docs.items():
        formulas += len(re.findall(r"(?<!\\)\$[^$`]+\$", text))
        prose = re.sub(r"(?<!\\)\$[^$`]+\$|``[^`]*``|:y\w+:`[^`]*`", " ", text)
        raw += ["%s: ...%s..." % (name, prose[max(0, m.start() - 30):m.end() + 20])
                for m in re.finditer(RAW_FORMULA, prose)]
    assert not raw, "\n".join(raw)
    assert formulas >= 40, formulas
    assert r"$k_n = C_n (\bar r N)^{1/3}$" in docs["SimplifiedMindlinPhys"]


def test_a_docstring_formula_between_dollars_becomes_math():
    """The generators' side: $x$ becomes a math role on the YADE page (MyST) and in the Python API
    (reStructuredText, through autodoc); an escaped \\$ and a dollar in code stay as they are, and
    so do doctest and literal blocks."""
    yc = _yade_classes()
    md = yc.to_markdown(r"$k_n = C_n (\bar r N)^{1/3}$ [$\mathrm{Pa}^{2/3}$], a \$5 fee, ``a$b`` and :math:`y`", set())
    assert md == r"{math}`k_n = C_n (\bar r N)^{1/3}` [{math}`\mathrm{Pa}^{2/3}`], a \$5 fee, `a$b` and {math}`y`"
    import trueaniso_manual
    lines = ["Eq. (25): $a_i^2 = E_i^{1/3}/(E_j E_k)^{1/6}$.", "", ">>> print('$x$')", "$x$", "",
             "Literal::", "", "    $y$", "", "after $\\nu$"]
    trueaniso_manual.docstring_math(None, "function", "f", None, {}, lines)
    # and a script's --help, which shows its docstring's first paragraph in a terminal, drops the dollars
    from trueaniso import cli
    assert cli.description("The factor $\\zeta$ fitted on $a_i^2$, a \\$5 fee.\n\nMore.") == \
        "The factor \\zeta fitted on a_i^2, a \\$5 fee."
    assert lines == ["Eq. (25): :math:`a_i^2 = E_i^{1/3}/(E_j E_k)^{1/6}`.", "", ">>> print('$x$')", "$x$", "",
                     "Literal::", "", "    $y$", "", "after :math:`\\nu`"]


USER_PAGES_MAX_LINES = 2500


def test_the_user_manual_stays_under_2500_lines():
    """The user-facing pages (tutorial, how-tos, reference, explanation: every docs/**/*.md but
    docs/studies/ and docs/report-*/) hold under 2,500 lines together: each gives the choice, its
    default and the measurement behind it; investigations go to docs/studies/ as short reports."""
    sources = [p for p in glob.glob(os.path.join(DOCS, "**", "*.md"), recursive=True)
               if _user_page(os.path.relpath(p, DOCS))]
    assert len(sources) >= 30 and os.path.join(DOCS, "tutorial.md") in sources
    lines = {}
    for path in sources:
        with open(path) as f:
            lines[os.path.relpath(path, DOCS)] = len(f.read().splitlines())
    longest = sorted(lines.items(), key=lambda kv: -kv[1])[:5]
    assert sum(lines.values()) < USER_PAGES_MAX_LINES, "%d lines; the longest pages: %s" % (sum(lines.values()), longest)


def test_the_index_opens_with_an_example_that_prints_what_it_shows():
    """docs/index.md opens with a Python example (within its first lines, before anything else in
    a code block) and the output it shows; run from the repository's root, the example prints
    exactly that."""
    with open(os.path.join(DOCS, "index.md")) as f:
        text = f.read()
    blocks = re.findall(r"```(\w*)\n(.*?)```", text, flags=re.S)
    assert blocks[0][0] == "python" and blocks[1][0] == "text", blocks[:2]
    assert text.index("```python") < 600, "the index does not open with its example"
    code, shown = blocks[0][1], blocks[1][1]
    done = subprocess.run([PYTHON, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert done.returncode == 0, done.stderr[-3000:]
    assert done.stdout == shown


def test_the_api_page_s_examples_and_the_index_s_call_the_public_modules_and_run():
    """The index's example and the Python API page's call the package one way: through the modules
    a script calls (trueaniso.PUBLIC_MODULES), not the internal ones (the engines' module among
    them). The API page's examples, run in order from the repository's root on a committed
    300-sphere specimen in place of the tutorial's, run."""
    import trueaniso
    with open(os.path.join(DOCS, "reference", "python-api.md")) as f:
        api = re.findall(r"```python\n(.*?)```", f.read(), flags=re.S)
    with open(os.path.join(DOCS, "index.md")) as f:
        index = re.findall(r"```python\n(.*?)```", f.read(), flags=re.S)[:1]
    assert len(api) >= 2 and index
    for code in api + index:
        for imported in re.findall(r"^from trueaniso(\.\w+)? import (.+)$", code, flags=re.M):
            names = [imported[0][1:]] if imported[0] else [n.strip() for n in imported[1].split(",")]
            internal = [n for n in names if n not in trueaniso.PUBLIC_MODULES]
            assert not internal, "an example imports internal modules: %s" % internal
        assert not re.search(r"\bengines\.", code), "an example calls the engines' module:\n" + code
    code = "\n".join(api).replace("results/tutorial/specimen.npz", "tests/data/spheres-300-s6.npz")
    assert "spheres-300-s6.npz" in code
    done = subprocess.run([PYTHON, "-c", code], cwd=REPO, capture_output=True, text=True, timeout=600,
                          env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert done.returncode == 0, done.stderr[-3000:]
