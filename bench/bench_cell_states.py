"""The isotropic state and the 39 states of Table C1 reached in the fully deformable cell: every
principal stress against its goal and every off-diagonal stress against zero.

    /usr/bin/python3 bench/bench_cell_states.py --specimen specimens/spheres-1000-s1.npz
    /usr/bin/python3 bench/bench_cell_states.py --specimen S.npz --control three --csv docs/data/cell-states-N-three.csv
    /usr/bin/python3 bench/bench_cell_states.py --doc docs/studies/cell.md     (tables only)

Each loading path starts from the specimen and reaches its states in order, each from the one
before it, as run_states.py does; the isotropic state (b = 0, sigma_z = 100 kPa) is reached from
the specimen. --control six holds the shear stresses at zero (the full cell); --control three
holds the cell's shear strains (an orthorhombic servo), for the steps and the shear
stress it leaves. One row per state is appended to --csv as it comes (by default
results/bench/cell-states-N-CONTROL.csv; the file is rewritten from the start by each run): the
measurements the manual's tables are made of, docs/data/cell-states-*.csv, change only when the
run is told to write there. With --doc, the tables between <!-- cell-states:begin --> and
<!-- cell-states:end --> of that file are rebuilt from every cell-states-*.csv of --data
(docs/data by default).
"""
import csv
import glob
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

ROOT = os.path.dirname(HERE)
DATA = os.path.join(ROOT, "docs", "data")  # read by --doc; written only when --csv names a file there
RESULTS = os.path.join(ROOT, "results", "bench")
COLUMNS = ["n", "control", "state", "b", "sigma_z_goal", "goal_1", "goal_2", "goal_3", "sigma_x", "sigma_y",
           "sigma_z", "sigma_1", "sigma_2", "sigma_3", "sigma_yz", "sigma_xz", "sigma_xy", "principal_error",
           "tau_max", "unbalanced", "steps", "wall_time", "start"]
TOLERANCE = 500.0  # Pa: a state's acceptance, 0.5 kPa


def csv_path(n, control):
    """Where a run writes its rows unless --csv says: results/bench/, never the manual's data."""
    return os.path.join(RESULTS, "cell-states-%d-%s.csv" % (n, control))


def run(o):
    import numpy as np
    from trueaniso import engines, specimen_file, triaxial
    engines.set_threads(o.threads)
    base, meta = specimen_file.load(o.specimen)
    n = base.num_bodies
    states = [("iso", 0.0, 100e3)] + list(triaxial.table_c1_states())
    groups = triaxial.paths(states)
    out = o.csv or csv_path(n, o.control)
    os.makedirs(os.path.dirname(out), exist_ok=True)
    t_all = time.time()
    with open(out, "w", newline="") as f:
        w = csv.DictWriter(f, COLUMNS)
        w.writeheader()
        for key in sorted(groups, key=lambda k: (k[1] != 0, k)):
            scene, start = base.copy(), "specimen"
            for sid, b, sz in groups[key]:
                info = triaxial.reach_state(scene, b, sz, control_shear=o.control == "six", chunk=2000)
                goal = np.sort(engines.true_triaxial_stresses(b, sz))[::-1]
                sig = engines.stress(scene)
                row = dict(n=n, control=o.control, state=sid, b=b, sigma_z_goal=sz, goal_1=goal[0], goal_2=goal[1],
                           goal_3=goal[2], sigma_x=sig[0, 0], sigma_y=sig[1, 1], sigma_z=sig[2, 2],
                           sigma_1=info["sigma_1"], sigma_2=info["sigma_2"], sigma_3=info["sigma_3"],
                           sigma_yz=info["sigma_yz"], sigma_xz=info["sigma_xz"], sigma_xy=info["sigma_xy"],
                           principal_error=float(np.abs(np.array([info["sigma_1"], info["sigma_2"], info["sigma_3"]])
                                                        - goal).max()),
                           tau_max=info["tau_max"], unbalanced=info["unbalanced"], steps=info["steps"],
                           wall_time=round(info["wall_time"], 2), start=start)
                w.writerow(row)
                f.flush()
                print("N %d %s state %s: principal error %.1f Pa, |shear| max %.1f Pa, %d steps, %.1f s"
                      % (n, o.control, sid, row["principal_error"], row["tau_max"], row["steps"], row["wall_time"]),
                      flush=True)
                start = str(sid)
    print("wrote %s (%.0f s; specimen %s, sha256 %s)" % (out, time.time() - t_all, o.specimen, meta["sha256"][:12]))


def _rows(data):
    out = {}
    for path in sorted(glob.glob(os.path.join(data, "cell-states-*.csv"))):
        with open(path) as f:
            rows = list(csv.DictReader(f))
        if rows:
            out[(int(rows[0]["n"]), rows[0]["control"])] = rows
    return out


def tables(directory=DATA):
    data = _rows(directory)
    if not data:
        raise cli.InputError("no %s yet: run with --specimen and --csv first"
                             % os.path.join(os.path.relpath(directory, ROOT), "cell-states-*.csv"))
    lines = ["Machine: %s; 1 engine thread; %s. Data: `docs/data/cell-states-N-CONTROL.csv`; "
             "run: `bench/bench_cell_states.py --specimen specimens/spheres-N-s1.npz [--control three] "
             "--csv docs/data/cell-states-N-CONTROL.csv` "
             "(reach_state defaults: stress tolerance 100 Pa, unbalanced force 1e-4, mu = 0.5). State 1 of Table C1 "
             "is the isotropic state; `iso` is the same goal reached from the specimen, state 1 from `iso`."
             % (_bench.machine(), time.strftime("%Y-%m-%d")), "",
             "| N | control | states | max principal error (Pa) | max off-diagonal (Pa) | all within 0.5 kPa | "
             "steps per state (median, max) | wall time (s) |", "|---|---|---|---|---|---|---|---|"]
    for (n, control), rows in sorted(data.items()):
        pe = max(float(r["principal_error"]) for r in rows)
        tau = max(float(r["tau_max"]) for r in rows)
        steps = sorted(int(r["steps"]) for r in rows)
        ok = all(float(r["principal_error"]) < TOLERANCE and float(r["tau_max"]) < TOLERANCE for r in rows)
        lines.append("| %d | %s | %d | %.1f | %.1f | %s | %d, %d | %.0f |"
                     % (n, control, len(rows), pe, tau, "yes" if ok else "**no**", steps[len(steps) // 2], steps[-1],
                        sum(float(r["wall_time"]) for r in rows)))
    six = sorted(k for k in data if k[1] == "six")
    if six:
        lines += ["", "Every state, six-component control: the largest principal error |sigma_k - goal_k| and the "
                      "largest |off-diagonal| (Pa), and the steps to reach it.", ""]
        head = "| state | b | sigma_z (kPa) |" + "".join(" N=%d principal | N=%d off-diag | N=%d steps |" % (n, n, n)
                                                        for n, _ in six)
        lines += [head, "|" + "---|" * (3 + 3 * len(six))]
        by_state = [{r["state"]: r for r in data[k]} for k in six]
        for r0 in data[six[0]]:
            sid = r0["state"]
            cells = "".join(" %.1f | %.1f | %s |" % (float(d[sid]["principal_error"]), float(d[sid]["tau_max"]),
                                                    d[sid]["steps"]) if sid in d else " | | |" for d in by_state)
            lines.append("| %s | %s | %.1f |%s" % (sid, r0["b"], float(r0["sigma_z_goal"]) / 1e3, cells))
    return "\n".join(lines)


def write_doc(path, data):
    _bench.replace_block(path, "cell-states", tables(data))
    print("updated %s" % path)


def main(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", help="specimen file (.npz) whose states are reached")
    p.add_argument("--control", choices=("six", "three"), default="six",
                   help="six: shear stresses held at zero (the full cell); three: shear strains held (orthorhombic)")
    p.add_argument("--threads", type=cli.count, default=1, help="engine threads (the tables use 1)")
    p.add_argument("--csv", help="CSV to write (default results/bench/cell-states-N-CONTROL.csv)")
    p.add_argument("--doc", help="markdown file whose cell-states block is rebuilt from --data")
    p.add_argument("--data", default=DATA, help="folder of the cell-states-*.csv the tables are made of")
    o = cli.parse(p, argv)
    if not o.specimen and not o.doc:
        raise cli.InputError("give --specimen (run the states) and/or --doc (rebuild the tables)")
    if o.specimen and not os.path.isfile(o.specimen):
        raise cli.InputError("specimen file not found: %s" % o.specimen)
    if o.threads < 1:
        raise cli.InputError("--threads must be >= 1")
    if o.doc and not os.path.isfile(o.doc):
        raise cli.InputError("--doc %s: no such file" % o.doc)
    if o.specimen:
        run(o)
    if o.doc:
        write_doc(o.doc, o.data)


if __name__ == "__main__":
    cli.guarded(main)
