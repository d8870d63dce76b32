"""Scenes built the way a YADE user builds them, shared by the peer scripts."""
import math
import time

import numpy as np
from yade import (O, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                  InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_MindlinPhys,
                  Law2_ScGeom_MindlinPhys_Mindlin, Matrix3, PeriTriaxController, pack, utils)


def mindlin_cloud(n, seed, solid_fraction, extra_engines=(), damping=0.4, r=0.0975e-3):
    """Periodic makeCloud of n spheres (radius r, fuzz 0.2) at `solid_fraction`, the paper's
    material (G 18 GPa, nu 0.15, mu 0.5) and YADE's Hertz-Mindlin law, avoidGranularRatcheting off
    (docs/yade-peer.md). `extra_engines` go before the NewtonIntegrator. Returns the cell side."""
    G, nu = 18e9, 0.15
    O.periodic = True
    mat = O.materials.append(FrictMat(young=2 * G * (1 + nu), poisson=nu, density=2500,
                                      frictionAngle=math.atan(0.5)))
    side = (n * 4.0 / 3.0 * math.pi * r ** 3 / solid_fraction) ** (1.0 / 3.0)
    O.cell.hSize = Matrix3(side, 0, 0, 0, side, 0, 0, 0, side)
    sp = pack.SpherePack()
    sp.makeCloud((0, 0, 0), (side, side, side), rMean=r, rRelFuzz=0.2, periodic=True, seed=seed, num=n)
    sp.toSimulation(material=mat)
    from yade import NewtonIntegrator
    O.engines = [
        ForceResetter(),
        InsertionSortCollider([Bo1_Sphere_Aabb()]),
        InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                        [Ip2_FrictMat_FrictMat_MindlinPhys()], [Law2_ScGeom_MindlinPhys_Mindlin()]),
        *extra_engines,
        NewtonIntegrator(damping=damping, label="newton"),
    ]
    return side


def two_spheres_both(r1, r2, delta0, box, dt, friction, **material):
    """Two spheres on the x axis (overlap delta0) in our scene and in YADE's O, through the bridge,
    YADE's bodies blocked (the scripts drive them kinematically), and our detection-and-forces
    loop on ours. `material`: further scene attributes (rolling_stiffness, ...); import_contacts
    is off, so YADE makes its own interaction at its first step. Returns (ours, YADE ids, sim)."""
    from trueaniso import engines as E, yade_bridge
    ours = E.Scene()
    ours.shear_modulus, ours.poisson, ours.density, ours.friction = 18e9, 0.15, 2500.0, friction
    for k, v in material.items():
        setattr(ours, k, v)
    ours.cell_size = ours.cell_ref_size = [box] * 3
    c = np.full(3, 0.5 * box)
    ours.add_spheres(np.array([c, c + [r1 + r2 - delta0, 0, 0]]), np.array([r1, r2]))
    ours.dt = dt
    ids = yade_bridge.yade_scene_from(ours, O, damping=0.0, import_contacts=False)
    for b in O.bodies:
        b.state.blockedDOFs = "xyzXYZ"
    O.dt = dt
    sim = E.Simulation(ours)
    sim.add(E.ContactDetection())
    sim.add(E.ContactForces())
    return ours, ids, sim


def _log_strain(ref):
    h = np.array([O.cell.hSize[k][k] for k in range(3)])
    return -np.log(h / ref)


def yade_user_probe(hold, increment, axis=2, max_steps=400_000):
    """A stress probe as a YADE user does it on the scene in O (friction already 1e23, the
    NewtonIntegrator last in O.engines): PeriTriaxController relaxes the state at the held
    stresses `hold` (Pa, compression positive), then raises the `axis` stress by `increment`.

    Stress every step (globUpdate=1; YADE extrapolates it in between otherwise) and a relative
    tolerance of 1e-5 (1 Pa at 100 kPa, 0.3 % of a ~300 Pa increment); with the defaults (3e-5,
    5) or 1e-6 the controller reaches its goal late or never. Returns E, the two nu, increments,
    steps and wall time."""
    hold = np.asarray(hold, dtype=float)
    ref_h = np.array([O.cell.hSize[k][k] for k in range(3)])
    t0 = time.time()
    start = O.iter
    triax = PeriTriaxController(goal=tuple(-hold), stressMask=7, relStressTol=1e-5, absStressTol=1e3,
                                globUpdate=1, maxUnbalanced=1e-5, maxStrainRate=(10, 10, 10),
                                doneHook="O.pause()", label="triax")
    O.engines = O.engines[:-1] + [triax] + O.engines[-1:]
    O.run(max_steps, True)
    relax_steps = O.iter - start
    s0 = -np.diag(np.array(utils.getStress()))
    e0 = _log_strain(ref_h)
    goal = hold.copy()
    goal[axis] += increment
    triax.goal = tuple(-goal)
    start = O.iter
    O.run(max_steps, True)
    ds = -np.diag(np.array(utils.getStress())) - s0
    de = _log_strain(ref_h) - e0
    out = dict(E=float(ds[axis] / de[axis]), d_stress=ds.tolist(), d_strain=de.tolist(),
               relax_steps=int(relax_steps), probe_steps=int(O.iter - start), wall_time=time.time() - t0,
               dt=O.dt)
    for j in range(3):
        if j != axis:
            out["nu_%s%s" % ("xyz"[axis], "xyz"[j])] = float(-de[j] / de[axis])
    return out
