"""Scenes built the way a YADE user builds them, shared by the peer scripts."""
import math

from yade import (O, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom,
                  InsertionSortCollider, InteractionLoop, Ip2_FrictMat_FrictMat_MindlinPhys,
                  Law2_ScGeom_MindlinPhys_Mindlin, Matrix3, pack)


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
