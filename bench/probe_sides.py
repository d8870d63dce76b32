"""The probes of held states against the exact static compliance of the same states: why a clump
packing's one-sided probes are not reciprocal, and what the two-sided probe gives
(docs/studies/clumps.md, 5j).

    OMP_NUM_THREADS=1 /usr/bin/python3 bench/probe_sides.py --states DIR/states --ids 4,12 \\
        --variants screen --out docs/data/probe-sides/clump2-2000-s1.jsonl
    OMP_NUM_THREADS=1 /usr/bin/python3 bench/probe_sides.py --states DIR/states --ids 1-39 \\
        --variants sides --out docs/data/probe-sides/clump2-2000-s1-all.jsonl
    OMP_NUM_THREADS=1 /usr/bin/python3 bench/probe_sides.py --states DIR/states --ids 4,12 --held-drift 16000 \\
        --out docs/data/probe-sides/drift-clump2-2000-s1.jsonl
    /usr/bin/python3 bench/probe_sides.py --doc docs/studies/clumps.md --data docs/data/probe-sides

DIR is a study directory (run_study.py, run_states.py): its states/ID.npz are the held states,
read only. For each state the script solves the static stiffness (rotations free and restrained,
engines/statics) and probes x, y and z with each variant (ProbeOptions fields; `sign` -1 probes
unloading, `zero_velocities` zeroes every body's velocity before the probe): one JSON line per
state and variant with each probe's increments and steps; a run started again skips what --out
holds. The
compliance column of a probe on axis i is d_eps / d_sigma_i; it is compared with the static
compliance S of the same rotations setting (probe over static - 1, off-diagonal and diagonal
terms apart), and the reciprocity error is trueaniso.analysis.seeds' measure (the largest
abs(S_ij - S_ji) over their mean modulus). --held-drift N holds each state's own stresses for N
steps with sliding suppressed (the probe's Relax, never ended) and records the cell's strain: what
the state does alone. --doc writes the tables from the JSON lines in --data.
"""
import json
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso importable)

from trueaniso import cli  # noqa: E402

# Variants: name -> ProbeOptions fields (and sign / zero_velocities). "screen" varies one suspected
# cause at a time from the one-sided probe of the studies before; "two_sided" varies the two-sided
# probe at the states where it is farthest from the static solve; "sides" is the one-sided probe
# and the two-sided one settled 100 and 300 steps (the default on clumps); "spheres" the same where
# the default is one-sided.
ONE = dict(sides="one")
TWO_100 = dict(sides="two", settle_steps=100)
TWO = dict(sides="two")  # settled options.TWO_SIDED_SETTLE_STEPS (300): the default on clumps
SCREEN = (("one-sided (before)", dict(ONE)),
          ("unbalanced 1e-6", dict(ONE, unbalanced=1e-6)),
          ("unbalanced 1e-7", dict(ONE, unbalanced=1e-7)),
          ("relative tolerance 2e-4", dict(ONE, relative_tolerance=2e-4)),
          ("settle 1000 steps", dict(ONE, settle_steps=1000)),
          ("gamma 1e-7", dict(ONE, gamma=1e-7)),
          ("gamma 1e-5", dict(ONE, gamma=1e-5)),
          ("unloading (sign -1)", dict(ONE, sign=-1)),
          ("detection off", dict(ONE, skip_detection=True)),
          ("ramp 1000 steps", dict(ONE, ramp_steps=1000)),
          ("velocities zeroed at the start", dict(ONE, zero_velocities=True)),
          ("rotations restrained", dict(ONE, restrain_rotations=True)),
          ("rotations restrained, two-sided", dict(TWO_100, restrain_rotations=True)),
          ("gamma 1e-7, two-sided", dict(TWO_100, gamma=1e-7)),
          ("gamma 1e-5, two-sided", dict(TWO_100, gamma=1e-5)),
          ("two-sided, settle 100 steps", dict(TWO_100)))
TWO_SIDED = (("two-sided, settle 100 steps", dict(TWO_100)),
             ("two-sided, unbalanced 1e-6", dict(TWO_100, unbalanced=1e-6)),
             ("two-sided, settle 300 steps (default)", dict(TWO)),
             ("two-sided, gamma 2e-6", dict(TWO_100, gamma=2e-6)),
             ("two-sided, gamma 5e-7", dict(TWO_100, gamma=5e-7)))
SIDES = (("one-sided (before)", dict(ONE)), ("two-sided, settle 100 steps", dict(TWO_100)),
         ("two-sided, settle 300 steps (default)", dict(TWO)))
SPHERES = (("one-sided (default)", dict(sides="auto")), ("two-sided, settle 300 steps", dict(TWO)))
VARIANTS = dict(screen=SCREEN, two_sided=TWO_SIDED, sides=SIDES, spheres=SPHERES, default=(SIDES[-1],))
PAIRS = ((0, 1), (0, 2), (1, 2))


def asymmetry(S):
    """seeds.reciprocity_errors' measure on a 3x3 compliance (S_ji = -nu_ij/E_i)."""
    return max(abs(S[i][j] - S[j][i]) / (0.5 * (abs(S[i][j]) + abs(S[j][i]))) for i, j in PAIRS)


def load(path):
    from trueaniso import specimen_file, triaxial
    scene, meta = specimen_file.load(path)
    p = meta["parameters"]
    return scene, triaxial.path_stresses(p.get("path", "true-triaxial"), float(p["b"]), float(p["sigma_z"]))


def probes(path, settings):
    """The x, y, z probes of the held state with these settings: [(d_stress, d_strain, record)]."""
    import numpy as np
    from trueaniso import triaxial
    kw = dict(settings)
    sign, zero = kw.pop("sign", 1), kw.pop("zero_velocities", False)
    out = []
    for axis in "xyz":
        scene, hold = load(path)
        if zero:
            scene.velocities = np.zeros((scene.num_bodies, 3))
            scene.angular_velocities = np.zeros((scene.num_bodies, 3))
        r = triaxial.probe(scene, hold, axis, sign=sign, **kw)
        out.append(dict(axis=axis, sides=r["sides"], d_stress=r["d_stress"], d_strain=r["d_strain"],
                        d_strain_sides=r.get("d_strain_sides"), E=r["E"], steps=r["steps"], relax=r["relax_steps"],
                        ramp=r["ramp_steps"], hold=r["hold_steps"], wall=r["wall_time"]))
    return out


def compliance(rows):
    """The probes' 3x3 compliance, column i from the probe on i: S[j][i] = d_eps_j / d_sigma_i."""
    return [[rows[i]["d_strain"][j] / rows[i]["d_stress"][i] for i in range(3)] for j in range(3)]


def compare(P, S):
    rel = [[P[j][i] / S[j][i] - 1.0 for i in range(3)] for j in range(3)]
    return dict(reciprocity=asymmetry(P), static_reciprocity=asymmetry(S), probe_over_static=rel,
                off_diagonal=max(abs(rel[j][i]) for i in range(3) for j in range(3) if i != j),
                diagonal=max(abs(rel[i][i]) for i in range(3)))


def done_in(out, key):
    """The keys of the records `out` holds already: a run interrupted and started again goes on
    from there (a last line cut short is dropped)."""
    if not os.path.exists(out):
        return set()
    good = []
    with open(out) as f:
        for line in f:
            try:
                good.append(json.loads(line))
            except ValueError:
                break
    with open(out, "w") as f:
        f.writelines(json.dumps(r) + "\n" for r in good)
    return {key(r) for r in good}


def screen(states, ids, variants, out):
    from trueaniso import engines, statics
    engines.set_threads(1)
    done = done_in(out, lambda r: (r["state"], r["variant"]))
    for sid in ids:
        todo = [(name, settings) for name, settings in VARIANTS[variants] if (sid, name) not in done]
        if not todo:
            continue
        path = os.path.join(states, "%s.npz" % sid)
        scene, _ = load(path)
        S = {rot: [list(map(float, row[:3])) for row in statics.static_stiffness(scene, rotations=rot)["S"][:3]]
             for rot in (True, False)}
        for name, settings in todo:
            t0 = time.time()
            rows = probes(path, settings)
            rec = dict(state=sid, states=states, variant=name, settings=settings,
                       **compare(compliance(rows), S[not settings.get("restrain_rotations", False)]),
                       steps=sum(r["steps"] for r in rows) / 3.0, relax=max(r["relax"] for r in rows),
                       wall=time.time() - t0, probes=rows)
            with open(out, "a") as f:
                f.write(json.dumps(rec) + "\n")
            print("state %s %-32s reciprocity %.4f (static %.4f) probe/static off %.4f diag %.4f, %.0f steps a probe"
                  % (sid, name, rec["reciprocity"], rec["static_reciprocity"], rec["off_diagonal"], rec["diagonal"],
                     rec["steps"]), flush=True)


def held_drift(states, ids, steps, out):
    """Hold each state's own stresses (the probe's Relax with an unbalanced-force criterion no state
    meets) and record the cell's strain since the start, rotations free and restrained."""
    import numpy as np
    from trueaniso import dem, engines, triaxial
    from trueaniso.options import ProbeOptions
    engines.set_threads(1)
    marks = [m for m in (25, 50, 100, 200, 300, 400, 500, 600, 800, 1000, 1500, 2000, 3000, 4000, 6000, 8000,
                         12000, 16000, 24000, 32000) if m <= steps]
    done = done_in(out, lambda r: (r["state"], r["rotations"]))
    for sid in ids:
        for restrained in (False, True):
            if (sid, "restrained" if restrained else "free") in done:
                continue
            scene, _ = load(os.path.join(states, "%s.npz" % sid))
            hold = triaxial.stress_as_held(scene)
            o = ProbeOptions(restrain_rotations=restrained)
            p = engines.StressProbe()
            p.restrain_rotations = restrained
            p.gain, p.relative_tolerance, p.unbalanced_tolerance = o.gain, o.relative_tolerance, 1e-300
            p.max_steps, p.max_strain_rate = 10 ** 9, 10.0
            chain = dem.Chain(scene, damping=o.damping, controllers=[p], rule=o.time_step)
            dem.refresh(scene)
            p.start(scene, np.asarray(hold, dtype=float))
            F0 = np.array(scene.deformation_gradient)
            trace, done = [], 0
            for m in marks:
                chain.run(m - done)
                done = m
                w = np.asarray(scene.angular_velocities)
                strain = engines.strain_between(F0, scene.deformation_gradient)
                trace.append(dict(step=m, d_strain=[float(x) for x in strain], unbalanced=float(p.unbalanced),
                                  spin=float(np.sum(w * w))))
            rec = dict(state=sid, states=states, rotations="restrained" if restrained else "free", trace=trace)
            with open(out, "a") as f:
                f.write(json.dumps(rec) + "\n")
            t = {r["step"]: r["d_strain"] for r in trace}
            print("state %s rotations %s: strain drift from step 200 to 1000 %s" % (
                sid, rec["rotations"], ", ".join("%.2e" % (t[1000][k] - t[200][k]) for k in range(3))
                if 1000 in t else "-"), flush=True)


def read(data, name):
    with open(os.path.join(data, name)) as f:
        return [json.loads(line) for line in f if line.strip()]


def screen_table(records):
    """One row a variant: per state (columns), reciprocity | probe vs static off-diagonal | diagonal."""
    states = []
    for r in records:
        if (r["label"], r["state"]) not in states:
            states.append((r["label"], r["state"]))
    head = "| variant | " + " | ".join("%s, state %s" % (lab, sid) for lab, sid in states) + " | steps a probe |"
    if not states:
        return ""
    out = [head, "|---" * (len(states) + 2) + "|"]
    names = []
    for r in records:
        if r["variant"] not in names:
            names.append(r["variant"])
    for name in names:
        cells, steps = [], []
        for lab, sid in states:
            r = next((x for x in records if x["variant"] == name and x["label"] == lab and x["state"] == sid), None)
            if r is None:
                cells.append("")
                continue
            cells.append("%.2f %% / %.2f %% / %.2f %%" % (100 * r["reciprocity"], 100 * r["off_diagonal"],
                                                          100 * r["diagonal"]))
            steps.append(r["steps"])
        out.append("| %s | %s | %s |" % (name, " | ".join(cells), "%.0f-%.0f" % (min(steps), max(steps))))
    static = []
    for lab, sid in states:
        r = next(x for x in records if x["label"] == lab and x["state"] == sid and
                 not x["settings"].get("restrain_rotations"))
        static.append("%.2f %%" % (100 * r["static_reciprocity"]))
    out.append("| static solve, rotations free: reciprocity | %s | |" % " | ".join(static))
    return "\n".join(out)


def sides_table(groups):
    """Per study: the largest reciprocity error and probe-vs-static difference over its states, one-
    and two-sided, and the steps a probe."""
    out = ["| held states | probe | largest reciprocity error (state) | median | states beyond 0.5 % | largest "
           "abs(probe/static - 1), off-diagonal | diagonal | steps a probe (mean) |", "|---|---|---|---|---|---|---|---|"]
    import statistics
    for label, records in groups:
        names = []
        for r in records:
            if r["variant"] not in names:
                names.append(r["variant"])
        for name in names:
            rs = [r for r in records if r["variant"] == name]
            worst = max(rs, key=lambda r: r["reciprocity"])
            out.append("| %s (%d states) | %s | %.2f %% (%s) | %.2f %% | %d | %.2f %% | %.2f %% | %.0f |" % (
                label, len(rs), name, 100 * worst["reciprocity"], worst["state"],
                100 * statistics.median(r["reciprocity"] for r in rs), sum(r["reciprocity"] > 5e-3 for r in rs),
                100 * max(r["off_diagonal"] for r in rs), 100 * max(r["diagonal"] for r in rs),
                statistics.mean(r["steps"] for r in rs)))
        rs = [r for r in records if r["variant"] == names[0]]
        if rs:
            worst = max(rs, key=lambda r: r["static_reciprocity"])
            out.append("| %s | static solve, rotations free | %.2f %% (%s) | %.2f %% | | | | |" % (
                label, 100 * worst["static_reciprocity"], worst["state"],
                100 * statistics.median(r["static_reciprocity"] for r in rs)))
    return "\n".join(out)


# The committed data of the tables: file under --data, its label.
SCREENS = (("clump2-2000-s1.jsonl", "seed 1"), ("clump2-2000-s2.jsonl", "seed 2"))
TWO_SCREENS = (("two-sided-clump2-2000-s1.jsonl", "seed 1"), ("two-sided-clump2-2000-s2.jsonl", "seed 2"))
ALL = (("clump2-2000-s1-all.jsonl", "clump2, 2000 clumps, seed 1"),
       ("clump2-2000-s2-all.jsonl", "clump2, 2000 clumps, seed 2"),
       ("clump2-2000-s3-all.jsonl", "clump2, 2000 clumps, seed 3"),
       ("clump1-2000-s1.jsonl", "clump1, 2000 clumps, seed 1"),
       ("spheres-1000.jsonl", "spheres, 1000"))


def main_doc(doc, data):
    """The tables of docs/studies/clumps.md 5j into `doc`, from the JSON lines in `data`."""
    for block, files in (("probe-sides-screen", SCREENS), ("probe-sides-two", TWO_SCREENS)):
        records = []
        for name, label in files:
            if os.path.exists(os.path.join(data, name)):
                records += [dict(r, label=label) for r in read(data, name)]
        _bench.publish(doc, block, screen_table(records))
    groups = [(label, read(data, name)) for name, label in ALL if os.path.exists(os.path.join(data, name))]
    _bench.publish(doc, "probe-sides-all", sides_table(groups))


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--states", help="a study's states/ directory (read only)")
    p.add_argument("--ids", default="4,12", help="state ids: 4,12 or 1-39")
    p.add_argument("--variants", choices=sorted(VARIANTS), default="screen",
                   help="screen: one cause at a time; two_sided: the two-sided probe with one setting changed; "
                        "sides: one-sided and two-sided; spheres: the same where the default is one-sided; "
                        "default: the default two-sided probe alone")
    p.add_argument("--held-drift", type=int, default=0, help="N > 0: record what each state does alone over N steps")
    p.add_argument("--out", help="JSON lines appended here")
    p.add_argument("--doc", help="write the tables of this Markdown file from --data")
    p.add_argument("--data", default="docs/data/probe-sides", help="the committed JSON lines")
    o = cli.parse(p)
    if o.doc:
        main_doc(o.doc, o.data)
        return
    if not (o.states and o.out):
        raise cli.InputError("give --states and --out (or --doc)")
    try:
        ids = [str(i) for i in _bench.state_ids(o.ids)]
    except ValueError:
        raise cli.InputError("--ids %r: give state ids as 4,12 or 1-39" % o.ids) from None
    missing = [i for i in ids if not os.path.isfile(os.path.join(o.states, "%s.npz" % i))]
    if missing:
        raise cli.InputError("%s has no held state %s (a study's states/ directory holds ID.npz)"
                             % (o.states, ", ".join(missing)))
    os.makedirs(os.path.dirname(os.path.abspath(o.out)), exist_ok=True)
    if o.held_drift > 0:
        held_drift(o.states, ids, o.held_drift, o.out)
    else:
        screen(o.states, ids, o.variants, o.out)


if __name__ == "__main__":
    cli.guarded(main)
