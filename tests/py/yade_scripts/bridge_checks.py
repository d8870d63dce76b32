"""What the bridge refuses and what strain it carries:
 - the strain (refHSize, trsf) and strain rate of our scene survive yade_scene_from and come back;
 - a cell YADE flipped imports with the strain of YADE's motion (trsf), not a shear that never was;
 - another material (ViscElMat), another law's interactions (FrictPhys) and bodies that are not
   free (blocked DOFs, not dynamic) are refused in one BridgeError each.
Usage: yade-double -n -x bridge_checks.py SPECIMEN.npz OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import (O, Matrix3, Vector3, Vector3i, utils, ViscElMat, ForceResetter, InsertionSortCollider, Bo1_Sphere_Aabb,  # noqa: E402
                  InteractionLoop, Ig2_Sphere_Sphere_ScGeom, Ip2_FrictMat_FrictMat_FrictPhys,
                  Law2_ScGeom_FrictPhys_CundallStrack, NewtonIntegrator)

from trueaniso import engines, specimen_file, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
res = {}
ours, _ = specimen_file.load(path)
# A strained cell and a strain rate: our reference 1 % longer in x, 1 % shorter in z.
ours.cell_ref = ours.cell @ np.diag([1.01, 1.0, 0.99])
ours.velocity_gradient = np.diag([-0.1, 0.05, 0.05])
ids = yade_bridge.yade_scene_from(ours, O)
back, _ = yade_bridge.scene_from_yade(O)
res["strain"] = [float(v) for v in ours.strain]
res["strain_back"] = [float(v) for v in back.strain]
res["velocity_gradient_back"] = float(np.abs(back.velocity_gradient - ours.velocity_gradient).max())

# YADE flips a sheared cell (hSize -> hSize M, trsf kept): the import's strain is the motion's.
h0 = np.array(ours.cell)
shear = np.array([[1.0, 0.8, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
O.cell.trsf = Matrix3(*shear.ravel())
O.cell.hSize = Matrix3(*(shear @ h0).ravel())
O.cell.refHSize = Matrix3(*h0.ravel())
before = np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)])
O.cell.flipCell()
after = np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)])
res["flipped"] = bool(np.abs(after - before).max() > 1e-3 * np.abs(h0).max())
flipped, _ = yade_bridge.scene_from_yade(O, import_contacts=False)
res["flip_motion_error"] = float(np.abs(flipped.cell @ np.linalg.inv(flipped.cell_ref) - shear).max())


def refusal(edit):
    """Rebuild O from our scene, apply `edit`, import: the BridgeError's message, or None."""
    yade_bridge.yade_scene_from(ours, O, import_contacts=False)
    edit()
    try:
        yade_bridge.scene_from_yade(O)
    except yade_bridge.BridgeError as exc:
        return str(exc)
    return None


def viscel():
    m = O.materials.append(ViscElMat(young=1e8, poisson=0.3, frictionAngle=0.5, density=2500))
    for b in O.bodies:
        b.material = O.materials[m]


def linear():
    O.engines = [ForceResetter(), InsertionSortCollider([Bo1_Sphere_Aabb()]),
                 InteractionLoop([Ig2_Sphere_Sphere_ScGeom()], [Ip2_FrictMat_FrictMat_FrictPhys()],
                                 [Law2_ScGeom_FrictPhys_CundallStrack()]), NewtonIntegrator()]
    O.step()


def blocked():
    O.bodies[3].state.blockedDOFs = "xyz"


def fixed():
    O.bodies[5].dynamic = False


def damped():
    yade_bridge.yade_scene_from(ours, O)  # with contacts: MindlinPhys, then given damping
    for I in O.interactions:
        if I.isReal:
            I.phys.betan = 0.5


def singular_trsf():
    O.cell.trsf = Matrix3(1, 0, 0, 0, 1, 0, 0, 0, 0)


def wall():  # a fixed wall: named as a wall, not told to be freed
    O.bodies.append(utils.wall((0, 0, 0), axis=2))


def coincident():  # a sphere on another's centre: the import returned, with a NaN stress
    b = O.bodies[4]
    O.bodies.append(utils.sphere(b.state.pos, b.shape.radius, material=b.material))


def young_zero():
    for b in O.bodies:
        b.material.young = 0


def nan_position():
    O.bodies[6].state.pos = Vector3(float("nan"), 0, 0)


def nan_young():  # NaN != NaN: each sphere would count as its own material
    for b in O.bodies:
        b.material.young = float("nan")


def nan_velocity():
    O.bodies[7].state.vel = Vector3(float("nan"), 0, 0)


def on_an_image():  # a sphere on another's centre plus a cell vector: a round-off branch, not NaN
    b = O.bodies[4]
    O.bodies.append(utils.sphere(b.state.pos + O.cell.hSize.col(0), b.shape.radius, material=b.material))


res["refusals"] = {name: refusal(edit) for name, edit in
                   (("viscel", viscel), ("linear", linear), ("blocked", blocked), ("fixed", fixed),
                    ("damped", damped), ("singular_trsf", singular_trsf), ("wall", wall),
                    ("coincident", coincident), ("young_zero", young_zero), ("nan_position", nan_position),
                    ("nan_young", nan_young), ("nan_velocity", nan_velocity), ("on_an_image", on_an_image))}


# A scene YADE has moved leaves bodies outside its cell; our import wraps them in. Written straight
# back, YADE's interactions must keep their images: the same contacts and stress after a step at rest.
def at_rest_step():
    for b in O.bodies:
        b.state.vel = b.state.angVel = Vector3(0, 0, 0)
        b.state.blockedDOFs = "xyzXYZ"
    O.cell.velGrad = Matrix3(0, 0, 0, 0, 0, 0, 0, 0, 0)
    O.step()
    for b in O.bodies:
        b.state.blockedDOFs = ""
    return sum(1 for I in O.interactions if I.isReal), -np.array(utils.getStress())


plain, _ = specimen_file.load(path)
ids = yade_bridge.yade_scene_from(plain, O)
res["unbalanced_after_export"] = [float(utils.unbalancedForce()), float(engines.unbalanced_force(plain))]
h = np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)])
moved = {ids[k]: np.array([1, 0, -1]) for k in range(0, len(ids), 7)}  # every 7th body a cell vector away
for i, shift in moved.items():
    O.bodies[i].state.pos = O.bodies[i].state.pos + Vector3(*(h @ shift))
for I in O.interactions:  # YADE consistent: each pair keeps its branch
    d = moved.get(I.id1, np.zeros(3, int)) - moved.get(I.id2, np.zeros(3, int))
    I.cellDist = Vector3i(*[int(v) for v in np.array([I.cellDist[k] for k in range(3)]) + d])
res["before_write"] = at_rest_step()[0]
count, stress = at_rest_step()
scene, ids = yade_bridge.scene_from_yade(O)
res["wrapped_on_import"] = int(np.sum(np.abs(scene.positions - np.array([list(O.bodies[i].state.pos) for i in ids]))
                                      .max(axis=1) > 1e-3 * np.abs(h).max()))
yade_bridge.write_to_yade(scene, O, ids)
count2, stress2 = at_rest_step()
res["contacts_before_after"] = [count, count2]
res["stress_change"] = float(np.abs(stress2 - stress).max() / np.abs(stress).max())
res["written_moved"] = float(max((O.bodies[i].state.pos - Vector3(*p)).norm() for i, p in
                                 zip(ids, scene.positions + yade_bridge.nearest_image_shifts(O, ids, scene.positions,
                                                                                             scene.cell))))


# Continued in YADE under a strain rate, the written-back scene follows the original (bodies written
# wrapped would make YADE's collider miss contacts, 2 of 314 after 1500 steps).
def continued(steps):
    for b in O.bodies:
        b.state.vel = Vector3(0, 0, 0)
    O.cell.velGrad = Matrix3(-1.0, 0.3, 0, 0, 0.5, 0, 0, 0, 0.5)
    O.run(steps, True)
    return sum(1 for I in O.interactions if I.isReal), -np.array(utils.getStress())


O.saveTmp("original")
count_a, stress_a = continued(300)
O.loadTmp("original")
scene, ids = yade_bridge.scene_from_yade(O)
yade_bridge.write_to_yade(scene, O, ids)
count_b, stress_b = continued(300)
res["continued_contacts"] = [count_a, count_b]
res["continued_stress_change"] = float(np.abs(stress_b - stress_a).max() / np.abs(stress_a).max())

# Our dynamics in between: YADE continues with our shear forces, not its own from before our run.
O.loadTmp("original")
scene, ids = yade_bridge.scene_from_yade(O)
scene.velocity_gradient = np.diag([-0.5, 0.25, 0.25])
from trueaniso import dem  # noqa: E402
dem.Chain(scene).run(1000)
scene.velocity_gradient = np.zeros((3, 3))
dem.refresh(scene)
yade_bridge.write_to_yade(scene, O, ids)
count_c, stress_c = at_rest_step()
ours_c = engines.stress(scene)
res["after_our_dynamics"] = [count_c, int(engines.coordination(scene)["Nc"]),
                             float(np.abs(stress_c - ours_c).max() / np.abs(ours_c).max())]
res["linear_positions_only"] = None
linear_ok = yade_bridge.yade_scene_from(ours, O, import_contacts=False)
linear()
try:
    yade_bridge.scene_from_yade(O, import_contacts=False)  # the way out the refusal names
    res["linear_positions_only"] = True
except yade_bridge.BridgeError as exc:
    res["linear_positions_only"] = str(exc)
# write_to_yade into a periodic O without the scene's bodies: one BridgeError, not an IndexError.
yade_bridge.yade_scene_from(ours, O, import_contacts=False)
O.bodies.erase(len(O.bodies) - 1)
try:
    yade_bridge.write_to_yade(ours, O)
    res["write_missing_bodies"] = None
except yade_bridge.BridgeError as exc:
    res["write_missing_bodies"] = str(exc)
# A scene saved with our controller attached, loaded where the controller is gone (a new process:
# here its name removed from __main__): O.run says why, where it said only NameError.
from trueaniso import yade_adapter  # noqa: E402
import __main__  # noqa: E402
yade_bridge.yade_scene_from(ours, O, import_contacts=False)
servo = engines.TrueTriaxialServo()
servo.set_goal(0.5, 100e3)
yade_adapter.attach(servo, engines.cell_stiffness(ours), O)
saved_with = os.path.join(os.path.dirname(os.path.abspath(out)), "with_controller.yade.gz")
O.save(saved_with)
for name in [k for k in vars(__main__) if k.startswith("_trueaniso_adapter_")]:
    delattr(__main__, name)
O.load(saved_with)
try:
    O.run(3, True)  # a PyRunner of iterPeriod 1 first runs at the second step
    res["loaded_without_controller"] = None
except RuntimeError as exc:
    res["loaded_without_controller"] = str(exc)
yade_adapter.attach(servo, engines.cell_stiffness(ours), O)  # the way out it names
start = O.iter
O.run(3, True)
res["reattached_steps"] = O.iter - start
# Under a label of the user's: the way out names that label (without it, it did not work).
yade_adapter.detach(O)
yade_adapter.attach(servo, engines.cell_stiffness(ours), O, label="servoX")
O.save(saved_with)
for name in [k for k in vars(__main__) if k.startswith("_trueaniso_adapter_")]:
    delattr(__main__, name)
O.load(saved_with)
try:
    O.run(3, True)
    res["loaded_without_labelled"] = None
except RuntimeError as exc:
    res["loaded_without_labelled"] = str(exc)
yade_adapter.detach(O, label="servoX")
start = O.iter
O.run(3, True)
res["detached_steps"] = O.iter - start
# write_to_yade into an O that is not periodic: one BridgeError, not an AttributeError traceback.
O.reset()
try:
    yade_bridge.write_to_yade(ours, O)
    res["write_not_periodic"] = None
except yade_bridge.BridgeError as exc:
    res["write_not_periodic"] = str(exc)
with open(out, "w") as f:
    json.dump(res, f, indent=1)
