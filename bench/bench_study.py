"""The whole study's clock: the default study end to end, and where its time goes.

    /usr/bin/python3 bench/bench_study.py --work DIR [--assembly sphere,clump1,clump2] [--n 4000]
        [--ids all] [--tree DIR --label NAME ...] [--doc docs/benchmarks.md]

Each tree (a built checkout, default this one; e.g. an older one to time before and after) runs
`run_study.py` with its own defaults, as `./main.sh` does: the specimen prepared, the states of
--ids (all 39 of Table C1 by default) reached and probed on z, x and y, the static solves and the
report, into a fresh results directory under --work, one engine thread unless --threads. The run is
timed in its own process, and the time split by what the code was doing, the outermost of these
counting where they nest:
  - stepping: the engine chains' steps (dem.Chain.run: contact detection, forces, the cell
    measures the controllers read, the integrator, the controllers);
  - measurement: the static solves, the fabric measures and the state records (statics,
    fabric, specimen.state, triaxial.stress_record);
  - report: the analysis (figures, the report, zeta);
  - I/O: specimen, checkpoint and results files read and written (specimen_file, atomic,
    results_csv);
  - Python: the rest (the studies' own bookkeeping, imports, the interpreter).
The steps come from the study's own records (the specimen's preparation, probes.csv). With --doc
the table between <!-- NAME:begin --> and <!-- NAME:end --> (--block) is replaced.
"""
import json
import os
import shlex
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

# Run in a fresh interpreter with the tree's packages first on the path; it wraps functions every
# tree has, so that it can time an older one.
WORKER = r"""
import json, os, runpy, sys, time
tree, script, out = sys.argv[1], sys.argv[2], sys.argv[3]
argv = json.loads(sys.argv[4])
sys.path[:0] = [tree + "/pyscripts", tree]
import importlib
clock = {"stepping": 0.0, "measurement": 0.0, "report": 0.0, "io": 0.0}
depth = [0]

def timed(module, name, key):
    try:
        mod = importlib.import_module(module)
    except ImportError:
        return
    owner, attr = (mod, name) if "." not in name else (getattr(mod, name.split(".")[0]), name.split(".")[1])
    f = getattr(owner, attr, None)
    if f is None:
        return
    def wrapper(*a, **k):
        if depth[0]:
            return f(*a, **k)
        depth[0] += 1
        t = time.perf_counter()
        try:
            return f(*a, **k)
        finally:
            clock[key] += time.perf_counter() - t
            depth[0] -= 1
    setattr(owner, attr, wrapper)

for module, name, key in [
        ("trueaniso.dem", "Chain.run", "stepping"),
        ("trueaniso.statics", "static_stiffness", "measurement"), ("trueaniso.statics", "cached_record", "measurement"),
        ("trueaniso.statics", "rotation_factor", "measurement"), ("trueaniso.atomic", "write_csv", "io"),
        ("trueaniso.fabric", "fabric", "measurement"), ("trueaniso.fabric", "fabric_row", "measurement"),
        ("trueaniso.specimen", "state", "measurement"), ("trueaniso.triaxial", "stress_record", "measurement"),
        ("trueaniso.analysis.report", "build", "report"), ("trueaniso.analysis.zeta_contrast", "fit", "report"),
        ("analysis.report", "build", "report"), ("analysis.zeta_contrast", "fit", "report"),  # older trees
        ("trueaniso.specimen_file", "save", "io"), ("trueaniso.specimen_file", "load", "io"),
        ("trueaniso.specimen_file", "read", "io"), ("trueaniso.atomic", "write_json", "io"),
        ("trueaniso.atomic", "write_text", "io"), ("trueaniso.results_csv", "append", "io"),
        ("trueaniso.results_csv", "read", "io")]:
    timed(module, name, key)
sys.argv = [script] + argv
t0 = time.perf_counter()
code = 0
try:
    runpy.run_path(script, run_name="__main__")
except SystemExit as exc:
    code = exc.code or 0
clock["total"] = time.perf_counter() - t0
clock["cpu"] = time.process_time()  # the process's CPU seconds: what other jobs on the machine disturb least
clock["code"] = code
print("BENCH " + json.dumps(clock), flush=True)
"""


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--work", required=True, help="folder for the studies (each run in a fresh folder)")
    p.add_argument("--assembly", default="sphere,clump1,clump2", help="assemblies, comma separated")
    p.add_argument("--n", type=int, default=4000, help="particles of each specimen")
    p.add_argument("--ids", default="all", help="Table C1 states (all: the 39; default: run_study.py's own, as ./main.sh runs)")
    p.add_argument("--seed", type=int, default=1, help="seed of the specimens")
    p.add_argument("--threads", type=int, default=1, help="engine threads")
    p.add_argument("--tree", action="append", default=None, help="a built source tree (default: this one); again for another")
    p.add_argument("--label", action="append", default=None, help="the name of each --tree in the table")
    p.add_argument("--doc", help="Markdown file whose table is replaced")
    p.add_argument("--block", default="study-clock", help="name of the table's markers in --doc")
    o = cli.parse(p)
    o.trees = [os.path.abspath(t) for t in (o.tree or [os.path.dirname(_bench._PYSCRIPTS)])]
    o.labels = o.label or [os.path.basename(t) for t in o.trees]
    if len(o.labels) != len(o.trees):
        cli.fail("--label: one for each --tree")
    for t in o.trees:
        if not os.path.isfile(os.path.join(t, "pyscripts", "run_study.py")):
            cli.fail("--tree %s: no pyscripts/run_study.py in it" % t)
    o.assemblies = [a.strip() for a in o.assembly.split(",") if a.strip()]
    if o.ids == "default":
        o.ids = None
    elif o.ids == "all":
        from trueaniso import triaxial
        o.ids = ",".join(str(i) for i, _, _ in triaxial.table_c1_states())
    os.makedirs(o.work, exist_ok=True)
    if o.doc:
        _bench.writable_doc(o.doc)
    return o


def run(o, tree, label, assembly):
    """One study, timed: the clock split, and its steps."""
    out = os.path.join(o.work, "%s-%s-%d" % (label, assembly, o.n))
    if os.path.exists(out):
        import shutil
        shutil.rmtree(out)
    argv = ["--assembly", assembly, "--n", str(o.n), "--seed", str(o.seed), "--threads", str(o.threads), "--out", out]
    if o.ids:
        argv += ["--ids", o.ids]
    env = dict(os.environ, OMP_NUM_THREADS=str(o.threads), TRUEANISO_BUILD=os.path.join(tree, "build"),
               MPLBACKEND="Agg")
    cmd = ["/usr/bin/python3", "-c", WORKER, tree, os.path.join(tree, "pyscripts", "run_study.py"), out, json.dumps(argv)]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    with open(os.path.join(o.work, "%s-%s-%d.log" % (label, assembly, o.n)), "w") as f:  # what the study said
        f.write(proc.stdout + proc.stderr)
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("BENCH ")]
    if not line or json.loads(line[-1][6:])["code"] != 0:
        cli.fail("study failed (%s, %s):\n%s\n%s" % (label, assembly, proc.stdout[-1500:], proc.stderr[-1500:]), 1)
    clock = json.loads(line[-1][6:])
    with open(os.path.join(out, "specimen.json")) as f:
        p = json.load(f)["parameters"]
    clock["prep_steps"] = int(p.get("steps_expansion", 0) + p.get("steps_consolidation", 0))
    from trueaniso import results_csv
    rows = results_csv.read(os.path.join(out, "probes.csv")).rows
    states = {r["state"]: int(float(r["state_steps"])) for r in rows}
    clock["state_steps"] = sum(states.values())
    clock["probe_steps"] = sum(int(float(r["probe_steps"])) for r in rows)
    with open(os.path.join(out, "metadata.json")) as f:  # the states' rule (none recorded: smallest-inertia)
        clock["time_step"] = (json.load(f).get("fingerprint", {}).get("state") or {}).get("time_step", "smallest-inertia")
    level = subprocess.run(["/usr/bin/python3", "-c", "import sys; sys.path.insert(0, %r); from trueaniso import engines; "
                            "print(engines.build_arch())" % os.path.join(tree, "pyscripts")],
                           capture_output=True, text=True, env=env).stdout.strip()
    clock["level"] = level
    return clock


def main():
    o = options()
    results = {}
    for assembly in o.assemblies:
        for tree, label in zip(o.trees, o.labels):
            c = run(o, tree, label, assembly)
            results[(assembly, label)] = c
            print("%s, %s: %.0f s, %.0f CPU s (stepping %.0f, measurement %.0f, report %.0f, I/O %.0f)"
                  % (assembly, label, c["total"], c["cpu"], c["stepping"], c["measurement"], c["report"], c["io"]),
                  flush=True)
    rows = []
    for assembly in o.assemblies:
        first = results[(assembly, o.labels[0])]
        for label in o.labels:
            c = results[(assembly, label)]
            python = c["total"] - c["stepping"] - c["measurement"] - c["report"] - c["io"]
            rows.append("| %s | %s | %s, %s | %d + %d + %d | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %.0f | %s |" % (
                assembly, label, c["level"], c["time_step"], c["prep_steps"], c["state_steps"], c["probe_steps"],
                c["total"], c["cpu"], c["stepping"], c["measurement"], c["report"], c["io"], python,
                "1" if label == o.labels[0] else "%.2f (CPU %.2f)" % (first["total"] / c["total"], first["cpu"] / c["cpu"])))
    load = os.getloadavg()
    text = ("Machine: %s; load average %.1f at the end; %d particles, seed %d, %d engine thread(s), states %s, each "
            "study in its own process, one at a time, %s. Steps: preparation + states + probes. Seconds of wall time.\n\n"
            "| assembly | code | level, time step | steps | total (s) | CPU (s) | stepping | measurement | report | I/O | "
            "Python | speed-up |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n%s\n\nReproduce: `/usr/bin/python3 "
            "bench/bench_study.py %s`" % (
                _bench.machine(), load[1], o.n, o.seed, o.threads, "run_study.py's default" if not o.ids else "all 39" if len(o.ids.split(",")) == 39 else o.ids,
                time.strftime("%Y-%m-%d"), "\n".join(rows), shlex.join(sys.argv[1:])))
    print(text)
    if o.doc:
        _bench.replace_block(o.doc, o.block, text)


if __name__ == "__main__":
    cli.guarded(main)
