"""The Python API's examples: every function and class a user calls (the ``__all__`` of each module
of trueaniso.PUBLIC_MODULES, exceptions aside) has an example in its docstring, and every example
gives what it says. doctest runs them as the manual shows them, from the repository's root (they
read the committed 150-sphere specimen tests/data/spheres-150-s4.npz); those of the YADE modules
run inside yade-double. Printed numbers are rounded to 3-4 digits, so an x86-64-v3 build, whose
last bits differ, prints the same."""
import doctest
import importlib
import inspect
import os
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "pyscripts"))
import trueaniso  # noqa: E402

YADE_MODULES = ("yade_bridge", "yade_adapter")
# Examples of more than a few seconds of a core: run by ./test.sh --long (the report writes its
# dozen figures: about 9 s).
LONG_MODULES = ("analysis.report",)
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def user_objects(module_name):
    """(qualified name, object) of what the module's __all__ names, exceptions left out."""
    module = importlib.import_module("trueaniso." + module_name)
    found = []
    for name in getattr(module, "__all__", ()):
        obj = getattr(module, name)
        if inspect.isclass(obj) and issubclass(obj, BaseException):
            continue
        if inspect.isfunction(obj) or inspect.isclass(obj):
            found.append(("trueaniso.%s.%s" % (module_name, name), obj))
    return module, found


def modules_with_functions():
    """The public modules but the packages (trueaniso.analysis holds no function of its own)."""
    return [m for m in trueaniso.PUBLIC_MODULES
            if not os.path.isdir(os.path.join(REPO, "pyscripts", "trueaniso", *m.split(".")))]


def test_every_public_module_names_its_user_functions_and_each_has_an_example():
    missing, without = [], []
    for name in modules_with_functions():
        module, objects = user_objects(name)
        if not getattr(module, "__all__", None):
            missing.append(name)
        for qualified, obj in objects:
            if ">>>" not in (obj.__doc__ or ""):
                without.append(qualified)
    assert not missing, "public modules without __all__ (the functions a user calls): %s" % ", ".join(missing)
    assert not without, "user functions without an example (>>> in the docstring): %s" % ", ".join(without)


def run_examples(module_name):
    """doctest of the module's user objects, from the repository's root; returns the failures' report."""
    _, objects = user_objects(module_name)
    finder, runner = doctest.DocTestFinder(recurse=False), doctest.DocTestRunner(optionflags=FLAGS)
    report = []
    here = os.getcwd()
    os.chdir(REPO)
    try:
        for qualified, obj in objects:
            for test in finder.find(obj, qualified, globs={}):
                out = []
                result = runner.run(test, out=out.append)
                if result.failed:
                    report.append("".join(out))
    finally:
        os.chdir(here)
    return report, runner


@pytest.mark.parametrize("module_name", [pytest.param(m, marks=pytest.mark.long) if m in LONG_MODULES else m
                                         for m in modules_with_functions() if m not in YADE_MODULES])
def test_the_examples_give_what_they_say(module_name, monkeypatch):
    monkeypatch.setenv("OMP_NUM_THREADS", "1")
    report, runner = run_examples(module_name)
    assert not report, "\n".join(report)
    _, objects = user_objects(module_name)
    assert runner.tries >= len(objects), "an example ran no statement"


def test_the_yade_modules_examples_give_what_they_say_in_yade_double(tmp_path):
    script = tmp_path / "examples.py"
    script.write_text("import sys; sys.path[:0] = [%r, %r]\n"
                      "import test_api_examples as t\n"
                      "failed = [r for m in t.YADE_MODULES for r in t.run_examples(m)[0]]\n"
                      "print('\\n'.join(failed) if failed else 'ALL-EXAMPLES-PASSED')\n"
                      % (HERE, os.path.join(REPO, "pyscripts")))
    done = subprocess.run(["yade-double", "-n", "-x", str(script)], cwd=REPO, capture_output=True,
                          text=True, timeout=600, env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert "ALL-EXAMPLES-PASSED" in done.stdout, done.stdout[-5000:] + done.stderr[-3000:]
