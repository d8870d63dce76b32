"""What this machine can run: cores, memory, and the cost of a specimen of N spheres.

The per-sphere costs are measured (docs/specimens.md, "Files" and "Preparation cost"), not derived.
The memory costs are upper bounds with a margin, so that a refusal is never wrong by a factor; the
time is a central estimate, printed before long work so that a user can stop it.
"""
import os

from .refusal import InputError

THREADS_PER_CORE = 4  # more threads than this only slow the contact loops (measured)

# Measured on 1,000-16,000 spheres (peak RSS of the preparation above the interpreter's, with the
# contact list of the dense state): 1.7 kB per sphere; 2.5 kB leaves a margin.
PREPARATION_BYTES_PER_SPHERE = 2500
# The interpreter with numpy and the module loaded (peak RSS, measured): python3 37 MB,
# yade-double 252 MB (YADE loads its own libraries and plugins). With a margin each; one figure for
# both would make every python3 estimate 2.7 times the measured peak (docs/specimens.md, "Files").
INTERPRETER_BYTES = {"python3": 60e6, "yade": 300e6}
# The exact static solve (statics.static_stiffness, run by run_study.py on its specimen):
# 7.6 GB at 53,004 spheres (docs/statics.md) = 143 kB per sphere; 160 kB with a margin.
STATICS_BYTES_PER_SPHERE = 160e3
# Preparation time: the random placement, then the recipe's steps, each costing about the same per
# member sphere at every size. Measured with prepare_specimen.py --threads 1, seed 1, x86-64-v3, on
# the 2-core machine beside two jobs at nice 19 (docs/studies/specimens.md, "Preparation cost"):
# placement 1.2-1.6 ms a sphere; 300 spheres 138,000 steps in 8.6 s, 1000 142,000 in 27.2 s, 4000
# 186,000 in 160 s: 0.19-0.21 us a sphere and step; 300 clump1 (1500 members) 154,500 in 37.4 s,
# 0.16 us. These estimate 1.24, 1.31 and 0.89 times those spheres' times and 1.9 times the clumps'.
# A step of 64,000 spheres costs about 1.25 times a step of 4000 (docs/benchmarks.md), so the
# paper's size takes somewhat longer than said.
PLACEMENT_SECONDS_PER_SPHERE = 1.5e-3
STEP_SECONDS_PER_SPHERE = 0.2e-6
# Steps of each recipe. Spheres' hardly grow with N: 138,000 at 300, 186,000 at 4000 and 180,000 at
# 53,004; 170,000 is taken. clump1's rotation-free expansion creeps longer in a larger packing:
# 154,500 at 300 clumps, 210,000 at 2000, 230,000 at 4000 (taken), 276,500 at 16,000. clump2 215,500
# at 4000 (docs/studies/specimens.md, "Preparation cost"; docs/studies/paper-size.md, "Size series").
PREPARATION_STEPS = {"sphere": 1.7e5, "clump1": 2.3e5, "clump2": 2.2e5}
MEMORY_SHARE = 0.8  # what a run may plan to use of the machine's memory (the rest: OS, other users)


def cores():
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def openmp_threads_env():
    """OMP_NUM_THREADS as OpenMP reads it for the outer team (the first item of a list), or None
    when unset: the count `--threads 0` takes."""
    text = os.environ.get("OMP_NUM_THREADS", "").split(",")[0].strip()
    return text or None


def max_threads():
    return THREADS_PER_CORE * cores()


def check_threads(threads, option="--threads"):
    """0 (all cores) or 1..4 x cores; beyond, OpenMP only slows down and at ~1e5 threads crashes."""
    if threads < 0 or threads > max_threads():
        raise InputError("%s %d: give 0 (OpenMP's count: OMP_NUM_THREADS, else all %d cores) or at most %d (%d x the cores; more threads only slow "
                         "the contact loops down)" % (option, threads, cores(), max_threads(), THREADS_PER_CORE))
    return threads


def use_threads(threads):
    """The run's thread count for the engines (OpenMP) and for numpy's BLAS alike: --threads N
    holds a run to N cores. Left to itself, OpenBLAS starts a thread per core at its first call and
    keeps it spinning between calls: a study on one engine thread then took 1.4-2 times its wall
    time in CPU (150 and 1000 spheres; 0.99 at 4000, whose steps outlast the spin), a second core
    taken from whatever ran beside it. The static solves' last bits follow BLAS's thread count (300
    spheres: nu_free 1 unit in the last place, the residual 0.1 %; the same on every repeat of a
    count: tests/py/test_run_cost.py), so holding it to --threads, which a study's fingerprint
    records, also makes them repeat wherever the study does. 0 leaves both to their own counts (all
    cores)."""
    from . import engines
    engines.set_threads(threads)
    if threads:
        import threadpoolctl
        threadpoolctl.threadpool_limits(limits=threads, user_api="blas")


def memory_limit():
    """(bytes, where the limit comes from): the cgroup's memory.max when set, else MemTotal."""
    limits = []
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemTotal:"):
                    limits.append((int(line.split()[1]) * 1024, "MemTotal in /proc/meminfo"))
    except OSError:  # pragma: no cover - not Linux
        pass
    for path in ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"):
        try:
            with open(path) as f:
                text = f.read().strip()
        except OSError:
            continue
        if text.isdigit() and int(text) < 2 ** 60:
            limits.append((int(text), "the cgroup limit in %s" % path))
    return min(limits) if limits else (float("inf"), "unknown")


def human_bytes(b):
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6)):
        if b >= size:
            return "%.1f %s" % (b / size, unit)
    return "%.0f kB" % (b / 1e3)


def human_seconds(s):
    if s >= 2 * 86400:
        return "%.0f days" % (s / 86400)
    if s >= 2 * 3600:
        return "%.0f h" % (s / 3600)
    if s >= 120:
        return "%.0f min" % (s / 60)
    return "%.0f s" % s


def interpreter_bytes():
    """INTERPRETER_BYTES of the interpreter running now: yade-double when YADE is loaded."""
    import sys
    return INTERPRETER_BYTES["yade" if "yade" in sys.modules else "python3"]


def preparation_estimate(n, threads, assembly="sphere"):
    """(bytes, seconds) to prepare a specimen of n member spheres of an assembly (sphere, clump1,
    clump2): memory and a step's cost go with the member spheres."""
    memory = interpreter_bytes() + PREPARATION_BYTES_PER_SPHERE * n
    seconds = n * (PLACEMENT_SECONDS_PER_SPHERE
                   + PREPARATION_STEPS[assembly] * STEP_SECONDS_PER_SPHERE / max(1, threads))
    return memory, seconds


# The largest clump count whose preparation's step count was measured, and what is known above it.
# clump1's count grows: 16,000 clumps took 1.2 times the steps of 4000 (docs/studies/paper-size.md,
# "Size series"). clump2's did not, up to 16,000 clumps (136,500 steps against 154,500 at 4000), but
# at 69,532 its free expansion crept: 334,000 steps in all (paper-size.md, "Where the clump
# preparations wait").
CLUMP_STEPS_MEASURED_UP_TO = {"clump1": 16000, "clump2": 16000}
_BEYOND = {"clump1": " at least (the step count of 4000 clumps; 16,000 took 1.2 times it, larger clump1 specimens "
                     "take more steps: docs/studies/paper-size.md)",
           "clump2": " at least (the step count of 4000 clumps; 16,000 took 0.88 of it, but 69,532 took 1.5 times it, "
                     "its expansion creeping: docs/studies/paper-size.md)"}


def preparation_caveat(assembly, clumps):
    """Words after a preparation's time estimate beyond the clump counts measured, else ''."""
    if assembly == "sphere" or clumps <= CLUMP_STEPS_MEASURED_UP_TO[assembly]:
        return ""
    return _BEYOND[assembly]


def check_memory(need, what):
    """Refuse work whose estimated memory exceeds MEMORY_SHARE of the machine's limit."""
    limit, source = memory_limit()
    if need > MEMORY_SHARE * limit:
        raise InputError("%s needs about %s of memory; this machine allows %s (%s), of which a run may plan "
                         "%.0f %%" % (what, human_bytes(need), human_bytes(limit), source, 100 * MEMORY_SHARE))
    return need
