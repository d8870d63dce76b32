"""Zm along the Table C1 paths with the specimen bounded by six rigid frictionless walls.

    OMP_NUM_THREADS=1 /usr/bin/python3 pyscripts/bench/zm_walls.py --specimen S.npz \
        --out docs/data/zm-walls/spheres-4000-s1.json [--ids 5,9,21]

The periodic specimen is put between walls (boundary/RigidWalls.hpp; docs/cell.md, "Rigid walls"):
its positions are wrapped into the cell, the cell is widened by room for the walls, and each wall
is placed where it just touches the outermost sphere on its side, so that no sphere starts
overlapping a wall. The pairs that crossed the periodic boundary are gone and the contact history
starts anew (the walled specimen is a new specimen made of the same spheres). The wall servo
(WallServo: the cell servo's path logic, fed with the wall stresses) then brings it to
100 kPa isotropically at the consolidation friction (default the preparation's, 0.015), sets the
loading friction 0.5 and holds 100 kPa again: that is the walled state 1. Each state asked for is
reached from state 1 along the straight Eq. 9 path, with the study's servo settings (path rate,
tolerances), and then measured:

- e of the walled box (its volume over the solid volume), and of the interior counted by centres;
- Zm (Eq. 14) of the sphere-sphere contacts over all spheres, with the wall contacts counted as
  contacts too, and over the interior: the spheres whose centre lies farther than k d50 from every
  wall, for each k of --interior (the first is the headline);
- the wall stresses, the wall contacts, the steps.

The time step is the smallest-inertia rule's at --safety (default 0.35, 0.7 of the study's 0.5): a
wall contact is 2 sqrt(2) times as stiff as a pair's at the same overlap (docs/cell.md), which
raises the summed stiffness of a sphere touching one or three walls by up to about 1.5 and 2 times
its pair contacts' (sqrt(1/2) = 0.71 of the step keeps the bound).
"""
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402  (it makes trueaniso and analysis importable)
from trueaniso import cli  # noqa: E402

PAPER_ZM_BAND = (5.94, 5.99)


def options(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="periodic specimen file (.npz) of single spheres")
    p.add_argument("--out", required=True, help="JSON file to write (atomically)")
    p.add_argument("--ids", default="5,9,21", help="Table C1 states by number, each reached from state 1")
    p.add_argument("--interior", default="2.5,1.5,4",
                   help="interior distances from every wall, in d50 (first: the headline)")
    p.add_argument("--gain", type=cli.positive, default=0.1,
                   help="servo gain: fraction of the stress error closed per step through the wall contacts' stiffness")
    p.add_argument("--consolidation-friction", type=cli.positive, default=0.015,
                   help="friction while the walls first bring the specimen to 100 kPa (the preparation's)")
    p.add_argument("--consolidation-inertial-number", type=cli.positive, default=1e-3,
                   help="inertial number that caps the walls' strain rate while they first bring the specimen "
                        "to 100 kPa")
    p.add_argument("--friction", type=cli.positive, default=0.5, help="friction at state 1 and along the paths")
    p.add_argument("--path-rate", type=cli.positive, default=2.0, help="Pa per reference step along a path")
    p.add_argument("--consolidation-path-rate", type=cli.positive, default=1e9,
                   help="Pa per reference step while the walls first bring the specimen to 100 kPa (the default "
                        "sets the goal at once: the walls close at the capped rate, then as the servo's law allows)")
    p.add_argument("--safety", type=cli.positive, default=0.35, help="factor of the smallest-inertia time step")
    p.add_argument("--damping", type=cli.non_negative, default=0.4, help="local damping of the integrator")
    p.add_argument("--tolerance", type=cli.positive, default=100.0, help="stress tolerance of a held state (Pa)")
    p.add_argument("--unbalanced", type=cli.positive, default=1e-4, help="unbalanced force of a held state")
    p.add_argument("--max-steps", type=cli.at_least(1), default=3_000_000, help="steps allowed per state")
    p.add_argument("--probe-strain", type=cli.non_negative, default=0.0,
                   help="probe E_x, E_y, E_z at each state with this compressive strain of one wall pair, "
                        "the other two holding their stresses, sliding suppressed (0: no probes)")
    p.add_argument("--periodic", action="store_true",
                   help="the control instead of the walls: reach each state from the periodic specimen itself with the "
                        "cell servo (the study's reach_state) and count its Zm and e")
    p.add_argument("--chunk", type=cli.at_least(1), default=5000, help="steps between progress lines")
    o = cli.parse(p, argv)
    if not os.path.isfile(o.specimen):
        cli.fail("--specimen %s: no such file" % o.specimen)
    try:
        o.ids = [int(x) for x in o.ids.split(",") if x.strip()]
        o.interior = [float(x) for x in o.interior.split(",") if x.strip()]
    except ValueError:
        cli.fail("--ids and --interior: comma-separated numbers")
    if not o.ids or any(i < 1 or i > 39 for i in o.ids):
        cli.fail("--ids: Table C1 states are numbered 1-39")
    if not o.interior or any(not (k >= 0) for k in o.interior):
        cli.fail("--interior: distances >= 0 in d50")
    out_dir = os.path.dirname(os.path.abspath(o.out))
    if not os.path.isdir(out_dir):
        cli.fail("--out %s: no directory %s" % (o.out, out_dir))
    return o


def mechanical(counts):
    """Eq. 14 over the given per-particle contact counts: (sum c - Np1) / (Np - Np0 - Np1)."""
    import numpy as np
    c = np.asarray(counts)
    n0, n1 = int((c == 0).sum()), int((c == 1).sum())
    den = c.size - n0 - n1
    return (float(c.sum()) - n1) / den if den > 0 else math.nan, n0, n1


def walled_scene(scene, friction):
    """The specimen's spheres between six walls that just touch it, in a cell wide enough that no
    pair forms across the periodic boundary. Returns (scene, walls)."""
    import numpy as np
    from trueaniso import engines, specimen
    if scene.has_clumps:
        cli.fail("--specimen: it has clumps; the walls take single spheres here")
    cell = np.asarray(scene.cell)
    # The cell servo holds the shear stresses at zero, which leaves the cell sheared by ~1e-5;
    # wrapped in reduced coordinates, the spheres fill the cell's parallelepiped, whose faces
    # lean from the box's planes by that much of the edge (~1e-8 m here), far below an overlap.
    off = cell - np.diag(np.diag(cell))
    if np.abs(off).max() > 1e-3 * np.diag(cell).min():
        cli.fail("--specimen: its cell is sheared by more than 1e-3; the walls are axis-aligned")
    r = np.asarray(scene.radii)
    reduced = np.mod(np.linalg.solve(cell, np.asarray(scene.positions).T).T, 1.0)
    x = reduced @ cell.T
    dmax = 2.0 * float(r.max())
    room = 2.0 * dmax  # outside the box on each side: a diameter plus a diameter of margin for the skin
    lo = (x - r[:, None]).min(axis=0)
    hi = (x + r[:, None]).max(axis=0)
    x = x - lo + room
    s = specimen.new_scene(x, r, (hi - lo) + 2 * room, shear_modulus=scene.shear_modulus, poisson=scene.poisson,
                           density=scene.density, friction=friction)
    walls = engines.RigidWalls()
    walls.set_box(np.full(3, room), (hi - lo) + room)
    walls.margin = dmax
    walls.validate(s)
    return s, walls


def reach(scene, walls, b, sigma_z, o, friction, label, p=100e3, path_rate=None, max_strain=0.05,
          inertial_number=1e-3, hold_steps=200_000):
    """The wall servo to (b, sigma_z, p) at `friction`, held; returns its record."""
    import numpy as np
    from trueaniso import dem, engines
    servo = engines.TrueTriaxialServo()
    servo.set_goal(b, sigma_z, p)
    servo.control_shear = False
    servo.path_rate = o.path_rate if path_rate is None else path_rate
    servo.max_strain = max_strain
    servo.hold_steps = hold_steps
    servo.gain = o.gain
    servo.stress_tolerance = o.tolerance
    servo.unbalanced_tolerance = o.unbalanced
    servo.max_steps = o.max_steps
    servo.loading_friction = friction
    d50 = 2.0 * float(np.median(scene.radii))
    servo.max_strain_rate = dem.strain_rate_for_inertial_number(inertial_number, d50, scene.density, p)
    ws = engines.WallServo(walls, servo)
    walls.rate = np.zeros(3)
    chain = dem.Chain(scene, damping=o.damping, controllers=[walls, ws], rule="smallest-inertia", safety=o.safety)
    ws.start(scene)
    t0 = time.time()
    while servo.status not in ("reached", "failed"):
        chain.run(o.chunk)
        print("%s: %s %.0f %% steps %d stress %s kPa unbalanced %.2e" % (
            label, servo.status, 100 * servo.progress, servo.steps, np.round(walls.stress / 1e3, 2), servo.unbalanced),
            file=sys.stderr, flush=True)
    walls.rate = np.zeros(3)
    dem.refresh(scene)
    walls.add_forces(scene)  # the wall forces of the positions held (refresh zeroes and recomputes the bodies')
    if servo.status == "failed":
        raise SystemExit("zm_walls: %s: %s" % (label, servo.message))
    return dict(steps=int(servo.steps), wall_time=time.time() - t0, goal=list(servo.goal_stresses),
                wall_stress=walls.stress.tolist(), unbalanced=float(servo.unbalanced))


def probe(scene, walls, axis, o, ramp_steps=1000, settle_steps=200, max_steps=100_000):
    """E_axis of the held state: one wall pair compressed by o.probe_strain (log strain) over
    ramp_steps while the other two pairs hold their stresses (the wall servo's proportional law,
    driven from here one step at a time), sliding suppressed (engines.PROBE_FRICTION), rotations
    free; before the ramp and after it the walls are held until the unbalanced force is below
    1e-5 and the held stresses are within 1e-3 of the ramp's stress change for settle_steps steps.
    E = dsigma / dstrain between the two settled states. The scene and walls are restored."""
    import numpy as np
    from trueaniso import dem, engines
    snap = scene.copy()
    saved = (walls.lower.copy(), walls.upper.copy(), walls.ref_width.copy())
    friction = scene.friction
    scene.friction = engines.PROBE_FRICTION
    dem.refresh(scene)
    walls.rate = np.zeros(3)
    walls.add_forces(scene)
    hold = walls.stress.copy()
    chain = dem.Chain(scene, damping=o.damping, controllers=[walls], rule="smallest-inertia", safety=o.safety)
    others = [j for j in range(3) if j != axis]
    expected = 300e6 * o.probe_strain  # Pa: the stress change of a ~300 MPa modulus, the holds' scale

    def settle(ramp_rate=0.0, ramp=0):
        ok = 0
        for step in range(max_steps):
            m = walls.measurement(scene)
            rate = np.zeros(3)
            for j in others:
                k = m["stiffness"][j]
                rate[j] = -o.gain * (hold[j] - m["stress"][j]) / (k * scene.dt) if k > 0 else 0.0
            rate[axis] = ramp_rate if step < ramp else 0.0
            walls.rate = rate
            chain.run(1)
            if step < ramp:
                continue
            good = m["unbalanced"] < 1e-5 and all(abs(m["stress"][j] - hold[j]) < 1e-3 * expected for j in others)
            ok = ok + 1 if good else 0
            if ok >= settle_steps:
                return step + 1
        raise SystemExit("zm_walls: the probe on axis %d did not settle in %d steps" % (axis, max_steps))

    try:
        n0 = settle()
        walls.rate = np.zeros(3)
        walls.add_forces(scene)
        s0, w0 = walls.stress.copy(), walls.width.copy()
        # A log strain -probe_strain over ramp_steps steps: the rate is per step of the current dt.
        n1 = settle(-o.probe_strain / (ramp_steps * scene.dt), ramp_steps)
        walls.rate = np.zeros(3)
        walls.add_forces(scene)
        s1, w1 = walls.stress.copy(), walls.width.copy()
    finally:
        scene.assign(snap)
        scene.friction = friction
        walls.lower, walls.upper, walls.ref_width = saved
        walls.rate = np.zeros(3)
    eps = -np.log(w1 / w0)  # compression positive
    return dict(E=float((s1[axis] - s0[axis]) / eps[axis]), strain=eps.tolist(), d_stress=(s1 - s0).tolist(),
                nu={str(j): float(-eps[j] / eps[axis]) for j in others}, steps=int(n0 + n1))


def measure(scene, walls, interior):
    """e, Zm overall and in the interior, wall contacts."""
    import numpy as np
    from trueaniso import engines
    r = np.asarray(scene.radii)
    x = np.asarray(scene.positions)
    lo, hi = np.asarray(walls.lower), np.asarray(walls.upper)
    c = np.asarray(engines.contacts_per_body(scene))
    wall_c = ((x - lo < r[:, None]).sum(axis=1) + (hi - x < r[:, None]).sum(axis=1))
    d50 = 2.0 * float(np.median(r))
    vs = np.asarray(scene.volumes)
    zm, n0, n1 = mechanical(c)
    zw, _, _ = mechanical(c + wall_c)
    rec = dict(void_ratio=walls.volume / float(vs.sum()) - 1.0, Zm=zm, Np0=n0, Np1=n1, Zm_with_walls=zw,
               n=int(r.size), wall_contacts=np.asarray(walls.contacts).tolist(), width=walls.width.tolist(),
               wall_stress=walls.stress.tolist(), max_wall_overlap_over_d50=float(walls.max_overlap) / d50,
               d50=d50, periodic_Zm_engine=engines.coordination(scene)["Zm"], interior={})
    dist = np.minimum(x - lo, hi - x).min(axis=1)
    for k in interior:
        inside = dist > k * d50
        z, m0, m1 = mechanical(c[inside])
        inner = np.prod(np.maximum(hi - lo - 2 * k * d50, 0.0))
        e_in = inner / float(vs[inside].sum()) - 1.0 if inside.any() else math.nan
        rec["interior"]["%g" % k] = dict(n=int(inside.sum()), Zm=z, Np0=m0, Np1=m1, void_ratio_by_centres=e_in)
    return rec


def main(argv=None):
    o = options(argv)
    import numpy as np
    from trueaniso import atomic, engines, specimen_file, triaxial
    engines.set_threads(1)
    t0 = time.time()
    periodic, meta = specimen_file.load(o.specimen)
    z = engines.coordination(periodic)
    out = dict(specimen=os.path.basename(o.specimen), specimen_summary=dict(
        void_ratio=engines.void_ratio(periodic), Zm=z["Zm"], n=periodic.num_bodies, seed=meta.get("seed")),
        settings=dict(gain=o.gain, consolidation_friction=o.consolidation_friction, friction=o.friction,
                      path_rate=o.path_rate, consolidation_path_rate=o.consolidation_path_rate,
                      consolidation_inertial_number=o.consolidation_inertial_number, safety=o.safety,
                      damping=o.damping, tolerance=o.tolerance,
                      unbalanced=o.unbalanced, interior_d50=o.interior),
        paper_Zm_band=list(PAPER_ZM_BAND), machine=_bench.machine(), engine_version=engines.version(),
        source_hash=engines.source_hash(), states={})
    if o.periodic:
        out["boundary"] = "periodic"
        for i, b, sz in triaxial.table_c1_states():
            if i in o.ids and i != 1:
                s, _ = specimen_file.load(o.specimen)
                info = triaxial.reach_state(s, b, sz)
                zc = engines.coordination(s)
                out["states"][str(i)] = dict(Zm=zc["Zm"], Np0=zc["Np0"], Np1=zc["Np1"], b=b, sigma_z=sz,
                                             void_ratio=engines.void_ratio(s), steps=info["steps"])
                print("periodic state %d: Zm %.3f" % (i, zc["Zm"]), file=sys.stderr, flush=True)
        out["wall_time"] = time.time() - t0
        atomic.write_json(o.out, out)
        return
    out["boundary"] = "walls"
    scene, walls = walled_scene(periodic, o.consolidation_friction)
    out["placed"] = dict(width=walls.width.tolist(), void_ratio=walls.volume / float(np.sum(scene.volumes)) - 1.0)
    # The walls first close the gaps the periodic boundary left at the faces (a strain of a few
    # per cent), so the path's strain limit is raised for this step alone.
    rec1 = reach(scene, walls, 0.0, 100e3, o, o.consolidation_friction, "consolidation",
                 path_rate=o.consolidation_path_rate, max_strain=0.3, inertial_number=o.consolidation_inertial_number,
                 hold_steps=2_000_000)
    rec2 = reach(scene, walls, 0.0, 100e3, o, o.friction, "state 1 at mu %g" % o.friction)
    m = measure(scene, walls, o.interior)
    m.update(consolidation=rec1, hold=rec2, b=0.0, sigma_z=100e3)
    if o.probe_strain > 0:
        m["probes"] = {"xyz"[a]: probe(scene, walls, a, o) for a in (2, 0, 1)}
    out["states"]["1"] = m
    atomic.write_json(o.out, out)
    base = scene.copy()
    base_walls = (walls.lower.copy(), walls.upper.copy(), walls.ref_width.copy())
    states = {i: (b, sz) for i, b, sz in triaxial.table_c1_states()}
    for i in o.ids:
        if i == 1:
            continue
        scene.assign(base)
        walls.lower, walls.upper, walls.ref_width = base_walls
        b, sz = states[i]
        rec = reach(scene, walls, b, sz, o, o.friction, "state %d" % i)
        m = measure(scene, walls, o.interior)
        m.update(reach=rec, b=b, sigma_z=sz)
        if o.probe_strain > 0:
            m["probes"] = {"xyz"[a]: probe(scene, walls, a, o) for a in (2, 0, 1)}
        out["states"][str(i)] = m
        out["wall_time"] = time.time() - t0
        atomic.write_json(o.out, out)  # each state as it comes: a long run keeps what it measured
    out["wall_time"] = time.time() - t0
    atomic.write_json(o.out, out)
    for k, v in out["states"].items():
        print("state %s: e %.4f Zm %.3f (with walls %.3f) interior(%s d50) Zm %.3f n %d" % (
            k, v["void_ratio"], v["Zm"], v["Zm_with_walls"], o.interior[0], v["interior"]["%g" % o.interior[0]]["Zm"],
            v["interior"]["%g" % o.interior[0]]["n"]))


if __name__ == "__main__":
    main()
