"""The layout of the Python code: no import cycle inside the trueaniso package, and its subpackage
trueaniso.analysis imports the package as a package, never by editing sys.path. Read from the source
with ast: nothing is imported or run."""
import ast
import os

import pytest

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
PACKAGE = os.path.join(REPO, "pyscripts", "trueaniso")
ANALYSIS = os.path.join(PACKAGE, "analysis")


def imports_within(package_dir, package_name="trueaniso"):
    """{module: set of modules of the same package it imports}, at any depth of the module (an
    import inside a function closes a cycle as well, only later). The package's __init__ is the
    node "__init__"; an import of the package itself (`from . import engines`, an attribute of
    __init__) is no edge: a submodule is never imported without its package."""
    modules = {f[:-3] for f in os.listdir(package_dir) if f.endswith(".py")}
    graph = {}
    for name in sorted(modules):
        with open(os.path.join(package_dir, name + ".py")) as f:
            tree = ast.parse(f.read(), filename=name + ".py")
        edges = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                if node.level == 1:
                    base = node.module
                elif node.level == 0 and node.module and node.module.split(".")[0] == package_name:
                    base = node.module.partition(".")[2] or None
                else:
                    continue
                if base:
                    edges.add(base.split(".")[0])
                else:  # from . import a, b: the names that are modules
                    edges.update(a.name for a in node.names)
            elif isinstance(node, ast.Import):
                for a in node.names:
                    parts = a.name.split(".")
                    if parts[0] == package_name and len(parts) > 1:
                        edges.add(parts[1])
        graph[name] = {m for m in edges if m in modules and m != name and m != "__init__"}
    return graph


def cycles(graph):
    """The strongly connected components of more than one module (Tarjan): each is a cycle."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_cycle_finder_finds_a_cycle_through_a_lazy_import(tmp_path):
    """The finder itself, on a package made here: a -> b at the top, b -> a inside a function
    (the shape a bridge and its clump half had), c -> a outside the cycle."""
    (tmp_path / "__init__.py").write_text("")
    (tmp_path / "a.py").write_text("from . import b\n")
    (tmp_path / "b.py").write_text("def f():\n    from .a import g\n    return g\n")
    (tmp_path / "c.py").write_text("import trueaniso.a\nfrom trueaniso import engines\n")
    graph = imports_within(str(tmp_path))
    assert graph == {"__init__": set(), "a": {"b"}, "b": {"a"}, "c": {"a"}}
    assert cycles(graph) == [["a", "b"]]
    assert cycles({"a": {"b"}, "b": {"c"}, "c": set()}) == []


def test_no_import_cycle_in_the_package():
    graph = imports_within(PACKAGE)
    assert "yade_convert" in graph and graph["yade_clumps"] and graph["yade_bridge"]  # the graph was read
    assert cycles(graph) == [], "import cycles inside trueaniso: %s" % cycles(graph)


def sys_path_uses(path):
    """Lines of `path` that read or change sys.path, outside a PEP 366 guard (`if __package__ ...`:
    a module run as a file puts the repository root on the path and names its package)."""
    with open(path) as f:
        tree = ast.parse(f.read(), filename=path)
    guarded = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and any(isinstance(n, ast.Name) and n.id == "__package__"
                                            for n in ast.walk(node.test)):
            guarded.update(id(n) for n in ast.walk(node))
    return sorted({node.lineno for node in ast.walk(tree)
                   if isinstance(node, ast.Attribute) and node.attr == "path" and id(node) not in guarded
                   and isinstance(node.value, ast.Name) and node.value.id == "sys"})


def test_sys_path_finder(tmp_path):
    p = tmp_path / "m.py"
    p.write_text("import sys\nimport os\nx = os.path.join('a')\nsys.path.insert(0, x)\n"
                 "if __package__ in (None, ''):\n    sys.path.insert(0, x)\n")
    assert sys_path_uses(str(p)) == [4]


@pytest.mark.parametrize("name", sorted(f for f in os.listdir(ANALYSIS) if f.endswith(".py")))
def test_analysis_modules_leave_sys_path_alone(name):
    """trueaniso.analysis is part of the package: nothing in it puts anything on the path."""
    assert sys_path_uses(os.path.join(ANALYSIS, name)) == []


def pyflakes_findings(paths):
    """pyflakes' warnings on the Python files under `paths`, as 'file:line: message', but for a line
    that says '# noqa' (an import kept for its side effect or as a re-export, said where it stands).
    pyflakes itself reads no noqa comments."""
    api = pytest.importorskip("pyflakes.api", reason="pyflakes (Debian: python3-pyflakes) is not installed")
    from pyflakes import reporter as _reporter

    found = []

    class Collect(_reporter.Reporter):
        def __init__(self):
            super().__init__(None, None)

        def unexpectedError(self, filename, msg):
            found.append("%s: %s" % (filename, msg))

        def syntaxError(self, filename, msg, lineno, offset, text):
            found.append("%s:%s: %s" % (filename, lineno, msg))

        def flake(self, message):
            with open(message.filename) as f:
                line = f.read().splitlines()[message.lineno - 1]
            if "# noqa" not in line:
                found.append("%s:%d: %s" % (os.path.relpath(message.filename, REPO), message.lineno,
                                            message.message % message.message_args))
    api.checkRecursive(paths, Collect())
    return found


def test_pyflakes_finds_nothing_unmarked():
    """No unused import or variable, no undefined name in pyscripts/, bench/ and tests/."""
    assert pyflakes_findings([os.path.join(REPO, d) for d in ("pyscripts", "bench", "tests")]) == []


def test_pyflakes_check_sees_an_unused_import(tmp_path):
    (tmp_path / "a.py").write_text("import os\nimport sys  # noqa: F401 (kept)\n")
    assert [f.split(": ", 1)[1] for f in pyflakes_findings([str(tmp_path)])] == ["'os' imported but unused"]
