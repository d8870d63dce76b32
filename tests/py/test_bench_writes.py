"""Benchmarks write into docs/ only when asked: a script of bench/ replaces a block of a manual page
only with the file its --doc names, and writes no other file under docs/ unless an option names it
(a CSV, a figure, a JSON); read it the other way, no default of a bench script points into docs/
for what it writes. Checked on the scripts' code (running them takes minutes to hours each): the
path of every write (open for writing, an atomic write, savefig, a specimen's save, a rename or a
copy, replace_block) is followed through the names assigned to it in its function, and through
the module's constants and functions, to a "docs" in the code."""
import ast
import glob
import os

from conftest import REPO

SCRIPTS = sorted(glob.glob(os.path.join(REPO, "bench", "*.py")))
# calls that write the file their argument names (open: with a writing mode)
WRITERS = {"atomic_open", "write_json", "write_csv", "savefig", "save", "savez", "replace", "copy", "copyfile",
           "makedirs", "replace_block", "publish", "rename"}


def _name(call):
    f = call.func
    return f.attr if isinstance(f, ast.Attribute) else f.id if isinstance(f, ast.Name) else None


def _writes(call):
    """The path arguments of a call that writes, or []."""
    name = _name(call)
    if name == "open":
        mode = call.args[1] if len(call.args) > 1 else next((k.value for k in call.keywords if k.arg == "mode"), None)
        if isinstance(mode, ast.Constant) and isinstance(mode.value, str) and set(mode.value) & set("wax"):
            return call.args[:1]
        return []
    if name in ("replace", "rename", "copy", "copyfile"):
        return call.args[1:2]
    if name in WRITERS:
        return call.args[:1]
    return []


def _mentions_docs(node):
    return any(isinstance(n, ast.Constant) and isinstance(n.value, str) and
               (n.value == "docs" or n.value.startswith("docs/")) for n in ast.walk(node))


def _docs_names(tree):
    """Module-level names (constants, functions) whose value reaches a "docs" path, transitively."""
    defs = {}
    for node in tree.body:
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    defs[target.id] = node.value
        elif isinstance(node, ast.FunctionDef):
            defs[node.name] = node
    found, grown = set(), True
    while grown:
        grown = False
        for name, node in defs.items():
            if name in found:
                continue
            if _mentions_docs(node) and not isinstance(node, ast.FunctionDef) or \
                    isinstance(node, ast.FunctionDef) and _returns_docs(node, found):
                found.add(name)
                grown = True
    return found


def _returns_docs(function, names):
    """A function whose return value reaches a "docs" path (its returns followed through its names)."""
    for node in ast.walk(function):
        if isinstance(node, ast.Return) and node.value is not None and \
                _reaches_docs(node.value, _assignments(function), names, set()):
            return True
    return False


def _assignments(function):
    out = {}
    for node in ast.walk(function):
        if isinstance(node, ast.Assign):
            for target in node.targets:
                if isinstance(target, ast.Name):
                    out.setdefault(target.id, []).append(node.value)
        elif isinstance(node, ast.With):
            for item in node.items:
                if isinstance(item.optional_vars, ast.Name):
                    out.setdefault(item.optional_vars.id, []).append(item.context_expr)
    return out


def _reaches_docs(expr, local, names, seen):
    if _mentions_docs(expr):
        return True
    for node in ast.walk(expr):
        if isinstance(node, ast.Name):
            if node.id in names:
                return True
            if node.id in local and node.id not in seen:
                seen.add(node.id)
                if any(_reaches_docs(v, local, names, seen) for v in local[node.id]):
                    return True
    return False


def _functions(tree):
    return [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)]


def _doc_option_defaults(tree, names):
    """dest of every option whose default reaches docs/ (``--data`` -> ``data``)."""
    dests = set()
    for call in (n for n in ast.walk(tree) if isinstance(n, ast.Call) and _name(n) == "add_argument"):
        default = next((k.value for k in call.keywords if k.arg == "default"), None)
        if default is not None and _reaches_docs(default, {}, names, set()):
            flag = next(a.value for a in call.args if isinstance(a, ast.Constant) and a.value.startswith("--"))
            dests.add(flag[2:].replace("-", "_"))
    return dests


def problems(path):
    with open(path) as f:
        tree = ast.parse(f.read())
    names = _docs_names(tree)
    from_docs = _doc_option_defaults(tree, names)
    found = []
    for function in _functions(tree):
        local = _assignments(function)
        params = {a.arg for a in function.args.args}
        for call in (n for n in ast.walk(function) if isinstance(n, ast.Call)):
            for arg in _writes(call):
                where = "%s line %d (%s)" % (os.path.basename(path), call.lineno, ast.unparse(call)[:80])
                if _reaches_docs(arg, local, names, set()):
                    found.append("%s writes under docs/ by default" % where)
                used = {n.attr for n in ast.walk(arg) if isinstance(n, ast.Attribute)}
                for name, values in local.items():  # options reached through local names
                    if any(isinstance(n, ast.Name) and n.id == name for n in ast.walk(arg)):
                        used |= {n.attr for v in values for n in ast.walk(v) if isinstance(n, ast.Attribute)}
                if used & from_docs:
                    found.append("%s writes to --%s, whose default is under docs/" % (where, sorted(used & from_docs)[0]))
                if _name(call) in ("replace_block", "publish"):
                    text = ast.unparse(arg)
                    if text != "o.doc" and not (isinstance(arg, ast.Name) and arg.id in params):
                        found.append("%s replaces a block of %s, not of --doc" % (where, text))
    # a function that hands its parameter to replace_block is called with --doc only
    for function in _functions(tree):
        blocks = [c for c in ast.walk(function) if isinstance(c, ast.Call) and _name(c) in ("replace_block", "publish")
                  and c.args and isinstance(c.args[0], ast.Name)]
        params = [a.arg for a in function.args.args]
        for block in blocks:
            if block.args[0].id not in params:
                continue
            k = params.index(block.args[0].id)
            for call in (n for n in ast.walk(tree) if isinstance(n, ast.Call) and _name(n) == function.name):
                given = call.args[k] if k < len(call.args) else None
                if given is None or ast.unparse(given) != "o.doc":
                    found.append("%s line %d: %s(...) replaces a block of %s, not of --doc"
                                 % (os.path.basename(path), call.lineno, function.name,
                                    ast.unparse(given) if given is not None else "?"))
    return found


def test_benchmarks_write_into_docs_only_when_asked():
    assert len(SCRIPTS) >= 10
    found = [p for path in SCRIPTS for p in problems(path)]
    assert not found, "\n".join(found)


def test_the_check_finds_a_default_under_docs(tmp_path):
    """The check itself: a script that appends its rows to docs/data by default, or rewrites a page
    it was not given, is found."""
    script = tmp_path / "bench_x.py"
    script.write_text('import os\nDATA = os.path.join("root", "docs", "data")\n\n\n'
                      'def data_path(n):\n    return os.path.join(DATA, "x-%d.csv" % n)\n\n\n'
                      'def run(o):\n    out = o.csv or data_path(o.n)\n    with open(out, "w") as f:\n'
                      '        f.write("")\n\n\n'
                      'def main(p, o):\n    p.add_argument("--json", default="docs/data/x.json")\n'
                      '    with open(o.json, "a") as f:\n        f.write("")\n'
                      '    _bench.replace_block("docs/benchmarks.md", "x", "")\n')
    found = problems(str(script))
    assert len(found) == 4, found
    assert any("--json" in p for p in found) and any("not of --doc" in p for p in found)
