"""Sphinx extension of the trueaniso manual: pages generated from the code at build time.

A page holding a line ``<!-- generated: KIND -->`` gets Markdown in its place (``source-read``):

* ``scripts``: every user script's ``--help`` (pyscripts/*.py);
* ``analysis-tools``: the ``--help`` of every analysis module that runs as a tool;
* ``bench``: the ``--help`` of every benchmark script (bench/*.py), on a page of the studies
  (studies/bench-scripts): the scripts reference lists the product's scripts only;
* ``python-api``: an autodoc section per module of the ``trueaniso`` package and its ``analysis``:
  the modules a user's script calls first (``trueaniso.PUBLIC_MODULES``, each with the functions
  of its ``__all__``), then the internal ones under a heading that says so; docstrings are Google
  style, read by napoleon;
* ``yade-classes``: the classes of the YADE plugin (engines/yade) with their attributes, read
  from the classes as yade-double loads them (yade_classes.py), or a note where the plugin is not
  built.

The lists are discovered from the files, so a new script or module has its page without an edit.

The directive ``schema-table`` (```` ```{schema-table} NAME``` ````) renders the fields of one of
the schemas trueaniso checks its input files against (``trueaniso.validate``) as a table: the format
pages show what the check asks for in the schema's own words.
"""
import glob
import json
import os
import re
import subprocess

from docutils import nodes
from docutils.parsers.rst import Directive

import yade_classes

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PYTHON = "/usr/bin/python3"
MARKER = re.compile(r"<!-- generated: ([a-z-]+) -->")


def user_scripts():
    return sorted(os.path.relpath(p, REPO) for p in glob.glob(os.path.join(REPO, "pyscripts", "*.py")))


def bench_scripts():
    return sorted(os.path.relpath(p, REPO) for p in glob.glob(os.path.join(REPO, "bench", "*.py"))
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
    return (modules("trueaniso", os.path.join("pyscripts", "trueaniso"))
            + modules("trueaniso.analysis", os.path.join("pyscripts", "trueaniso", "analysis")))


def public_and_internal():
    """(public, internal) module names: the package, then trueaniso.PUBLIC_MODULES in its order;
    every other module of the folders is internal."""
    import trueaniso
    public = ["trueaniso"] + ["trueaniso." + m for m in trueaniso.PUBLIC_MODULES]
    found = api_modules()
    unknown = [m for m in public if m not in found]
    if unknown:
        raise ValueError("trueaniso.PUBLIC_MODULES names modules that do not exist: %s" % ", ".join(unknown))
    return public, [m for m in found if m not in public]


def automodule(name, level):
    return ("%s `%s`\n\n```{eval-rst}\n.. automodule:: %s\n   :members:\n   :undoc-members:\n"
            "   :show-inheritance:\n```\n\n" % ("#" * level, name, name))


def python_api():
    public, internal = public_and_internal()
    return ("".join(automodule(name, 2) for name in public)
            + "## Internal modules\n\n"
            "These serve the scripts and the modules above. They are documented for those who change "
            "trueaniso; a script of yours should not need them, and their functions may change without "
            "notice.\n\n"
            + "".join(automodule(name, 3) for name in internal))


def analysis_tools():
    """Analysis modules that run as a tool (``python3 -m trueaniso.analysis.X``)."""
    tools = []
    for name in modules("trueaniso.analysis", os.path.join("pyscripts", "trueaniso", "analysis"))[1:]:
        with open(os.path.join(REPO, "pyscripts", "trueaniso", "analysis", name.rsplit(".", 1)[1] + ".py")) as f:
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
    env = dict(os.environ, COLUMNS="100", OMP_NUM_THREADS="1", PYTHONDONTWRITEBYTECODE="1",
               PYTHONPATH=os.path.join(REPO, "pyscripts"))
    done = subprocess.run([PYTHON] + args + ["--help"], cwd=REPO, env=env, capture_output=True, text=True,
                          timeout=120)
    if done.returncode != 0:
        raise RuntimeError("%s --help failed (%d): %s" % (" ".join(args), done.returncode, done.stderr[-2000:]))
    return machine_independent(done.stdout)


def help_section(title, args, level=3):
    body = help_text(args).rstrip()
    return "%s `%s`\n\n```text\n%s\n```\n\n" % ("#" * level, title, body)


def generate(kind):
    if kind == "scripts":
        return "".join(help_section(s, [s]) for s in user_scripts())
    if kind == "analysis-tools":
        return "".join(help_section("python3 -m " + m, ["-m", m]) for m in analysis_tools())
    if kind == "bench":
        return "".join(help_section(s, [s], level=2) for s in bench_scripts())  # a page of its own
    if kind == "python-api":
        return python_api()
    if kind == "yade-classes":
        return yade_classes.markdown(REPO)
    raise ValueError("unknown generated section %r" % kind)


# --- ```{schema-table} NAME```: a schema's fields as a table -------------------------------------

def _schema(name):
    """Schema `name` of trueaniso.validate (its file in pyscripts/trueaniso/schemas/)."""
    from trueaniso import validate
    if name not in validate.NAMES + ("specimen_arrays",):
        raise ValueError("schema-table: unknown schema %r (known: %s, specimen_arrays)"
                         % (name, ", ".join(validate.NAMES)))
    return validate.schema(name)


def schema_file(name):
    """The file name of schema `name`, as the page shows it."""
    return name + (".json" if name == "specimen_arrays" else ".schema.json")


def _resolved(sub, root):
    """`sub` with a local $ref (#/definitions/X) merged in, its own keys winning."""
    ref = sub.get("$ref", "")
    if ref.startswith("#/"):
        target = root
        for key in ref[2:].split("/"):
            target = target[key]
        merged = dict(_resolved(target, root))
        merged.update((k, v) for k, v in sub.items() if k != "$ref")
        if "description" in target and target is not sub:
            merged["_kind"] = target["description"]
        return merged
    return sub


def _value(v):
    return json.dumps(v)


def _type_words(sub, root):
    """(type, constraints) of a (sub)schema in words: ('number', ['finite', '> 0'])."""
    sub = _resolved(sub, root)
    if "anyOf" in sub:
        parts = [_type_words(s, root) for s in sub["anyOf"]]
        constrained = [(t, c) for t, c in parts if c]
        if len(constrained) == 1:
            return _alternatives([t for t, _ in parts]), constrained[0][1]
        # each alternative's own constraints, said with its type: "number: finite, > 0; or string: ..."
        return _alternatives([t for t, _ in parts]), ["%s%s: %s" % ("or " if k else "", t, ", ".join(c))
                                                      for k, (t, c) in enumerate(constrained)]
    constraints = []
    types = sub.get("type", [])
    types = [types] if isinstance(types, str) else list(types)
    if "const" in sub:
        types = types or [type(sub["const"]).__name__.replace("str", "string").replace("int", "integer")]
        constraints.append("always %s" % _value(sub["const"]))
    if "enum" in sub:
        kinds = sorted({type(v).__name__ for v in sub["enum"]})
        types = types or ["string" if kinds == ["str"] else "integer" if kinds == ["int"] else "any"]
        constraints.append("one of " + ", ".join(_value(v) for v in sub["enum"]))
    if "number" in types:
        constraints.append("finite")
    for key, op in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="), ("exclusiveMaximum", "<")):
        if key in sub:
            constraints.append("%s %s" % (op, _value(sub[key])))
    if "_kind" in sub:
        constraints.append(sub["_kind"])
    elif "pattern" in sub:
        constraints.append("matches %s" % sub["pattern"])
    if sub.get("minLength") == 1:
        constraints.append("not empty")
    elif sub.get("minLength"):
        constraints.append("at least %d characters" % sub["minLength"])
    if "array" in types:
        if sub.get("minItems") is not None and sub.get("minItems") == sub.get("maxItems"):
            constraints.append("%d items" % sub["minItems"])
        else:
            if "minItems" in sub:
                constraints.append("at least %d items" % sub["minItems"])
            if "maxItems" in sub:
                constraints.append("at most %d items" % sub["maxItems"])
        if "items" in sub:
            item_type, item_constraints = _type_words(sub["items"], root)
            types[types.index("array")] = "array of %s" % ("(%s)" % item_type if " or " in item_type else item_type)
            constraints.extend("each %s" % c for c in item_constraints)
    return _alternatives(types) or "any", constraints


def _alternatives(words):
    return " or ".join(words) if len(words) < 3 else ", ".join(words[:-1]) + " or " + words[-1]


def _object_parts(sub, root, extends):
    """The properties, required names and additionalProperties of an object schema, allOf merged;
    a $ref to another schema file is recorded in `extends` (its fields are that schema's table)."""
    sub = _resolved(sub, root)
    properties, required, additional = dict(sub.get("properties", {})), set(sub.get("required", [])), \
        sub.get("additionalProperties")
    for part in sub.get("allOf", []):
        if "$ref" in part and not part["$ref"].startswith("#"):
            extends.append(part["$ref"])
            required |= set(_schema(part["$ref"].split(".")[0]).get("required", []))
            continue
        p, r, a = _object_parts(part, root, extends)
        for key, value in p.items():
            properties[key] = dict(properties.get(key, {}), **value)
        required |= r
        additional = additional if a is None else a
    return properties, required, additional


def schema_rows(name):
    """(field, type, constraints, required, description) of every field of schema `name` (required
    None for the arrays of specimen_arrays, which the format's version decides), nested
    objects and the objects of lists followed into: a field is a dotted path into the file, ``*``
    stands for any key and ``[]`` for each item of a list. Also the schema's title, description and
    the schema files it extends."""
    root = _schema(name)
    rows, extends = [], []
    if "arrays" in root:  # specimen_arrays.json: a declarative table, not JSON Schema
        for key, spec in root["arrays"].items():
            shape = "(%s)" % ", ".join(str(n) for n in spec["shape"]) if len(spec["shape"]) > 1 \
                else "(%s,)" % spec["shape"][0]
            rows.append((key, "%s array %s" % (spec["kind"], shape), ["finite"] if spec.get("finite") else [],
                         None, spec["description"]))
        return root, rows, extends

    def walk(sub, prefix, required_names):
        sub = _resolved(sub, root)
        if sub.get("type") == "array" and "items" in sub and \
                (_resolved(sub["items"], root).get("properties") or _resolved(sub["items"], root).get("allOf")):
            walk(sub["items"], prefix + "[]", required_names)
            return
        properties, required, additional = _object_parts(sub, root, extends)
        for key, prop in properties.items():
            path = prefix + ("." if prefix else "") + key
            kind, constraints = _type_words(prop, root)
            rows.append((path, kind, constraints, "required" if key in required else "optional",
                         _resolved(prop, root).get("description", "")))
            inner = _resolved(prop, root)
            if inner.get("properties") or isinstance(inner.get("additionalProperties"), dict) or \
                    (inner.get("type") == "array" and isinstance(inner.get("items"), dict)
                     and _resolved(inner["items"], root).get("properties")):
                walk(inner, path, required)
        if isinstance(additional, dict):
            path = prefix + ("." if prefix else "") + "*"
            kind, constraints = _type_words(additional, root)
            description = additional.get("description", "")
            names = sub.get("propertyNames")
            if names:
                constraints = ["name %s" % c for c in _type_words(names, root)[1]] + constraints
                description = "%s; the name: %s" % (description, names.get("description", "")) if description \
                    else names.get("description", "")
            rows.append((path, kind, constraints, "any other key", description or
                         _resolved(additional, root).get("description", "one entry per key")))
            if _resolved(additional, root).get("properties"):
                walk(additional, path, set())

    walk(root, "", set())
    return root, rows, extends


def _with_math(text):
    """Nodes of a schema's words: text, and each $x$ of it a formula (MathJax), as in the docstrings."""
    found, at = [], 0
    for m in yade_classes.DOLLARS.finditer(text):
        found += [nodes.Text(text[at:m.start()]), nodes.math(m.group(1), m.group(1))]
        at = m.end()
    return found + [nodes.Text(text[at:])]


def _cell(*children):
    entry = nodes.entry()
    paragraph = nodes.paragraph()
    paragraph.extend(children)
    entry += paragraph
    return entry


class SchemaTable(Directive):
    """```{schema-table} NAME```: the fields of schema NAME (trueaniso.validate.schema) as a table,
    under a line naming its file and its description; the schema's own words, so the page and the
    check that refuses a file cannot disagree."""
    required_arguments = 1
    has_content = False

    def run(self):
        name = self.arguments[0]
        try:
            root, rows, extends = schema_rows(name)
        except (ValueError, OSError, KeyError) as e:
            raise self.error(str(e))
        self.state.document.settings.env.note_dependency(
            os.path.join(REPO, "pyscripts", "trueaniso", "schemas", schema_file(name)))
        intro = nodes.paragraph()
        intro += nodes.Text("Schema ")
        intro += nodes.literal(text=schema_file(name))
        intro.extend(_with_math(" (pyscripts/trueaniso/schemas/): %s" % root.get("description", root.get("title", ""))))
        if extends:
            intro += nodes.Text(" Every field of ")
            for i, ref in enumerate(extends):
                intro += nodes.Text(", " if i else "")
                intro += nodes.literal(text=ref)
            intro += nodes.Text(", and:")
        with_required = any(row[3] is not None for row in rows)
        headings = ("field", "type", "constraints") + (("required",) if with_required else ()) + ("description",)
        widths = (22, 12, 22) + ((10,) if with_required else ()) + (34,)
        table = nodes.table(classes=["schema-table", "schema-" + name.replace("_", "-")])
        group = nodes.tgroup(cols=len(headings))
        table += group
        for width in widths:
            group += nodes.colspec(colwidth=width)
        head = nodes.thead()
        row = nodes.row()
        for heading in headings:
            row += _cell(nodes.Text(heading))
        head += row
        group += head
        body = nodes.tbody()
        for field, kind, constraints, required, description in rows:
            row = nodes.row()
            row += _cell(nodes.literal(text=field))
            row += _cell(nodes.Text(kind))
            row += _cell(nodes.Text("; ".join(constraints)))
            if with_required:
                row += _cell(nodes.Text(required))
            row += _cell(*_with_math(description))
            body += row
        group += body
        # the schema's words as written: no curly quotes or dashes made of its ' and --
        for node in (intro, table):
            node["support_smartquotes"] = False
        return [intro, table]


# Debian's MathJax 2 (libjs-mathjax), the parts the TeX-AMS_CHTML configuration loads: the manual
# then renders its formulas without a network. conf.py points mathjax_path here when it exists.
MATHJAX_PARTS = ("MathJax.js", "config/TeX-AMS_CHTML.js", "extensions", "jax/input/TeX", "jax/output/CommonHTML",
                 "jax/element", "localization/en", "fonts/HTML-CSS/TeX/woff")


def copy_mathjax(app, exception):
    source = app.config.trueaniso_mathjax_dir
    if exception is not None or app.builder.format != "html" or not source or \
            not app.config.mathjax_path.startswith("mathjax/"):
        return
    import shutil
    target = os.path.join(app.outdir, "_static", "mathjax")
    for part in MATHJAX_PARTS:
        src, dst = os.path.join(source, part), os.path.join(target, part)
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        if os.path.isdir(src):
            shutil.copytree(src, dst, dirs_exist_ok=True)
        else:
            shutil.copyfile(src, dst)


def on_source_read(app, docname, source):
    source[0] = MARKER.sub(lambda m: generate(m.group(1)), source[0])


def docstring_math(app, what, name, obj, options, lines):
    """A docstring's formulas, written between dollars as the YADE plugin's are (yade_classes.py:
    TeX that reads as it stands in help()), as :math: roles for MathJax. Doctest blocks (from a
    ``>>>`` line to the next blank one) and literal blocks (after a line ending in ``::``) are
    code and stay as they are."""
    doctest, literal = False, None
    for i, line in enumerate(lines):
        text = line.strip()
        indent = len(line) - len(line.lstrip())
        if literal is not None and (not text or indent > literal):
            continue
        literal = None
        doctest = text.startswith(">>>") or (doctest and bool(text))
        if doctest:
            continue
        lines[i] = yade_classes.dollar_math(line, ":math:")
        if text.endswith("::") and not text.startswith(".. math::"):
            literal = indent


def setup(app):
    app.connect("source-read", on_source_read)
    app.connect("autodoc-process-docstring", docstring_math)
    app.add_config_value("trueaniso_mathjax_dir", None, "html")
    app.connect("build-finished", copy_mathjax)
    app.add_directive("schema-table", SchemaTable)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}
