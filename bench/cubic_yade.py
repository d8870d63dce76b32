"""Table B1's Sphere*: the simple cubic packing of equal spheres at 100 kPa, by YADE alone.

    yade-double -n -x bench/cubic_yade.py --json docs/data/cubic-yade.json

A second code for the closed form E = k_n / (2 r) = (12 E*^2 sigma)^(1/3) / 2 (406.7 MPa for the
paper's G = 18 GPa, nu = 0.15 at 100 kPa; docs/triaxial.md), against the paper's 386.1-386.7 MPa:
nothing of trueaniso's physics is imported (its command line only, trueaniso.cli). 4 x 4 x 4 spheres (YADE's collider needs a cell more than twice
a body's size) of one radius in YADE's periodic cell, its own
Hertz-Mindlin law (Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin) and its own
stress (utils.getStress). The cell is set so that every contact carries the Hertz force of the
isotropic stress (the overlap from Hertz's law in closed form, then corrected by YADE's own
stress until it reads the target to 1e-9), and E_i is the secant of sigma_i against the cell's
strain over a strain of +/- STRAIN along axis i with the other two edges fixed, which for the
cubic packing (nu_ij = 0) is Young's modulus. Rotations and sliding play no part (the contacts
are all normal). Writes the moduli, the stress reached and YADE's version to --json.
"""
import json
import math
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso importable)

from trueaniso import cli  # noqa: E402

G, NU, RADIUS, SIGMA = 18e9, 0.15, 0.0975e-3, 100e3
M = 4  # spheres along each edge of the cell
SITES = [(i, j, k) for i in range(M) for j in range(M) for k in range(M)]
STRAIN = 1e-6  # the study's probe size (gamma = 1e-6): the secant is the tangent to 1e-6 relative


def closed_form(sigma=SIGMA, g=G, nu=NU):
    """E = (12 E*^2 sigma)^(1/3) / 2 with E* = G / (1 - nu) (docs/triaxial.md)."""
    e_star = g / (1.0 - nu)
    return (12.0 * e_star ** 2 * sigma) ** (1.0 / 3.0) / 2.0


def build(spacing):
    from yade import (O, Bo1_Sphere_Aabb, ForceResetter, FrictMat, Ig2_Sphere_Sphere_ScGeom, InsertionSortCollider,
                      InteractionLoop, Ip2_FrictMat_FrictMat_MindlinPhys, Law2_ScGeom_MindlinPhys_Mindlin, Matrix3,
                      NewtonIntegrator, utils)
    O.reset()
    O.periodic = True
    mat = O.materials.append(FrictMat(young=2 * G * (1 + NU), poisson=NU, density=2500, frictionAngle=math.atan(0.5)))
    O.cell.hSize = Matrix3(M * spacing, 0, 0, 0, M * spacing, 0, 0, 0, M * spacing)
    for i, j, k in SITES:
        O.bodies.append(utils.sphere(((i + 0.5) * spacing, (j + 0.5) * spacing, (k + 0.5) * spacing), RADIUS,
                                     material=mat, fixed=True))
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()], verletDist=0.1 * RADIUS),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom(avoidGranularRatcheting=False)],
                                 [Ip2_FrictMat_FrictMat_MindlinPhys()], [Law2_ScGeom_MindlinPhys_Mindlin()]),
                 NewtonIntegrator(damping=0.0)]
    O.dt = 1e-9


def stress_at(h):
    """YADE's stress (compression > 0, diagonal) with the cell's edges h (x, y, z) and the spheres
    at the same fractional positions; contacts made new at this geometry (no tangential history)."""
    from yade import O, Matrix3, utils
    O.interactions.clear()
    O.cell.hSize = Matrix3(h[0], 0, 0, 0, h[1], 0, 0, 0, h[2])
    for b, (i, j, k) in zip(O.bodies, SITES):
        b.state.pos = ((i + 0.5) * h[0] / M, (j + 0.5) * h[1] / M, (k + 0.5) * h[2] / M)
    O.step()
    s = utils.getStress()
    return [-s[0][0], -s[1][1], -s[2][2]], sum(1 for I in O.interactions if I.isReal)


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--json", required=True, help="where the moduli are written")
    o = cli.parse(p)
    try:
        import yade  # noqa: F401
    except ImportError:
        sys.stderr.write("error: this script runs in YADE: yade-double -n -x %s --json OUT\n" % sys.argv[0])
        return 2
    # Hertz: F = 4/3 E* sqrt(R/2) delta^(3/2) between equal spheres, F = sigma (2r - delta)^2 a contact.
    e_star_pair = G / (2.0 * (1.0 - NU))  # E / (2 (1 - nu^2)) of two identical spheres
    delta = 0.0
    for _ in range(50):
        force = SIGMA * (2 * RADIUS - delta) ** 2
        delta = (3.0 * force / (4.0 * e_star_pair * math.sqrt(RADIUS / 2.0))) ** (2.0 / 3.0)
    spacing = 2 * RADIUS - delta
    build(spacing)
    h = [M * spacing] * 3
    for _ in range(30):  # YADE's stress to the target: rescale the overlap by Hertz's exponent
        sig, contacts = stress_at(h)
        mean = sum(sig) / 3.0
        if abs(mean / SIGMA - 1.0) < 1e-9:
            break
        delta *= (SIGMA / mean) ** (2.0 / 3.0)
        h = [M * (2 * RADIUS - delta)] * 3
    moduli = []
    for axis in range(3):
        hp, hm = list(h), list(h)
        hp[axis] *= 1.0 - STRAIN
        hm[axis] *= 1.0 + STRAIN
        sp, _ = stress_at(hp)
        sm, _ = stress_at(hm)
        # log strains of the two cells, compression positive
        moduli.append((sp[axis] - sm[axis]) / (math.log(hm[axis] / hp[axis])))
    sig, contacts = stress_at(h)
    import yade.config
    from yade import O
    out = dict(E_yade=moduli, E_closed_form=closed_form(), sigma=sig, contacts=contacts, spheres=len(O.bodies),
               strain=STRAIN, radius=RADIUS, shear_modulus=G, poisson=NU, paper=[386.1e6, 386.7e6],
               yade_version=str(yade.config.version))
    out["relative_to_closed_form"] = [m / out["E_closed_form"] - 1.0 for m in moduli]
    with open(o.json, "w") as f:
        json.dump(out, f, indent=1)
    print(json.dumps(dict(E_yade_MPa=[round(m / 1e6, 2) for m in moduli], closed_form_MPa=round(closed_form() / 1e6, 2),
                          sigma_kPa=[round(x / 1e3, 4) for x in sig], contacts=contacts)))
    return 0


sys.exit(main())
