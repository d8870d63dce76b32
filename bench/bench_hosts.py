"""The cost of one study on each host: run_states.py on our stepper and with --host yade (YADE's
loop with the plugin's classes in O.engines), the same specimen, states and probes, each in a new
results directory, one thread each (yade-double -j1, --threads 1). The hosts alternate within each
of --repeats rounds, so that a round's ratio compares them under the same load of a shared machine;
the medians over the rounds are reported, with the machine's load average before and after.

    /usr/bin/python3 bench/bench_hosts.py --specimen S.npz [--ids 1,21] [--repeats 3] [--doc docs/benchmarks.md]

Reports per host the wall time of the whole run, the steps and seconds of the states and of the
probes (probes.csv), and how far the two hosts' moduli and Zm are apart. Needs the plugin
(./setup.sh with the YADE source: build/yade-prefix).
"""
import csv
import os
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
REPO = os.path.dirname(HERE)
sys.path[:0] = [os.path.join(REPO, "pyscripts")]
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402
from trueaniso import cli  # noqa: E402

PREFIX = os.path.join(REPO, "build", "yade-prefix")


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz), spheres or clumps")
    p.add_argument("--ids", default="1,21", help="Table C1 states, as run_states.py --ids")
    p.add_argument("--repeats", type=int, default=3, help="rounds, each host once a round (alternating)")
    p.add_argument("--doc", default=None, help="Markdown file whose hosts table is replaced (docs/benchmarks.md)")
    o = cli.parse(p)
    if o.repeats < 1:
        cli.fail("--repeats must be >= 1, not %d" % o.repeats)
    if o.doc:
        _bench.writable_doc(o.doc)
    if not os.path.exists(os.path.join(PREFIX, "lib", "x86_64-linux-gnu", "yade-double", "libtrueanisoYade.so")):
        cli.fail("the YADE plugin is not installed in %s (./setup.sh with the YADE source builds it)" % PREFIX)
    return o


def run(host, o, out):
    script = os.path.join(REPO, "pyscripts", "run_states.py")
    args = ["--specimen", o.specimen, "--ids", o.ids, "--out", out, "--threads", "1"]
    env = dict(os.environ, OMP_NUM_THREADS="1")
    if host == "yade":
        cmd = ["yade-double", "-j1", "-n", "-x", script, "--host", "yade"] + args
        env["YADE_PREFIX"] = PREFIX
    else:
        cmd = ["/usr/bin/python3", script] + args
    t0 = time.time()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    wall = time.time() - t0
    if proc.returncode != 0:
        cli.fail("%s host failed:\n%s\n%s" % (host, proc.stdout[-2000:], proc.stderr[-2000:]))
    with open(os.path.join(out, "probes.csv")) as f:
        rows = list(csv.DictReader(f))
    states = {r["state"]: r for r in rows}
    return dict(wall=wall, rows=rows,
                state_steps=sum(int(r["state_steps"]) for r in states.values()),
                state_time=sum(float(r["state_wall_time"]) for r in states.values()),
                probe_steps=sum(int(r["probe_steps"]) for r in rows),
                probe_time=sum(float(r["probe_wall_time"]) for r in rows))


def main():
    o = options()
    from trueaniso import specimen_file
    try:
        arrays, _ = specimen_file.read(o.specimen)
    except specimen_file.SpecimenFileError as exc:
        cli.fail(str(exc))
    n = len(arrays["member_begin"]) - 1
    load_before = os.getloadavg()[0]
    rounds = []
    for k in range(o.repeats):
        with tempfile.TemporaryDirectory() as tmp:
            order = ("trueaniso", "yade") if k % 2 == 0 else ("yade", "trueaniso")
            rounds.append({h: run(h, o, os.path.join(tmp, h)) for h in order})
        print("round %d: ours %.1f s, yade %.1f s" % (k + 1, rounds[-1]["trueaniso"]["wall"], rounds[-1]["yade"]["wall"]),
              flush=True)
    load_after = os.getloadavg()[0]
    # the rows of the first round: the studies are deterministic, every round gives the same steps and moduli
    ours, yade = rounds[0]["trueaniso"], rounds[0]["yade"]
    key = {(r["state"], r["probe"]): r for r in ours["rows"]}
    dE = max(abs(float(r["E"]) / float(key[(r["state"], r["probe"])]["E"]) - 1) for r in yade["rows"])
    dZm = max(abs(float(r["Zm"]) - float(key[(r["state"], r["probe"])]["Zm"])) for r in yade["rows"])

    def median(values):
        v = sorted(values)
        return v[len(v) // 2] if len(v) % 2 else 0.5 * (v[len(v) // 2 - 1] + v[len(v) // 2])

    ratios = [r["yade"]["wall"] / r["trueaniso"]["wall"] for r in rounds]
    lines = ["Machine: %s, shared with other jobs (load average %.1f before, %.1f after). Specimen: %s%s, states "
             "%s of Table C1, probes z, x, y, one thread each (`--threads 1`, `yade-double -j1`), %d rounds, the "
             "hosts alternating within each, medians, %s." % (
                 _bench.machine(), load_before, load_after, os.path.basename(o.specimen),
                 " (%d particles)" % n if n else "", o.ids, o.repeats, time.strftime("%Y-%m-%d")),
             "",
             "| host | whole run (s) | states: steps | states (s) | probes: steps | probes (s) | s / step |",
             "|---|---|---|---|---|---|---|"]
    for name, h in (("trueaniso (our stepper)", "trueaniso"), ("yade (`--host yade`)", "yade")):
        r = rounds[0][h]
        steps = r["state_steps"] + r["probe_steps"]
        state_time = median([x[h]["state_time"] for x in rounds])
        probe_time = median([x[h]["probe_time"] for x in rounds])
        lines.append("| %s | %.1f | %d | %.1f | %d | %.1f | %.3g |" % (
            name, median([x[h]["wall"] for x in rounds]), r["state_steps"], state_time, r["probe_steps"], probe_time,
            (state_time + probe_time) / max(steps, 1)))
    lines += ["",
              "YADE's loop costs %.1f times our stepper's wall time for this study (the median of the rounds' ratios; "
              "%.1f-%.1f); its moduli are within %.2g (relative) of ours, its Zm within %.3g." % (
                  median(ratios), min(ratios), max(ratios), dE, dZm),
              "",
              "Reproduce: `/usr/bin/python3 bench/bench_hosts.py --specimen %s --ids %s --repeats %d --doc "
              "docs/benchmarks.md`" % (os.path.relpath(o.specimen, REPO) if o.specimen.startswith(REPO) else o.specimen,
                                       o.ids, o.repeats)]
    _bench.publish(o.doc, "hosts", lines, heading="## The study on each host")


if __name__ == "__main__":
    main()
