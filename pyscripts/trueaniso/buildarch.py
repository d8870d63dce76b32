"""The x86-64 level of the engines' module: which build to load for this processor, checked before
the module is loaded.

A default build (CMake's TRUEANISO_ARCH empty) makes two modules, the portable baseline's and one
whose hot loops are built for x86-64-v3, faster (by how much: docs/benchmarks.md), in the folder
LEVELS_DIR beside the first; `choose` picks the fastest one the processor runs, or the level that
TRUEANISO_LEVEL names (TRUEANISO_LEVEL=x86-64: the baseline, whose bits every x86-64 processor
reproduces; docs/runs.md, "Across machines"). A module for a level the processor lacks would die of
an illegal instruction with no word of why (on a cluster whose nodes differ, a build made on one
node is loaded on another): CMake writes each module's level to `_trueaniso.arch` beside it, and
`refuse_unsupported` compares it with the processor's flags (/proc/cpuinfo) before the import. The
flag sets are GCC's definitions of the levels (the x86-64 psABI), in the kernel's names.
"""
import os

BASELINE = "x86-64"
LEVEL_FLAGS = {
    "x86-64-v2": ("cx16", "lahf_lm", "popcnt", "pni", "sse4_1", "sse4_2", "ssse3"),
}
LEVEL_FLAGS["x86-64-v3"] = LEVEL_FLAGS["x86-64-v2"] + (
    "avx", "avx2", "bmi1", "bmi2", "f16c", "fma", "abm", "movbe", "xsave")
LEVEL_FLAGS["x86-64-v4"] = LEVEL_FLAGS["x86-64-v3"] + (
    "avx512f", "avx512bw", "avx512cd", "avx512dq", "avx512vl")

ARCH_FILE = "_trueaniso.arch"
# Beside the baseline module of a default build: one folder per other level, each with a module of
# the same name and interface (engines/python/CMakeLists.txt).
LEVELS_DIR = "_trueaniso_levels"
# Names the level to load (one the build has and the processor runs), instead of the fastest.
LEVEL_ENV = "TRUEANISO_LEVEL"
FASTEST_FIRST = ("x86-64-v4", "x86-64-v3", "x86-64-v2", BASELINE)


def cpu_flags(cpuinfo="/proc/cpuinfo"):
    """The processor's feature flags (the first 'flags' line), or None where they cannot be read
    (not Linux): then nothing is refused."""
    try:
        with open(cpuinfo) as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return None


def missing_features(level, flags):
    """The flags of `level` that the processor lacks (sorted), [] for the baseline or unknown flags."""
    if flags is None or level == BASELINE:
        return []
    return sorted(f for f in LEVEL_FLAGS.get(level, ()) if f not in flags)


def module_level(directory):
    """The level written beside the module in `directory`; the baseline when there is no file (a
    build from before the option)."""
    try:
        with open(os.path.join(directory, ARCH_FILE)) as f:
            return f.read().strip() or BASELINE
    except OSError:
        return BASELINE


def setup_command(level):
    """The command of a checkout that builds the engines for `level` (README, setup.sh)."""
    return "TRUEANISO_ARCH=%s ./setup.sh" % ("" if level == BASELINE else level)


def how_to_run_at(level, directory):
    """How to run at `level` with the build whose module is in `directory`: TRUEANISO_LEVEL where the
    build has that level and this processor runs it, else the command of a build for it."""
    try:
        found = levels_beside(first_folder(directory))
    except (ImportError, OSError):
        found = {}
    if level in found and not missing_features(level, cpu_flags()):
        return "%s=%s before the command (this build has it)" % (LEVEL_ENV, level)
    return "a build for %s (%s, README)" % (level, setup_command(level))


REBUILD = ("rebuild it here for the portable baseline (in a checkout: %s; with CMake: -DTRUEANISO_ARCH= and "
           "build again)" % setup_command(BASELINE))


def refuse_unsupported(directory, flags=None):
    """ImportError, before the module is loaded, when it was compiled for a level this processor
    lacks, or for one this code does not know (a file from elsewhere)."""
    level = module_level(directory)
    if level == BASELINE:  # every x86-64 processor runs it: no need to read the flags
        return
    if level not in LEVEL_FLAGS:
        raise ImportError("trueaniso: %s says the compiled module beside it was built for %r, not a level this "
                          "code knows (%s); %s" % (os.path.join(directory, ARCH_FILE), level,
                                                   ", ".join([BASELINE] + sorted(LEVEL_FLAGS)), REBUILD))
    missing = missing_features(level, cpu_flags() if flags is None else flags)
    if missing:
        raise ImportError("trueaniso: the compiled module in %s was built for %s (TRUEANISO_ARCH), and this "
                          "processor lacks %s; %s" % (directory, level, " ".join(missing), REBUILD))


def refuse_mismatch(directory, module):
    """ImportError when the loaded module's own level differs from the file beside it: the file is
    what the check above trusts, so a stale one must not pass unnoticed."""
    said, built = module_level(directory), getattr(module, "build_arch", lambda: BASELINE)()
    if said != built:
        raise ImportError("trueaniso: the compiled module in %s was built for %s, but %s beside it says %s; "
                          "build it again (./setup.sh, or cmake --build) so that they agree"
                          % (directory, built, ARCH_FILE, said))


def first_folder(directory):
    """The folder of a build's first module, given the folder of any of its modules."""
    parent = os.path.dirname(os.path.abspath(directory))
    return os.path.dirname(parent) if os.path.basename(parent) == LEVELS_DIR else directory


def levels_beside(directory):
    """{level: folder} of the modules a build has: the one in `directory` and those in its LEVELS_DIR."""
    found = {module_level(directory): directory}
    extra = os.path.join(directory, LEVELS_DIR)
    for name in sorted(os.listdir(extra)) if os.path.isdir(extra) else ():
        folder = os.path.join(extra, name)
        if any(f.startswith("_trueaniso") and f.endswith(".so") for f in os.listdir(folder)):
            found[module_level(folder)] = folder
    return found


def choose(directory, flags=None, asked=None):
    """The folder of the module to load, of the modules `directory` and its LEVELS_DIR hold: the
    level `asked` (TRUEANISO_LEVEL; ImportError when the build has none of it or the processor
    lacks it), else the fastest whose features the processor has. Where the processor's flags
    cannot be read (flags None) only the baseline is chosen unasked: no level is guessed."""
    found = levels_beside(directory)
    if asked:
        asked = asked.strip().lower()
        if asked not in found:
            raise ImportError("trueaniso: %s=%s, but this build has %s (in %s); give one of those, or leave %s unset "
                              "for the fastest the processor runs" % (LEVEL_ENV, asked, ", ".join(sorted(found)),
                                                                      directory, LEVEL_ENV))
        missing = missing_features(asked, flags)
        if missing:
            raise ImportError("trueaniso: %s=%s, and this processor lacks %s; give %s=%s (or leave it unset)"
                              % (LEVEL_ENV, asked, " ".join(missing), LEVEL_ENV, BASELINE))
        return found[asked]
    for level in FASTEST_FIRST:
        if level in found and (level == BASELINE or (flags is not None and not missing_features(level, flags))):
            return found[level]
    return directory  # a single-level build: refuse_unsupported says whether it runs here
