"""A packing made the way a YADE user makes one, saved with O.save: makeCloud, YADE's Hertz-Mindlin
law, PeriTriaxController to an isotropic 100 kPa with the paper's mu = 0.5.
Usage: yade-double -n -x yade_save_packing.py N PACK.yade.gz OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, GlobalStiffnessTimeStepper, PeriTriaxController, utils  # noqa: E402

from yade_scenes import mindlin_cloud  # noqa: E402

n, pack, out = int(sys.argv[1]), sys.argv[2], sys.argv[-1]
# relStressTol 1e-3 and maxUnbalanced 1e-3: a consolidated state, not a perfect one; the probe
# that reads this file relaxes it further at its own tolerance.
triax = PeriTriaxController(goal=(-100e3, -100e3, -100e3), stressMask=7, relStressTol=1e-3, maxUnbalanced=1e-3,
                            maxStrainRate=(20, 20, 20), globUpdate=1, doneHook="O.pause()", label="triax")
mindlin_cloud(n, seed=1, solid_fraction=0.4,
              extra_engines=[GlobalStiffnessTimeStepper(timestepSafetyCoefficient=0.5), triax])
O.dt = 1e-8
O.run(1_000_000, True)
O.save(pack)
with open(out, "w") as f:
    json.dump(dict(n=len(O.bodies), iter=O.iter, stress=np.array(utils.getStress()).tolist(),
                   unbalanced=utils.unbalancedForce(), materials=len(O.materials)), f, indent=1)
