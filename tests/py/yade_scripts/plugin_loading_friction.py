"""TrueTriaxialServo's loading friction on contacts made while it runs
(test_yade_plugin.py::test_the_servo_s_loading_friction_reaches_contacts_made_while_it_runs).

Usage: YADE_PREFIX=... yade-double -n -x plugin_loading_friction.py SPECIMEN.npz OUT.json

The material's friction 0.3, the servo's loadingFriction 0.5 on the way to state 21: every contact,
those YADE made after the servo started too, at 0.5.
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
from yade import O  # noqa: E402
from yade.wrapper import TrueTriaxialServo  # noqa: E402

from trueaniso import specimen_file, yade_bridge  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
scene, _ = specimen_file.load(path)
scene.friction = 0.3
yade_bridge.yade_scene_from(scene, damping=0.4, law="trueaniso")
start = O.iter
servo = TrueTriaxialServo(b=0.5, sigmaZ=140e3, meanStress=100e3, pathRate=20.0)
O.engines = O.engines[:-1] + [servo] + O.engines[-1:]
while not (servo.reached or servo.failed):
    O.run(5000, True)
real = [I for I in O.interactions if I.isReal]
result = dict(reached=servo.reached, contacts=len(real), made_later=sum(1 for I in real if I.iterMadeReal > start),
              frictions=sorted({round(I.phys.tangensOfFrictionAngle, 12) for I in real}),
              material=O.materials[0].frictionAngle)
with open(out, "w") as f:
    json.dump(result, f)
