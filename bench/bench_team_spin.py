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
import os
import re
import statistics
import subprocess
import sys
import tempfile

import _bench  # noqa: E402  (it makes trueaniso importable)
from trueaniso import cli  # noqa: E402

LIBGOMP_DEFAULT = "300000"
BUSY_LOOP = "while True:\n    pass\n"


def stepping_seconds(log):
    """The seconds the study's log says its states and probes stepped."""
    reached = re.findall(r"reached in \d+ steps \(([0-9.]+) s\)", log)
    probes = re.findall(r"probes done \(([0-9.]+) s\)", log)
    if not reached or not probes:
        cli.fail("the study's log names no state reached or no probes done:\n" + log[-2000:], 1)
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
        cli.fail("run_study.py failed (%d):\n%s" % (p.returncode, p.stderr[-2000:]), 1)
    return stepping_seconds(p.stdout + p.stderr)


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz) the study starts from")
    p.add_argument("--ids", default="1", help="Table C1 states (run_study.py --ids)")
    p.add_argument("--spins", default="libgomp,10000,3000,1000,0",
                   help="GOMP_SPINCOUNT values on two threads, comma separated; libgomp: libgomp's own count")
    p.add_argument("--busy", default="0,1", help="busy processes beside the study, comma separated: a row group each")
    p.add_argument("--rounds", type=int, default=3, help="rounds, the variants alternating in each")
    p.add_argument("--timeout", type=float, default=1800, help="seconds a study run may take")
    p.add_argument("--doc", help="Markdown file whose table is replaced")
    p.add_argument("--block", default="team-spin", help="name of the table's markers in --doc")
    o = cli.parse(p)
    o.spin_list = [s.strip() for s in o.spins.split(",") if s.strip()]
    if not o.spin_list or any(s != "libgomp" and not s.isdigit() for s in o.spin_list):
        cli.fail("--spins: counts (whole numbers) or libgomp, comma separated, not %r" % o.spins)
    try:
        o.busy_counts = [int(k) for k in o.busy.split(",")]
    except ValueError:
        cli.fail("--busy: whole numbers separated by commas, not %r" % o.busy)
    if o.rounds < 1 or min(o.busy_counts) < 0:
        cli.fail("--rounds must be >= 1 and --busy >= 0")
    if not os.path.exists(o.specimen):
        cli.fail("no specimen %s" % o.specimen)
    return o


def main():
    o = options()
    variants = [(1, "libgomp")] + [(2, s) for s in o.spin_list]
    rows = []
    for busy in o.busy_counts:
        loops = [subprocess.Popen([sys.executable, "-c", BUSY_LOOP], start_new_session=True) for _ in range(busy)]
        try:
            times = {v: [] for v in variants}
            for _ in range(o.rounds):
                for v in variants:
                    times[v].append(one_run(o.specimen, o.ids, v[0], v[1], o.timeout))
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
                                         o.ids, os.path.basename(o.specimen), o.rounds),
             "",
             "| busy | threads | GOMP_SPINCOUNT | stepping (s) | x one thread |",
             "|---|---|---|---|---|"] + rows + [
             "",
             "Reproduce: `/usr/bin/python3 bench/bench_team_spin.py --specimen %s --ids %s --spins %s --busy %s "
             "--rounds %d`" % (o.specimen, o.ids, o.spins, o.busy, o.rounds)]
    _bench.publish(o.doc, o.block, lines)


if __name__ == "__main__":
    main()
