"""The manual (docs/, Sphinx with myst-parser): it builds with no warning, its reference covers every
script, module and input schema, the benchmark tables are where the scripts write them, and the
tutorial's commands, run as written, give what the tutorial says."""
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
    """Every user script (pyscripts/*.py), analysis tool and benchmark script has its --help in the
    reference, as the script prints it (a new script is picked up without an edit of the page)."""
    proc, out = manual
    assert proc.returncode == 0
    html = _text(out, os.path.join("reference", "scripts.html"))
    scripts = sorted(glob.glob(os.path.join(REPO, "pyscripts", "*.py")))
    bench = sorted(p for p in glob.glob(os.path.join(REPO, "bench", "*.py"))
                   if not os.path.basename(p).startswith("_"))
    assert len(scripts) >= 3 and len(bench) >= 10
    for path in scripts + bench:
        rel = os.path.relpath(path, REPO)
        assert rel in html, "%s has no section in reference/scripts" % rel
    assert html.count("usage:") >= len(scripts) + len(bench), "a section without the script's usage"
    for tool in ("report", "figures", "zeta_contrast", "cross_anisotropy", "path_fidelity"):
        assert "python3 -m trueaniso.analysis.%s" % tool in html
    cores = os.cpu_count() or 1
    for said in (r"all\s+%d\s+cores" % cores, r"at most\s+%d\s+\(" % (4 * cores)):
        assert not re.search(said, html), "the help names this machine's core count: %s" % said
    assert REPO not in html, "the help names this checkout's path"


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
    names = set(re.findall(r'replace_block\([^,]+,\s*"([\w-]+)"', text))
    names |= set(re.findall(r'"--block",\s*default="([\w-]+)"', text))
    headings = set(re.findall(r'heading="(#+ [^"]+)"', text))
    return names, headings


def test_the_benchmark_tables_are_where_the_scripts_write_them():
    """Every heading a bench script writes under is a line of its page, and every "Reproduce:" line
    of the docs that runs a bench script with --doc names a block that page holds between markers
    (renaming a heading or a marker without the script, or the reverse, fails here)."""
    with open(os.path.join(DOCS, "benchmarks.md")) as f:
        lines = f.read().split("\n")
    checked = 0
    for path in glob.glob(os.path.join(REPO, "bench", "*.py")):
        for heading in _bench_names(path)[1]:
            assert heading in lines, "%s writes under %r, which docs/benchmarks.md lacks" % (path, heading)
            checked += 1
    assert checked >= 3
    reproduced = 0
    for page in glob.glob(os.path.join(DOCS, "*.md")):
        with open(page) as f:
            text = f.read()
        for command in re.findall(r"Reproduce: `([^`]*bench/[^`]*--doc [^`]*)`", text):
            words = shlex.split(command)
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
