"""How long the engines' OpenMP team spins at a barrier (libgomp's GOMP_SPINCOUNT; the package's
default trueaniso.TEAM_SPIN_COUNT) against the study's stepping time, alone on the cores and beside
busy processes: each run is `run_study.py --specimen S --ids IDS --threads T` in its own process,
with GOMP_SPINCOUNT set to each count ("libgomp": unset, with OMP_WAIT_POLICY=passive unset too
and the count libgomp's own, 300,000, forced), the variants alternating within a round; its time
is what the study's log says it stepped (each state's "reached in ... (X s)" and "probes done
(X s)"). --busy K starts K processes that spin on their own for the whole benchmark, each in a
session of its own, as a job started from another terminal is (Linux schedules each session as a
group: a busy loop in the benchmark's own session takes its time slices from the study's threads
instead).

    /usr/bin/python3 bench/bench_team_spin.py --specimen S.npz --busy 0,1 --doc docs/studies/benchmarks.md
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile

import _bench

LIBGOMP_DEFAULT = "300000"
BUSY_LOOP = "while True:\n    pass\n"


def stepping_seconds(log):
    """The seconds the study's log says its states and probes stepped."""
    reached = re.findall(r"reached in \d+ steps \(([0-9.]+) s\)", log)
    probes = re.findall(r"probes done \(([0-9.]+) s\)", log)
    if not reached or not probes:
        raise RuntimeError("the study's log names no state reached or no probes done:\n" + log[-2000:])
    return sum(map(float, reached + probes))


def one_run(specimen, ids, threads, spin, timeout):
    env = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    env["GOMP_SPINCOUNT"] = LIBGOMP_DEFAULT if spin == "libgomp" else spin
    script = os.path.join(os.path.dirname(_bench._PYSCRIPTS), "pyscripts", "run_study.py")
    with tempfile.TemporaryDirectory() as out:
        p = subprocess.run([sys.executable, script, "--specimen", specimen, "--ids", ids, "--threads", str(threads),
                            "--out", os.path.join(out, "study")], env=env, capture_output=True, text=True,
                           timeout=timeout)
    if p.returncode != 0:
        raise RuntimeError("run_study.py failed (%d):\n%s" % (p.returncode, p.stderr[-2000:]))
    return stepping_seconds(p.stdout + p.stderr)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--specimen", required=True)
    ap.add_argument("--ids", default="1", help="Table C1 states (run_study.py --ids)")
    ap.add_argument("--spins", default="libgomp,10000,3000,1000,0",
                    help="GOMP_SPINCOUNT values on two threads; libgomp: libgomp's own count")
    ap.add_argument("--busy", default="0,1", help="busy processes beside, one table row group each")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--timeout", type=float, default=1800)
    ap.add_argument("--doc")
    ap.add_argument("--block", default="team-spin")
    a = ap.parse_args(argv)
    spins = [s.strip() for s in a.spins.split(",") if s.strip()]
    for s in spins:
        if s != "libgomp" and not s.isdigit():
            ap.error("--spins: %r is neither libgomp nor a count" % s)
    busy_counts = [int(k) for k in a.busy.split(",")]
    if a.rounds < 1 or min(busy_counts) < 0:
        ap.error("--rounds >= 1 and --busy >= 0")
    if not os.path.exists(a.specimen):
        ap.error("no specimen %s" % a.specimen)
    variants = [(1, "libgomp")] + [(2, s) for s in spins]
    rows = []
    for busy in busy_counts:
        loops = [subprocess.Popen([sys.executable, "-c", BUSY_LOOP], start_new_session=True) for _ in range(busy)]
        try:
            times = {v: [] for v in variants}
            for _ in range(a.rounds):
                for v in variants:
                    times[v].append(one_run(a.specimen, a.ids, v[0], v[1], a.timeout))
        finally:
            for p in loops:
                p.kill()
                p.wait()
        base = statistics.median(times[(1, "libgomp")])
        for v in variants:
            t = times[v]
            label = "one thread" if v[0] == 1 else ("libgomp's own (%s)" % LIBGOMP_DEFAULT if v[1] == "libgomp" else v[1])
            rows.append("| %d | %d | %s | %.1f (%.1f-%.1f) | %.2f |" % (busy, v[0], label, statistics.median(t),
                                                                     min(t), max(t), statistics.median(t) / base))
    lines = ["Machine: %s; %s. State(s) %s of %s; the seconds the study stepped (its states and probes, its "
             "own timers), median and range of %d rounds, the variants alternating; busy: processes that "
             "spin beside the study, each in a session of its own." % (_bench.machine(), __import__("datetime").date.today().isoformat(),
                                         a.ids, os.path.basename(a.specimen), a.rounds),
             "",
             "| busy | threads | GOMP_SPINCOUNT | stepping (s) | x one thread |",
             "|---|---|---|---|---|"] + rows + [
             "",
             "Reproduce: `/usr/bin/python3 bench/bench_team_spin.py --specimen %s --ids %s --spins %s --busy %s "
             "--rounds %d`" % (a.specimen, a.ids, a.spins, a.busy, a.rounds)]
    _bench.publish(a.doc, a.block, lines)


if __name__ == "__main__":
    main()
