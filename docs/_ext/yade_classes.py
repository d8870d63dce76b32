"""The YADE classes' reference, generated when the manual is built, as YADE's own manual is: the
classes the plugin registers (its ``YADE_PLUGIN((A)(B)...)`` in engines/yade/*.cpp) are loaded in
yade-double from build/yade-prefix, and their docstrings and attributes' docstrings (YADE's
``YADE_CLASS_BASE_DOC_*`` macros: text, then ``:ydefault:``, ``:yattrtype:``, ``:yattrflags:``) are
turned into one section per class with a table of its attributes.

Where the plugin is not installed (build/yade-plugin.status is not ``installed``: no YADE source,
``./test.sh`` alone), the page says so and why, and lists the classes by name from the source."""
import glob
import json
import os
import re
import subprocess

HERE = os.path.dirname(os.path.abspath(__file__))
LIBDIR = os.path.join("lib", "x86_64-linux-gnu", "yade-double")
YADE_DOCS = "https://yade-dem.org/doc/yade.wrapper.html#yade.wrapper.%s"
# YADE's attribute flags (lib/serialization/Serializable.hpp, Attr::), those a user needs to know
FLAGS = {2: "read-only", 1: "not saved"}
# YADE's rule for a formula in a docstring (its doc/sphinx/conf.py): an unescaped $x$; here also
# no backtick inside, so that a code span holding a dollar stays code
DOLLARS = re.compile(r"(?<!\\)\$([^$`]+)(?<!\\)\$")


def dollar_math(text, role):
    """`text` with each $x$ written as the given role of x (``{math}`x` `` in MyST, ``:math:`x` ``
    in reStructuredText)."""
    return DOLLARS.sub(lambda m: "%s`%s`" % (role, m.group(1)), text)


def plugin_classes(repo):
    """The class names of the plugin's YADE_PLUGIN((A)(B)...) macros, in their order, the ABI
    self-test's (TrueanisoAbiCheck, a build check) left out."""
    names = []
    for path in sorted(glob.glob(os.path.join(repo, "engines", "yade", "*.cpp"))):
        with open(path) as f:
            for macro in re.findall(r"YADE_PLUGIN\(((?:\s*\(\s*\w+\s*\))+)\s*\)", f.read()):
                names += re.findall(r"\(\s*(\w+)\s*\)", macro)
    return [n for n in names if n != "TrueanisoAbiCheck"]


def plugin_state(repo):
    """(installed?, the status line of cmake/yade_plugin.sh or why there is none)."""
    status = os.path.join(repo, "build", "yade-plugin.status")
    try:
        with open(status) as f:
            line = f.read().strip()
    except OSError:
        return False, "the plugin has not been built in this checkout (build/yade-plugin.status is missing)"
    library = os.path.join(repo, "build", "yade-prefix", LIBDIR, "libtrueanisoYade.so")
    if line == "installed" and os.path.exists(library):
        return True, line
    return False, line


def loaded_classes(repo, names):
    """The classes as yade-double loads them from build/yade-prefix (yade_class_dump.py)."""
    env = dict(os.environ, YADE_PREFIX=os.path.join(repo, "build", "yade-prefix"), OMP_NUM_THREADS="1")
    done = subprocess.run(["yade-double", "-n", "-x", os.path.join(HERE, "yade_class_dump.py")] + names,
                          cwd=repo, env=env, capture_output=True, text=True, timeout=300)
    for line in done.stdout.splitlines():
        if line.startswith("TRUEANISO-YADE-CLASSES "):
            return json.loads(line.split(" ", 1)[1])
    raise RuntimeError("yade-double could not list the plugin's classes (exit %d):\n%s\n%s"
                       % (done.returncode, done.stdout[-2000:], done.stderr[-3000:]))


def split_roles(doc):
    """(text, default, type, flags) of a YADE attribute docstring."""
    found = {}
    for role in ("ydefault", "yattrtype", "yattrflags"):
        m = re.search(r":%s:`([^`]*)`" % role, doc)
        found[role] = m.group(1) if m else ""
        doc = doc.replace(m.group(0), "") if m else doc
    return " ".join(doc.split()), found["ydefault"], found["yattrtype"], found["yattrflags"]


def to_markdown(text, ours):
    """YADE's reStructuredText roles in a docstring as Markdown: :yref:`X` a link (to this page for
    the plugin's classes, to YADE's reference for YADE's), ``x`` code, $x$ and :math:`x` MathJax.

    The plugin writes its formulas as YADE's own classes do, between single dollars (YADE's
    doc/sphinx/conf.py turns an unescaped $x$ into :math:`x` and \\$ into a dollar): TeX that a
    user reads as it stands in help() and in the GUI's inspector, which print docstrings raw. Each
    formula becomes a {math} role, whose code span keeps its backslashes and underscores from
    Markdown, and which needs no $ or | to mean math inside a table's cell."""
    def yref(m):
        label, target = m.group(1).strip(), (m.group(2) or m.group(1)).strip()
        cls = re.split(r"::|\.", target)[0]
        if cls in ours:
            return "[`%s`](#%s)" % (label, cls.lower())
        return "[`%s`](%s)" % (label, YADE_DOCS % target.replace("::", "."))
    text = re.sub(r":yref:`([^`<]*?)\s*(?:<([^`>]*)>)?`", yref, text)
    text = re.sub(r":ref:`([^`<]*?)\s*<[^`]*>`", r"\1", text)
    text = text.replace("|yupdate|", "(updated by the engine)").replace("|ycomp|", "(computed)")
    text = re.sub(r"``([^`]+)``", r"`\1`", text)
    text = re.sub(r":math:`([^`]*)`", r"{math}`\1`", text)
    return dollar_math(text, "{math}")


def cell(text):
    return text.replace("|", "\\|").replace("\n", " ")


def default_of(attribute, ydefault):
    value = attribute.get("value")
    if value is not None and len(value) <= 40:
        return value
    return ydefault


def section(cls, ours):
    out = ["## `%s`\n" % cls["name"],
           "Base: [`%s`](%s)\n" % (cls["base"], YADE_DOCS % cls["base"]),
           to_markdown(" ".join(cls["doc"].split()), ours) + "\n"]
    if cls["attributes"]:
        out.append("| attribute | type | default | what |\n|---|---|---|---|")
        for attribute in cls["attributes"]:
            text, ydefault, kind, flags = split_roles(attribute["doc"])
            said = [word for bit, word in FLAGS.items() if flags.isdigit() and int(flags) & bit]
            what = to_markdown(text, ours) + (" (%s)" % ", ".join(said) if said else "")
            out.append("| `%s` | %s | `%s` | %s |" % (attribute["name"], cell(kind), cell(default_of(attribute, ydefault)),
                                                     cell(what)))
        out.append("")
    for method in cls["methods"]:
        doc = method["doc"].strip().split("\n")
        signature = doc[0].strip() if doc else method["name"]
        text = " ".join(" ".join(doc[1:]).split()).lstrip(": ").strip()
        out.append("Method `%s`: %s\n" % (method["name"], to_markdown(text, ours) or signature))
    return "\n".join(out) + "\n"


def markdown(repo):
    """The page's generated part: one section per class, or, without the plugin, the note."""
    names = plugin_classes(repo)
    if not names:
        raise RuntimeError("no YADE_PLUGIN((...)) macro found in engines/yade/*.cpp")
    installed, line = plugin_state(repo)
    if not installed:
        return ("```{note}\nThe YADE plugin was not built where this manual was built (%s), so its classes' "
                "documentation, which is read from the loaded classes, is not here. `./setup.sh` builds the "
                "plugin when the YADE 2023.02a source is at hand (`TRUEANISO_YADE_SOURCE=...`, "
                "{doc}`../yade-peer`); `./docs/build.sh` then puts it on this page. The plugin's classes: %s.\n```\n"
                % (line.rstrip("."), ", ".join("`%s`" % n for n in names)))
    classes = loaded_classes(repo, names)
    ours = {c["name"] for c in classes}
    return "".join(section(c, ours) for c in classes)
