"""LAMMPS input and data files from one of our specimens, and a LAMMPS run timed and checked.

    /usr/bin/python3 bench/lammps_peer.py --specimen S.npz --out DIR [--style granular] [--run]

LAMMPS is a speed peer (Debian's `lammps`, binary `lmp`, package GRANULAR); bench_stepper.py uses
this module. Our specimen is written as a LAMMPS data file (atom_style sphere, units si, the periodic box) with
an input script for one of two pair styles:
 - `granular`: pair_coeff hertz/material E 0 nu, tangential mindlin NULL 0 mu. Its Hertz normal
   force (4/3) E* sqrt(R*) delta^1.5 with E* = E/(2(1-nu^2)) = G/(1-nu), and Mindlin's
   k_t = 8 G* a with G* = G/(2(2-nu)), a = sqrt(R* delta), are our Eqs. (5)-(6) exactly;
 - `gran/hertz/history`: Kn = (4/3) E* and Kt = 4 G/(2-nu) give the same normal force and the
   same initial tangential stiffness (k_t sqrt(R* delta)), with LAMMPS's simpler shear update.
No damping on either side of LAMMPS's (eta_n = 0, x_gamma_t = 0; gamma_n = gamma_t = 0), the
integrator fix nve/sphere. The pressure of the pair forces at step 0 must equal ours: it proves
the same packing and the same normal law (the tangential history is not carried over; for spheres
it does not enter the trace of the Love-Weber stress).
"""
import math
import os
import re
import subprocess
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
if os.path.join(os.path.dirname(HERE), "pyscripts") not in sys.path:
    sys.path.insert(0, os.path.join(os.path.dirname(HERE), "pyscripts"))  # trueaniso
from trueaniso import cli  # noqa: E402

STYLES = ("granular", "gran/hertz/history")


def write_inputs(scene, directory, style, dt, steps, skin_factor=0.2):
    """data.lmp and in.lmp in `directory` for `steps` timed steps of `style`."""
    if style not in STYLES:
        raise ValueError("LAMMPS pair style must be one of %s" % (STYLES,))
    os.makedirs(directory, exist_ok=True)
    h = np.asarray(scene.cell_size, dtype=float)
    if h.shape != (3,):
        raise ValueError("the LAMMPS peer writes orthorhombic cells only")
    pos = np.mod(np.asarray(scene.positions), h)  # LAMMPS wants every atom inside the box
    rad = np.asarray(scene.radii)
    rho = scene.density
    lines = ["trueaniso specimen (%d spheres)" % len(rad), "", "%d atoms" % len(rad), "1 atom types", "",
             "0 %.17g xlo xhi" % h[0], "0 %.17g ylo yhi" % h[1], "0 %.17g zlo zhi" % h[2], "", "Atoms # sphere", ""]
    lines += ["%d 1 %.17g %.17g %.17g %.17g %.17g" % (k + 1, 2 * rad[k], rho, *pos[k]) for k in range(len(rad))]
    with open(os.path.join(directory, "data.lmp"), "w") as f:
        f.write("\n".join(lines) + "\n")
    G, nu, mu = scene.shear_modulus, scene.poisson, scene.friction
    estar = G / (1 - nu)
    if style == "granular":
        pair = ["pair_style granular",
                "pair_coeff * * hertz/material %.17g 0.0 %.17g tangential mindlin NULL 0.0 %.17g"
                % (2 * G * (1 + nu), nu, mu)]
    else:
        pair = ["pair_style gran/hertz/history %.17g %.17g 0.0 0.0 %.17g 0"
                % (4.0 / 3.0 * estar, 4.0 * G / (2.0 - nu), mu), "pair_coeff * *"]
    script = ["units si", "atom_style sphere", "boundary p p p", "comm_modify vel yes",
              "read_data data.lmp", *pair,
              "neighbor %.17g bin" % (skin_factor * rad.max()), "neigh_modify delay 0 every 1 check yes",
              "timestep %.17g" % dt, "fix integrate all nve/sphere",
              "compute pair_pressure all pressure NULL pair", "thermo_style custom step c_pair_pressure",
              "thermo_modify format float %.12g", "run 0", "thermo %d" % max(steps, 1), "run %d" % steps]
    with open(os.path.join(directory, "in.lmp"), "w") as f:
        f.write("\n".join(script) + "\n")


def run(directory, procs=1, timeout=3600):
    """Run LAMMPS in `directory` on `procs` MPI ranks (the Debian build has no OpenMP package).
    Returns dict(seconds, steps, atoms, procs, pressure) from LAMMPS's own log."""
    cmd = ["lmp", "-in", "in.lmp", "-log", "log.lammps", "-screen", "none"]
    if procs > 1:
        cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(procs)] + cmd
    env = dict(os.environ, OMP_NUM_THREADS="1")
    proc = subprocess.run(cmd, cwd=directory, capture_output=True, text=True, timeout=timeout, env=env)
    log = open(os.path.join(directory, "log.lammps")).read() if os.path.exists(os.path.join(directory, "log.lammps")) else ""
    if proc.returncode != 0 or "Loop time" not in log:
        raise RuntimeError("LAMMPS failed in %s:\n%s\n%s" % (directory, log[-2000:], proc.stderr[-2000:]))
    loops = re.findall(r"Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", log)
    seconds, nproc, steps, atoms = loops[-1]
    # The first thermo line after "run 0": step 0 and the pair pressure.
    p0 = re.search(r"Step\s+c_pair_pressure\s*\n\s*0\s+([0-9.eE+-]+)", log)
    return dict(seconds=float(seconds), procs=int(nproc), steps=int(steps), atoms=int(atoms),
                pressure=float(p0.group(1)) if p0 else math.nan)


def main():
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--specimen", required=True, help="specimen file (.npz)")
    p.add_argument("--out", required=True, help="directory for data.lmp and in.lmp")
    p.add_argument("--style", default="granular", choices=STYLES, help="LAMMPS pair style")
    p.add_argument("--steps", type=int, default=1000, help="timed steps in in.lmp")
    p.add_argument("--dt", type=float, default=0.0, help="time step (s); 0: half our stiffness bound")
    p.add_argument("--run", action="store_true", help="also run LAMMPS there and compare its pressure with ours")
    p.add_argument("--procs", type=int, default=1, help="MPI ranks for --run")
    o = cli.parse(p)
    if o.steps < 1 or o.procs < 1 or o.dt < 0:
        cli.fail("--steps and --procs must be >= 1 and --dt >= 0")
    from trueaniso import engines, specimen_file
    import _bench
    # Squared as bench_stepper squares it: a prepared specimen's cell keeps ~1e-8 of shear, and
    # would be refused here as sheared.
    s, _ = specimen_file.load(o.specimen)
    squared = _bench.orthorhombic(s)
    if squared is not s:
        print("the cell's shear terms (largest %.2g of its edge) dropped: LAMMPS is given an orthorhombic box"
              % float(np.abs(s.cell - np.diag(np.diag(s.cell))).max() / np.abs(np.diag(s.cell)).min()))
    s = squared
    dt = o.dt or 0.5 * engines.TimeStepper.stiffness_bound(s)
    write_inputs(s, o.out, o.style, dt, o.steps)
    print("wrote %s (data.lmp, in.lmp: %d steps of %g s, pair style %s)" % (o.out, o.steps, dt, o.style))
    if o.run:
        r = run(o.out, o.procs)
        ours = float(engines.stress(s).trace() / 3)
        print("LAMMPS: %.3f M particle-steps/s on %d ranks; pair pressure at step 0 %.9g Pa, ours %.9g Pa"
              % (r["atoms"] * r["steps"] / r["seconds"] / 1e6, r["procs"], r["pressure"], ours))


if __name__ == "__main__":
    cli.guarded(main)
