"""One line of a yade-batch table (columns b, sigmaZ): the 100-sphere specimen S.npz in the
working directory taken to that state with the plugin's TrueTriaxialServo; writes
state-<line>.json. Run by yade-batch with YADE_PREFIX set to the plugin's prefix."""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O  # noqa: E402
from yade.utils import readParamsFromTable  # noqa: E402
from yade.wrapper import TrueTriaxialServo  # noqa: E402

from trueaniso import dem, specimen_file, yade_bridge  # noqa: E402

readParamsFromTable(b=0.0, sigmaZ=100e3)
from yade.params import table  # noqa: E402  (made by readParamsFromTable)
scene, _ = specimen_file.load("S.npz")
yade_bridge.yade_scene_from(scene, damping=0.4, law="trueaniso")
d50 = 2.0 * float(np.median(scene.radii))
servo = TrueTriaxialServo(b=table.b, sigmaZ=table.sigmaZ, meanStress=100e3, pathRate=20.0, stressTolerance=100.0,
                          maxStrainRate=dem.strain_rate_for_inertial_number(1e-3, d50, scene.density, 100e3))
O.engines = O.engines[:-1] + [servo] + O.engines[-1:]
while not (servo.reached or servo.failed) and O.iter < 1_000_000:
    O.run(5000, True)
line = os.environ["YADE_BATCH"].split(":")[-1]  # the table line yade-batch gave this job
with open("state-%s.json" % line, "w") as f:
    json.dump(dict(b=table.b, sigmaZ=table.sigmaZ, reached=servo.reached, message=servo.message,
                   stress=list(servo.stress), goal=list(servo.finalStress())), f)
