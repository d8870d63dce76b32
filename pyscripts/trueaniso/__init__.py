"""trueaniso: DEM study of anisotropic elasticity of granular materials under true triaxial stress.

The physics lives in the C++ engines (module ``_trueaniso``, built by CMake into ``build/python``);
this package composes them: specimens, protocols, the YADE bridge, file formats.
"""
import os
import sys

if sys.argv[:1] == ["-m"]:  # Python is locating a module of this package to run it as a tool
    from . import start_guard as _start_guard
    _start_guard.install()  # cli.guarded takes over when the tool's work starts

# The modules a user's script calls, in the order of a study: the manual's Python API lists them
# first, each with the functions of its __all__, every one of them with an example that
# tests/py/test_api_examples.py runs. The other modules serve the scripts and these; the manual
# lists them after, as internal.
PUBLIC_MODULES = ("specimen", "clump_specimen", "specimen_file", "options", "triaxial", "fabric", "statics", "zeta",
                  "study", "dem", "psd", "validate", "yade_bridge", "yade_adapter",
                  "analysis", "analysis.results", "analysis.hyperelastic", "analysis.chain", "analysis.report",
                  "analysis.figures")

_HERE = os.path.dirname(os.path.abspath(__file__))
REPO_ROOT = os.path.dirname(os.path.dirname(_HERE))


# How long a thread of the engines' OpenMP team spins at a barrier before it sleeps, in libgomp's
# turns (about 100 a microsecond). libgomp's own default, 300,000, is right for a team alone on its
# cores; beside another busy process the waiting thread spins away the time slice its partner
# needs: state 1 of 4000 spheres and its probes stepped 58 s on two threads against 2.0 s on one.
# At 10,000 the same took 5.5 s, and alone on the cores the study stepped as fast as at libgomp's
# count (docs/studies/benchmarks.md, "Two threads"). libgomp reads the setting when it loads, with
# the engines; a user's GOMP_SPINCOUNT or OMP_WAIT_POLICY is kept.
TEAM_SPIN_COUNT = "10000"


def _shorten_team_spin():
    if "GOMP_SPINCOUNT" not in os.environ and "OMP_WAIT_POLICY" not in os.environ:
        os.environ["GOMP_SPINCOUNT"] = TEAM_SPIN_COUNT


def _find_extension():
    """Locate the compiled module: $TRUEANISO_BUILD/python, else <repo>/build/python."""
    candidates = []
    if os.environ.get("TRUEANISO_BUILD"):
        candidates.append(os.path.join(os.environ["TRUEANISO_BUILD"], "python"))
    candidates.append(os.path.join(REPO_ROOT, "build", "python"))
    # Insert in reverse so the first candidate ($TRUEANISO_BUILD) ends up first on sys.path.
    for path in reversed(candidates):
        if os.path.isdir(path):
            if path in sys.path:
                sys.path.remove(path)
            sys.path.insert(0, path)
    # numpy first, from Python: the module's C initialisation imports it too, and an exception
    # there (Ctrl-C while numpy loads) crashed the interpreter (SIGSEGV) instead of raising.
    import numpy  # noqa: F401
    import importlib.util
    from . import buildarch
    found = importlib.util.find_spec("_trueaniso")
    if found is not None and found.origin:
        # The build's module for this processor (buildarch.choose): first on the path, so that the
        # import below takes it.
        chosen = buildarch.choose(os.path.dirname(found.origin), buildarch.cpu_flags(),
                                  os.environ.get(buildarch.LEVEL_ENV))
        if chosen != os.path.dirname(found.origin):
            sys.path.insert(0, chosen)
            found = importlib.util.find_spec("_trueaniso")
        buildarch.refuse_unsupported(os.path.dirname(found.origin))
    _shorten_team_spin()
    try:
        import _trueaniso  # noqa: F401
    except ImportError as exc:  # pragma: no cover - message for users, tested by hand
        raise ImportError(
            "trueaniso: the compiled module _trueaniso was not found in %s; build it first "
            "(./main.sh or ./test.sh do, or: cmake -S . -B build && cmake --build build), or set "
            "TRUEANISO_BUILD to a build directory that has it" % candidates
        ) from exc
    if found is not None and found.origin:
        buildarch.refuse_mismatch(os.path.dirname(found.origin), _trueaniso)
    return _trueaniso


def __getattr__(name):
    """`engines` (the compiled module) is loaded on first use, not with the package: reading and
    analysing results (trueaniso.results_csv, trueaniso.analysis) needs none of it, and on a machine without
    the build those tools run, rather than end in a 20-line ImportError traceback."""
    if name == "engines":
        global engines
        engines = _find_extension()
        return engines
    raise AttributeError("module 'trueaniso' has no attribute %r" % name)


# The version of trueaniso: one home, the file VERSION beside this one, which CMake reads for the
# engines (engines.version()) and a study records in metadata.json (versions.trueaniso).
with open(os.path.join(_HERE, "VERSION")) as _f:
    __version__ = _f.read().strip()
del _f
FORMAT_VERSION = 4  # specimen files; 2: the checksum covers the metadata; 3: the full cell matrix; 4: the bodies' volumes (docs/specimens.md)
