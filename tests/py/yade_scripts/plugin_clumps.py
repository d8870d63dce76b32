"""The plugin's classes on a clump specimen moved into YADE by the bridge with our law
(test_yade_plugin.py::test_clump_*): what the servo measures against a Love-Weber sum over clump
centres written here (and YADE's getStress), FabricRecorder against our fabric() of the same state,
StressProbe against our stepper's probe of the same scene.

Usage: YADE_PREFIX=... yade-double -n -x plugin_clumps.py SPECIMEN.npz [noprobe] OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, utils  # noqa: E402
from yade.wrapper import FabricRecorder, PyRunner, StressProbe, TrueTriaxialServo  # noqa: E402

from trueaniso import engines, specimen_file, triaxial, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
probing = "noprobe" not in sys.argv[2:-1]
DAMPING = 0.4
result = {}


def matrix(m):
    return np.array([[m[i][j] for j in range(3)] for i in range(3)])


def insert(engine):
    O.engines = O.engines[:-1] + [engine] + O.engines[-1:]


def love_weber_over_clump_centres():
    """sum F (x) L / V over the real interactions, F the force on body 2, L from the particle of
    body 1 (its clump for a clump member) to the particle of body 2's image (pos + hSize cellDist),
    compression positive: written from YADE's attributes alone."""
    h = matrix(O.cell.hSize)
    sigma = np.zeros((3, 3))
    for I in O.interactions:
        if not I.isReal:
            continue
        b1, b2 = O.bodies[I.id1], O.bodies[I.id2]
        c1 = O.bodies[b1.clumpId] if b1.isClumpMember else b1
        c2 = O.bodies[b2.clumpId] if b2.isClumpMember else b2
        L = np.array(c2.state.pos) + h @ np.array([I.cellDist[k] for k in range(3)], dtype=float) - np.array(c1.state.pos)
        F = np.array(I.phys.normalForce) + np.array(I.phys.shearForce)
        sigma += np.outer(F, L)
    return sigma / np.linalg.det(h)


def voigt(t):
    s = 0.5 * (t + t.T)
    return [s[0, 0], s[1, 1], s[2, 2], s[1, 2], s[0, 2], s[0, 1]]


scene, _ = specimen_file.load(path)
yade_bridge.yade_scene_from(scene, damping=DAMPING, law="trueaniso")
result["clumps"] = sum(1 for b in O.bodies if b.isClump)
result["members"] = sum(1 for b in O.bodies if b.isClumpMember)

# 1. The servo's measurement of one step, bodies and cell held (the integrator off: the sums below
# read the positions and cell the servo read).
newton = O.engines[-1]
newton.dead = True
servo = TrueTriaxialServo(b=0.5, sigmaZ=140e3, meanStress=100e3, label="servo")
insert(servo)
O.run(1, True)
result["servo"] = dict(stress=list(servo.stress), unbalanced=servo.unbalanced)
result["love_weber"] = voigt(love_weber_over_clump_centres())
result["getStress"] = voigt(-matrix(utils.getStress()))
result["unbalancedForce"] = utils.unbalancedForce()
O.engines = [e for e in O.engines if e is not servo]
newton.dead = False

# 2. FabricRecorder against our fabric() of the scene as it is now.
rec = FabricRecorder(label="fabric")
insert(rec)
rec()
mine, _ = yade_bridge.scene_from_yade(O)
f = engines.fabric(mine)
result["fabric"] = dict(
    recorder=dict(Zm=rec.Zm, Nc=rec.contacts, Np=rec.particles, Np0=rec.rattlers, Np1=rec.oneContact, e=rec.voidRatio,
                  NcV=rec.NcOverV, NcV36=rec.NcOverVEq36, R=matrix(rec.R).tolist(), H=matrix(rec.H).tolist(),
                  B=matrix(rec.B).tolist(), M=list(rec.M), message=rec.message),
    # YADE's own count: Thornton's Zm over its histogram of interactions per body, a clump's
    # members' interactions summed onto the clump
    yade_Zm=utils.avgNumInteractions(skipFree=True),
    ours=dict(Zm=f["Zm"], Nc=int(f["Nc"]), Np=int(f["Np"]), Np0=int(f["Np0"]), Np1=int(f["Np1"]), e=f["e"],
              NcV=f["NcV_count"], NcV36=f["NcV_eq36"], R=f["R"].tolist(), H=f["H"].tolist(), B=f["B"].tolist(),
              M=np.asarray(f["M"]).ravel().tolist()))
O.engines = [e for e in O.engines if e is not rec]

# 3. The z probe: StressProbe in YADE and our stepper's probe, from the same scene holding its own stresses.
if probing:
    scene, _ = specimen_file.load(path)
    from trueaniso import dem
    dem.refresh(scene)
    hold = triaxial.stress_as_held(scene)
    ours = triaxial.probe(scene, hold, "z", damping=DAMPING)
    result["ours"] = dict(E=ours["E"], nu_zx=ours["nu_zx"], nu_zy=ours["nu_zy"], steps=ours["steps"])
    scene, _ = specimen_file.load(path)
    yade_bridge.yade_scene_from(scene, damping=DAMPING, law="trueaniso")
    p = StressProbe(axis="z", holdStress=list(hold), restoreState=False, label="probe")  # YADE reads its end
    insert(p)
    # YADE's stress and cell where the probe takes its reference (the step its ramp begins) and its
    # increments (the step it ends), read after the probe within the same step (the forces and
    # positions it read): E from YADE's getStress over the strain of YADE's cell.
    seen = {}

    def watch():
        if p.stage in (2, 4) and p.stage not in seen:
            seen[p.stage] = dict(stress=-matrix(utils.getStress()), h=matrix(O.cell.hSize))

    globals()["watch"] = watch
    insert(PyRunner(iterPeriod=1, command="watch()"))
    while not p.finished:
        O.run(1000, True)
    result["probe"] = dict(E=p.E, nu=list(p.nu), stage=p.stage, steps=p.steps, message=p.message,
                           lost=p.lostContacts, dStress=list(p.dStress), dStrain=list(p.dStrain))
    if 2 in seen and 4 in seen:
        # small strain of the cell from the ramp's start, compression positive: -(sym(F) - I), F = h h0^-1
        F = seen[4]["h"] @ np.linalg.inv(seen[2]["h"])
        eps = -(0.5 * (F + F.T) - np.eye(3))
        d_sigma = seen[4]["stress"] - seen[2]["stress"]
        result["probe"]["yade"] = dict(d_sigma_z=d_sigma[2, 2], eps_z=eps[2, 2],
                                       E=d_sigma[2, 2] / eps[2, 2])

with open(out, "w") as fh:
    json.dump(result, fh)
