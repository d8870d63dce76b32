"""The x86-64 level a build of the engines was compiled for (CMake's TRUEANISO_ARCH), checked
against the processor before the module is loaded.

A build for x86-64-v3 steps faster than the portable baseline (by how much: docs/benchmarks.md)
and dies of an illegal instruction on a processor without AVX2 and FMA, with no word of why: on a
cluster whose nodes differ, a module built on one node can be loaded on another. CMake writes the
level to `_trueaniso.arch` beside the module; `refuse_unsupported` reads it and compares with the
processor's flags (/proc/cpuinfo) before the import. The flag sets are GCC's definitions of the
levels (the x86-64 psABI), in the kernel's names.
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
