"""Sphinx extension of the trueaniso manual: pages generated from the code at build time.

A page holding a line ``<!-- generated: KIND -->`` gets Markdown in its place (``source-read``):

* ``scripts``: every user script's ``--help`` (pyscripts/*.py);
* ``analysis-tools``: the ``--help`` of every analysis module that runs as a tool;
* ``bench``: the ``--help`` of every benchmark script (pyscripts/bench/*.py);
* ``python-api``: an autodoc section per module of the ``trueaniso`` and ``analysis`` packages,
  whose docstrings (plain text) are shown as written.

The lists are discovered from the files, so a new script or module has its page without an edit.
"""
import glob
import os
import re
import subprocess

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PYTHON = "/usr/bin/python3"
MARKER = re.compile(r"<!-- generated: ([a-z-]+) -->")


def user_scripts():
    return sorted(os.path.relpath(p, REPO) for p in glob.glob(os.path.join(REPO, "pyscripts", "*.py")))


def bench_scripts():
    return sorted(os.path.relpath(p, REPO) for p in glob.glob(os.path.join(REPO, "pyscripts", "bench", "*.py"))
                  if not os.path.basename(p).startswith("_"))


def modules(package, folder):
    """Module names of a package folder, the package itself first."""
    names = [package]
    for path in sorted(glob.glob(os.path.join(REPO, folder, "*.py"))):
        name = os.path.splitext(os.path.basename(path))[0]
        if name != "__init__":
            names.append("%s.%s" % (package, name))
    return names


def api_modules():
    return modules("trueaniso", os.path.join("pyscripts", "trueaniso")) + modules("analysis", "analysis")


def analysis_tools():
    """Analysis modules that run as a tool (``python3 -m analysis.X``)."""
    tools = []
    for name in modules("analysis", "analysis")[1:]:
        with open(os.path.join(REPO, "analysis", name.split(".")[1] + ".py")) as f:
            if "__main__" in f.read():
                tools.append(name)
    return tools


def machine_independent(text):
    """The help as it reads on any machine: core counts and the repository's place are not printed."""
    cores = os.cpu_count() or 1
    text = text.replace(REPO + os.sep, "").replace(REPO, ".")
    # argparse may wrap a line anywhere: match the words across the wrap and keep its whitespace
    text = re.sub(r"\ball(\s+)%d(\s+)cores\b" % cores, r"all\1the\2cores", text)
    text = re.sub(r"\b%d(\s+)cores\b" % cores, r"N\1cores", text)
    text = re.sub(r"at most %d(\s+)\(4 x the(\s+)cores\)" % (4 * cores), r"at most\g<1>4 x the\g<2>cores", text)
    return text


def help_text(args):
    env = dict(os.environ, COLUMNS="100", OMP_NUM_THREADS="1", PYTHONDONTWRITEBYTECODE="1")
    done = subprocess.run([PYTHON] + args + ["--help"], cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=120)
    if done.returncode != 0:
        raise RuntimeError("%s --help failed (%d): %s" % (" ".join(args), done.returncode, done.stderr[-2000:]))
    return machine_independent(done.stdout)


def help_section(title, args):
    body = help_text(args).rstrip()
    return "### `%s`\n\n```text\n%s\n```\n\n" % (title, body)


def generate(kind):
    if kind == "scripts":
        return "".join(help_section(s, [s]) for s in user_scripts())
    if kind == "analysis-tools":
        return "".join(help_section("python3 -m " + m, ["-m", m]) for m in analysis_tools())
    if kind == "bench":
        return "".join(help_section(s, [s]) for s in bench_scripts())
    if kind == "python-api":
        out = []
        for name in api_modules():
            out.append("## `%s`\n\n```{eval-rst}\n.. automodule:: %s\n   :members:\n   :undoc-members:\n"
                       "   :show-inheritance:\n```\n\n" % (name, name))
        return "".join(out)
    raise ValueError("unknown generated section %r" % kind)


def plain_docstring(app, what, name, obj, options, lines):
    """The package's docstrings are plain text (equations, tables, indented examples), not
    reStructuredText: shown as written, in a literal block, they need no markup and warn of none."""
    if any(line.strip() for line in lines):
        text = [line.rstrip() for line in lines]
        while text and not text[-1]:
            text.pop()
        lines[:] = ["::", ""] + ["   " + line if line else "" for line in text] + [""]


def on_source_read(app, docname, source):
    source[0] = MARKER.sub(lambda m: generate(m.group(1)), source[0])


def setup(app):
    app.connect("source-read", on_source_read)
    app.connect("autodoc-process-docstring", plain_docstring)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
