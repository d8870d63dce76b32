"""Steps to reach a state: the servo's path rate and feed-forward against the default, on Table C1 states.

    /usr/bin/python3 bench/bench_state_speed.py --specimen S.npz [--ids 1,5,21] \
        [--rates 2,inf] [--feed-forward off,on] [--doc docs/studies/state-speed.md] [--csv docs/data/state-speed-N.csv]

Every state is reached from the specimen itself (not along its path, so that each pair compares
the two ways from the same start), once per way: each path rate (Pa per step; inf: the goal jumps
to the state at once and the servo relaxes onto it, its strain rate capped by the inertial number
as always) with each feed-forward setting of the servo (off: proportional control alone; on: the
ramp fed forward through the measured tangent stiffness, docs/triaxial.md), rates outer; the
first way is the reference. At each reached state: Zm, void ratio, and E_i, nu_ij of the exact
static solve (rotations free; noise-free, so a difference is the state's, not a probe's). The
table gives, per state, the steps and wall time of each way and the differences of the others
from the first: |dZm|, |de|, max |dE_i/E_i|, max |dnu_ij|, beside the default probe's own error
(6.0e-4 in E, 1.1e-4 in nu against the static solve; docs/speed-vs-error.md).
"""
import csv
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)  # _bench.py: yade-double does not put the script's folder on the path
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

PROBE_ERROR_E, PROBE_ERROR_NU = 6.0e-4, 1.1e-4  # docs/speed-vs-error.md, default probe, 1000-16,000 spheres


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz)")
    p.add_argument("--ids", default="", help="Table C1 states by number (default: all 39)")
    p.add_argument("--rates", default="2,inf", help="path rates to compare (Pa per step; inf: at once), the first is the reference")
    p.add_argument("--feed-forward", default="off",
                   help="servo feed-forward settings to compare at each rate: off, on, or off,on (the first is the reference)")
    p.add_argument("--doc", help="Markdown file whose table between <!-- state-speed:begin/end --> is replaced")
    p.add_argument("--block", default="state-speed", help="name of the Markdown block to replace (default: state-speed)")
    p.add_argument("--csv", help="CSV of every state and rate")
    o = cli.parse(p)
    try:
        o.rates = [float(r) for r in o.rates.split(",")]
    except ValueError:
        cli.fail("--rates: comma-separated numbers or inf")
    o.feed_forward = o.feed_forward.split(",")
    if any(f not in ("off", "on") for f in o.feed_forward) or len(set(o.feed_forward)) != len(o.feed_forward):
        cli.fail("--feed-forward: off, on, or both separated by a comma")
    if any(not r > 0 for r in o.rates):
        cli.fail("--rates: each rate must be > 0")
    o.ways = [(r, f == "on") for r in o.rates for f in o.feed_forward]
    if len(o.ways) < 2:
        cli.fail("compare at least two ways: two --rates, or --feed-forward off,on")
    return o


def way_name(way):
    return "%g%s" % (way[0], " ff" if way[1] else "")


def measure(path, b, sz, way):
    from trueaniso import fabric, specimen, specimen_file, statics, triaxial
    scene, _ = specimen_file.load(path)
    info = triaxial.reach_state(scene, b, sz, path_rate=way[0], feed_forward=way[1])
    st = specimen.state(scene)
    res = statics.static_stiffness(scene, rotations=True)
    nu = res["nu"]
    return dict(steps=info["steps"], wall=info["wall_time"], waited=info["waited_steps"],
                overshoot=max(info["overshoot"]), Zm=fabric.fabric(scene)["Zm"], e=st["void_ratio"],
                E=list(res["E"]), nu=[nu[i][j] for i in range(3) for j in range(3) if i != j])


def main():
    o = options()
    from trueaniso import study
    states = study.table_states(study.parse_ids(o.ids)) if o.ids else study.table_states()
    rows, table = [], []
    for sid, b, sz in states:
        res = [measure(o.specimen, b, sz, w) for w in o.ways]
        ref = res[0]
        for way, r in zip(o.ways, res):
            rows.append(dict(state=sid, b=b, sigma_z=sz, rate=way[0], feed_forward=int(way[1]), steps=r["steps"],
                             waited=r["waited"], overshoot=r["overshoot"], wall=r["wall"], Zm=r["Zm"], e=r["e"],
                             E_x=r["E"][0], E_y=r["E"][1], E_z=r["E"][2]))
        for way, r in zip(o.ways[1:], res[1:]):
            dE = max(abs(a / c - 1) for a, c in zip(r["E"], ref["E"]))
            dnu = max(abs(a - c) for a, c in zip(r["nu"], ref["nu"]))
            table.append((sid, b, sz, ref["steps"], ref["wall"], way_name(way), r["steps"], r["wall"],
                          abs(r["Zm"] - ref["Zm"]), dE, dnu, abs(r["e"] - ref["e"])))
        for t in table[-(len(o.ways) - 1):]:
            print("state %s: %d steps %.1f s -> %s: %d steps %.1f s; |dZm| %.4f, |de| %.1e, max|dE/E| %.1e, max|dnu| %.1e"
                  % (sid, t[3], t[4], t[5], t[6], t[7], t[8], t[11], t[9], t[10]), flush=True)
    from trueaniso import atomic, specimen_file
    _, meta = specimen_file.read(o.specimen)
    if o.csv:
        with atomic.atomic_open(o.csv) as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0]))
            w.writeheader()
            w.writerows(rows)
    from trueaniso import specimen_file as sf
    n = sf.load(o.specimen)[0].num_bodies
    lines = ["Specimen %s (%d particles), 1 thread, %s; each state from the specimen, moduli from the static solve."
             % (os.path.basename(o.specimen), n, time.strftime("%Y-%m-%d")), "",
             "| state | b | sigma_z (kPa) | steps (%s) | s | way | steps | s | abs dZm | abs de | max abs dE/E | max abs dnu |"
             % way_name(o.ways[0]), "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for t in table:
        lines.append("| %s | %.2f | %.0f | %d | %.1f | %s | %d | %.1f | %.4f | %.1e | %.1e | %.1e |"
                     % (t[0], t[1], t[2] / 1e3, t[3], t[4], t[5], t[6], t[7], t[8], t[11], t[9], t[10]))
    lines.append("")
    for way in o.ways[1:]:  # one summary line per other way
        fast = [t for t in table if t[5] == way_name(way)]
        steps0, steps1 = sum(t[3] for t in fast), sum(t[6] for t in fast)
        within = sum(1 for t in fast if t[9] <= PROBE_ERROR_E and t[10] <= PROBE_ERROR_NU)
        lines.append("Way %s against %s: total steps %d -> %d (%.2fx fewer); %d of %d states within the default probe's own "
                     "error (%.1e in E, %.1e in nu); max abs dE/E %.1e; max abs dnu %.1e; max abs dZm %.4f; max abs de %.1e."
                     % (way_name(way), way_name(o.ways[0]), steps0, steps1, steps0 / max(steps1, 1), within, len(fast),
                        PROBE_ERROR_E, PROBE_ERROR_NU, max(t[9] for t in fast), max(t[10] for t in fast),
                        max(t[8] for t in fast), max(t[11] for t in fast)))
    _bench.publish(o.doc, o.block, lines, heading=None if o.doc and os.path.exists(o.doc) else "# Steps to reach a state")


if __name__ == "__main__":  # also under yade-double -x; an import runs nothing
    cli.guarded(main)
