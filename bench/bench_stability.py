"""Stability of the time step: the energy drift of an undamped packing in a held cell against dt.

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/bench_stability.py \
        --specimen spheres=S.npz --specimen clump1=C1.npz [--factors 0.5,1,1.5] [--steps 100000] \
        [--csv docs/data/stability.csv] [--figure docs/figures/time-step-stability.png] [--doc docs/studies/time-step.md]

Each specimen is taken as it is (contact history included), its cell held (no strain rate), the
damping off and the friction made unreachable (the probe's 1e23: nothing slides, nothing dissipates),
and every body given a random velocity and spin (fixed seed, no net momentum) whose kinetic energy
is --kinetic times the packing's elastic energy. It is then stepped at the fixed time step
dt = f x per_axis_bound (TimeStepper, the bound of the specimen as loaded) for each factor f, and
the total mechanical energy (measure/Energy.hpp: kinetic + Hertz normal + tangential spring) read
every --every steps from the first reading after the first step (that step increments the
tangential springs by the given velocities for a motion the positions never made). The drift is the
mean energy of the last tenth of the readings minus that of the first tenth, over the initial
kinetic energy; the wobble is the standard deviation of the readings over the same. An unstable step grows the energy exponentially: the run stops when the
energy has risen by 100 times the initial kinetic energy (or the integrator refuses the step as
above the two-body limit of a contact) and the row says at which step. The energies are read after
a step, the kinetic at the half step and the elastic at the step (leapfrog), which adds a wobble of
O(omega dt) but no drift. With --damping the integrator's local damping is on: the energy then only
falls, and the run says whether the step blows up under the damping every study runs with.
"""
import csv
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

BLOW_UP = 100.0        # energy rise, in initial kinetic energies, taken as unstable


def options():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", action="append", default=[], help="LABEL=PATH of a specimen (.npz), repeatable")
    p.add_argument("--json", help="write the runs (bounds and rows) to this JSON file")
    p.add_argument("--merge", action="append", default=[],
                   help="JSON of earlier runs (--json) to show with these, repeatable (no --specimen: only those)")
    p.add_argument("--factors", default="0.3,0.5,0.7,0.9,1.0,1.1,1.2,1.3,1.4,1.5,1.7",
                   help="time steps as multiples of the per-axis bound, comma separated")
    p.add_argument("--steps", type=cli.at_least(1), default=100000, help="steps per run")
    p.add_argument("--every", type=cli.at_least(1), default=100, help="steps between energy readings")
    p.add_argument("--kinetic", type=cli.positive, default=1e-4,
                   help="initial kinetic energy as a fraction of the packing's elastic energy")
    p.add_argument("--seed", type=int, default=1, help="seed of the random velocities")
    p.add_argument("--damping", type=cli.finite, default=0.0,
                   help="local damping of the integrator (0: the energy measurement; > 0: only whether it blows up)")
    p.add_argument("--csv", help="CSV of every run")
    p.add_argument("--figure", help="PNG of drift against f, old and new steps marked")
    p.add_argument("--doc", help="Markdown file whose table between <!-- stability:begin/end --> is replaced")
    p.add_argument("--block", default="stability", help="name of the Markdown block to replace")
    p.add_argument("--safety", type=cli.positive, default=None,
                   help="the chosen factor of the per-axis bound, marked in the figure and the table")
    o = cli.parse(p)
    if not o.specimen and not o.merge:
        cli.fail("give --specimen or --merge")
    o.specimens = []
    for item in o.specimen:
        if "=" not in item:
            cli.fail("--specimen takes LABEL=PATH, not %r" % item)
        label, path = item.split("=", 1)
        if not os.path.isfile(path):
            cli.fail("--specimen %s: no such file" % path)
        o.specimens.append((label, path))
    try:
        o.factors = [float(f) for f in o.factors.split(",")]
    except ValueError:
        cli.fail("--factors: comma-separated numbers")
    if any(not f > 0 for f in o.factors):
        cli.fail("--factors: each factor must be > 0")
    if o.doc:
        _bench.writable_doc(o.doc)
    o.threads = os.environ.get("OMP_NUM_THREADS", "all")
    return o


def held_specimen(path):
    """The specimen with its cell held, no sliding, forces evaluated."""
    import numpy as np
    from trueaniso import dem, engines, specimen_file
    s, _ = specimen_file.load(path)
    s.velocity_gradient = np.zeros((3, 3))
    s.friction = engines.PROBE_FRICTION  # nothing slides
    s.block_rotations = False
    dem.refresh(s)
    return s


def shaken(scene, fraction, seed):
    """Random velocities and spins (no net momentum) carrying `fraction` of the elastic energy."""
    import numpy as np
    from trueaniso import engines
    rng = np.random.default_rng(seed)
    n = scene.num_bodies
    m = np.array(scene.masses)
    v = rng.standard_normal((n, 3))
    v -= (m[:, None] * v).sum(axis=0) / m.sum()
    scene.velocities = v
    # Spins of the same order as v / r (r: the body's largest member radius).
    radii, begin = np.array(scene.radii), np.array(scene.member_begin)
    rmax = np.maximum.reduceat(radii, begin[:-1])
    scene.angular_velocities = rng.standard_normal((n, 3)) / rmax[:, None]
    e = engines.mechanical_energy(scene)
    elastic = e["normal"] + e["tangential"] + e["rolling"]
    scale = math.sqrt(fraction * elastic / (e["translational"] + e["rotational"]))
    scene.velocities = np.array(scene.velocities) * scale
    scene.angular_velocities = np.array(scene.angular_velocities) * scale
    return engines.mechanical_energy(scene)


def run(base, factor, bound, o):
    """One run at dt = factor x bound; a dict of the row."""
    import numpy as np
    from trueaniso import dem, engines
    s = base.copy()
    e0 = shaken(s, o.kinetic, o.seed)
    k0 = e0["translational"] + e0["rotational"]
    s.dt = factor * bound
    chain = dem.Chain(s, damping=o.damping, max_dt=s.dt)
    chain.timestep.dead = True
    # The first step increments the tangential springs by the given velocities times dt for a motion
    # that the positions, evaluated at rest, never made: a one-off jump of O(F_s v dt). The readings
    # start after it; the blow-up (far above that jump) is measured from the start.
    energy = []
    status, stopped = "stable", None
    t = time.perf_counter()
    done = 0
    while done < o.steps:
        try:
            chain.run(min(o.every, o.steps - done))
        except Exception as exc:  # the integrator refuses a step above a contact's two-body limit
            if "unstable time step refused" not in str(exc):
                raise
            status, stopped = "refused", done
            break
        done = min(done + o.every, o.steps)
        e = engines.mechanical_energy(s)["total"]
        energy.append(e)
        if not math.isfinite(e) or e - e0["total"] > BLOW_UP * k0:
            status, stopped = "unstable", done
            break
    wall = time.perf_counter() - t
    row = dict(f=factor, dt=s.dt, status=status, stopped_at=stopped, steps=done, wall=wall)
    if status == "stable":
        e = np.array(energy)
        tenth = max(1, len(e) // 10)
        row["drift"] = (e[-tenth:].mean() - e[:tenth].mean()) / k0
        row["wobble"] = e.std() / k0
    return row


def describe(label, path, s, bound, old):
    from trueaniso import engines
    z = engines.coordination(s)
    return dict(label=label, path=path, bodies=s.num_bodies, members=s.num_members, contacts=z["Nc"],
                per_axis=bound, old=old, pair=engines.TimeStepper.critical_pair_step(s))


def table(specs, rows, o):
    head = ("| dt / per-axis bound | " + " | ".join("%s drift (wobble)" % sp["label"] for sp in specs) + " |")
    lines = [head, "|" + "---|" * (len(specs) + 1)]
    for f in o.factors:
        cells = []
        for sp in specs:
            r = next((r for r in rows if r["label"] == sp["label"] and r["f"] == f), None)
            if r is None:
                cells.append("-")
            elif r["status"] == "stable":
                cells.append("%+.1e (%.1e)" % (r["drift"], r["wobble"]))
            else:
                cells.append("%s at step %d" % (r["status"], r["stopped_at"]))
        mark = ""
        if o.safety is not None and abs(f - o.safety) < 1e-12:
            mark = " (chosen)"
        lines.append("| %.2f%s | %s |" % (f, mark, " | ".join(cells)))
    lines.append("")
    lines.append("| assembly | bodies (members) | contacts | per-axis bound (s) | old bound / per-axis | "
                 "old default 0.5 x old, as f | two-body limit / per-axis |")
    lines.append("|---|---|---|---|---|---|---|")
    for sp in specs:
        lines.append("| %s | %d (%d) | %d | %.4g | %.3f | %.3f | %.2f |" % (
            sp["label"], sp["bodies"], sp["members"], sp["contacts"], sp["per_axis"], sp["old"] / sp["per_axis"],
            0.5 * sp["old"] / sp["per_axis"], sp["pair"] / sp["per_axis"]))
    lines.append("")
    lines.append("%d steps a run, energy read every %d steps, initial kinetic energy %.0e of the elastic; "
                 "machine: %s, %s OpenMP thread(s), shared with other jobs." % (
                     o.steps, o.every, o.kinetic, _bench.machine(), o.threads))
    return "\n".join(lines)


def figure(path, specs, rows, o):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    top = 1e3
    for k, sp in enumerate(specs):
        color = "C%d" % k
        mine = [r for r in rows if r["label"] == sp["label"]]
        ok = [r for r in mine if r["status"] == "stable"]
        ax.semilogy([r["f"] for r in ok], [max(abs(r["drift"]), 1e-12) for r in ok], "o-", color=color,
                    label="%s |drift|" % sp["label"])
        ax.semilogy([r["f"] for r in ok], [r["wobble"] for r in ok], ":", color=color, alpha=0.6)
        bad = [r for r in mine if r["status"] != "stable"]
        ax.semilogy([r["f"] for r in bad], [top * 0.4 ** k] * len(bad), "x", color=color, markersize=9)
        ax.axvline(0.5 * sp["old"] / sp["per_axis"], color=color, linestyle="--", linewidth=1)
    if o.safety is not None:
        ax.axvline(o.safety, color="k", linewidth=1.5, label="chosen factor %.2f" % o.safety)
    ax.set_xlabel("dt / per-axis bound")
    ax.set_ylabel("energy drift / initial kinetic energy")
    ax.set_title("Undamped packings, held cell, %d steps (x: unstable; dotted: wobble; dashed: old default)"
                 % o.steps, fontsize=8)
    ax.legend(fontsize=8, loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    o = options()
    from trueaniso import engines
    specs, rows = [], []
    for label, path in o.specimens:
        base = held_specimen(path)
        bound = engines.TimeStepper.per_axis_bound(base)
        old = engines.TimeStepper.stiffness_bound(base)
        sp = describe(label, path, base, bound, old)
        specs.append(sp)
        print("%s: %d bodies, per-axis bound %.4g s, old bound %.4g s (ratio %.3f), two-body limit %.4g s"
              % (label, sp["bodies"], bound, old, old / bound, sp["pair"]), flush=True)
        for f in o.factors:
            r = run(base, f, bound, o)
            r["label"] = label
            rows.append(r)
            print("  f = %.2f: %s%s (%d steps, %.0f s)" % (
                f, r["status"], "" if r["status"] != "stable" else
                ", drift %+.2e, wobble %.2e" % (r["drift"], r["wobble"]), r["steps"], r["wall"]), flush=True)
    if o.json:
        with open(o.json, "w") as fh:
            json.dump(dict(specs=specs, rows=rows, steps=o.steps, every=o.every, kinetic=o.kinetic, threads=o.threads),
                      fh, indent=1)
    threads = {o.threads} if o.specimen else set()
    for path in o.merge:
        with open(path) as fh:
            earlier = json.load(fh)
        if (earlier["steps"], earlier["every"], earlier["kinetic"]) != (o.steps, o.every, o.kinetic):
            cli.fail("--merge %s: runs of other --steps, --every or --kinetic" % path)
        threads.add(earlier["threads"])
        specs += [sp for sp in earlier["specs"] if sp["label"] not in [x["label"] for x in specs]]
        rows += earlier["rows"]
    if len(threads) > 1:
        cli.fail("--merge: runs on other OpenMP thread counts (%s)" % ", ".join(sorted(threads)))
    o.threads = threads.pop()
    o.factors = sorted(set(r["f"] for r in rows))
    text = table(specs, rows, o)
    print(text)
    if o.csv:
        keys = ["label", "f", "dt", "status", "stopped_at", "steps", "drift", "wobble", "wall"]
        with open(o.csv, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=keys, extrasaction="ignore")
            w.writeheader()
            for r in rows:
                w.writerow(r)
    if o.figure:
        figure(o.figure, specs, rows, o)
    if o.doc:
        _bench.replace_block(o.doc, o.block, text)


if __name__ == "__main__":
    main()
