"""What a run costs the machine, recorded with its results: the wall and CPU seconds, the peak
memory of the process and the machine's load while it ran. A study adds it to its run's entry in
metadata.json; a preparation carries it through its checkpoints into the specimen's parameters.
The cost table of a study (analysis/cost.py) is then read from the data, not from a log kept by
hand.

CPU time is this process's and its children's that have ended (getrusage): a study's workers
started by mpiexec on other ranks are not counted, and the record says so. Peak memory is the
largest resident set of this process or of any such child (Linux reports kilobytes). The load is
the one-minute load average, sampled at the start, at each saved result and at the end: a run on
a machine shared with other jobs says how shared it was."""
import os
import resource
import time


def cpu_seconds():
    """User and system seconds of this process and of its children that have ended."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def peak_memory_mb():
    """The largest resident set (MB) this process or one of its ended children has had."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return max(own.ru_maxrss, kids.ru_maxrss) / 1024.0


def load_average():
    """The machine's one-minute load average (None where the system has none)."""
    try:
        return os.getloadavg()[0]
    except OSError:
        return None


class Meter:
    """The cost of a run from now, or of a piece of work that earlier runs began: `carried` is
    what those runs recorded (totals(), as a checkpoint holds them). With `cpu_from_process_start`
    the CPU time counts from the process's start, the work done before the meter (a preparation's
    random placement) included."""

    def __init__(self, carried=None, cpu_from_process_start=False):
        carried = dict(carried or {})
        self.wall0, self.cpu0 = time.monotonic(), 0.0 if cpu_from_process_start else cpu_seconds()
        self.wall_before = float(carried.get("wall_time", 0.0))
        self.cpu_before = float(carried.get("cpu_time", 0.0))
        self.peak_before = float(carried.get("peak_memory_mb", 0.0))
        self.runs_before = int(carried.get("runs", 0))
        self.load_min, self.load_max = carried.get("load_min"), carried.get("load_max")
        self.sample()

    def sample(self):
        """The machine's load now, into the run's range (its least and greatest)."""
        x = load_average()
        if x is not None:
            x = round(x, 2)
            self.load_min = x if self.load_min is None else min(self.load_min, x)
            self.load_max = x if self.load_max is None else max(self.load_max, x)

    def spent(self):
        """The cost so far, earlier runs included: wall and CPU seconds, peak memory (MB) and the
        load's range."""
        self.sample()
        return dict(wall_time=round(self.wall_before + time.monotonic() - self.wall0, 3),
                    cpu_time=round(self.cpu_before + cpu_seconds() - self.cpu0, 3),
                    peak_memory_mb=round(max(self.peak_before, peak_memory_mb()), 1),
                    load_min=self.load_min, load_max=self.load_max)

    def totals(self):
        """spent() and the number of runs it covers: what a checkpoint carries to the next run."""
        return dict(self.spent(), runs=self.runs_before + 1)

    def record(self, ended, workers_elsewhere=False):
        """This run's entry: spent() and how it ended ('complete', 'failed', 'interrupted',
        'error'); with `workers_elsewhere`, a note that the CPU time is this process's only."""
        r = dict(self.spent(), ended=ended)
        if workers_elsewhere:
            r["cpu_of"] = "this process only: its workers ran in processes of their own"
        return r
