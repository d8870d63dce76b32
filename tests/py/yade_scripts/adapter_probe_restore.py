"""The documented adapter workflow (docs/howto/yade-bridge.md): save the held state with O.saveTmp,
mu = 1e23, our StressProbe through the adapter on z, detach, O.loadTmp; then the same on x.
Checks that YADE's own save/restore brings back positions, cell and friction between probes.
Usage: yade-double -n -x adapter_probe_restore.py SPECIMEN.npz OUT.json
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import numpy as np  # noqa: E402
from yade import O, utils  # noqa: E402

from trueaniso import engines, triaxial, yade_adapter, yade_bridge, specimen_file  # noqa: E402

path, out = sys.argv[1], sys.argv[-1]
scene, _ = specimen_file.load(path)
yade_bridge.yade_scene_from(scene, O)
held = -np.diag(np.array(utils.getStress()))
pos0 = np.array([list(b.state.pos) for b in O.bodies])
h0 = np.array([[O.cell.hSize[i][j] for j in range(3)] for i in range(3)])
O.saveTmp("held")
res = dict(ours={}, adapter={})
for axis in (2, 0):
    yade_adapter.set_friction(O, 1e23)
    probe = engines.StressProbe()
    probe.axis = axis
    probe.max_strain_rate = 10.0
    probe.begin(held)
    yade_adapter.attach(probe, engines.cell_stiffness(scene))
    yade_adapter.run_until_done(probe, O)
    res["adapter"]["xyz"[axis]] = float(probe.young_modulus)
    # A plain O.run with the finished probe still attached runs its steps (it stopped after one).
    start = O.iter
    O.run(20, True)
    res["steps_after_done_" + "xyz"[axis]] = O.iter - start
    yade_adapter.detach(O)
    O.loadTmp("held")
    res["pos_diff_" + "xyz"[axis]] = float(np.abs(np.array([list(b.state.pos) for b in O.bodies]) - pos0).max())
    res["cell_diff_" + "xyz"[axis]] = float(np.abs(np.array([[O.cell.hSize[i][j] for j in range(3)]
                                                             for i in range(3)]) - h0).max())
    res["mu_after_" + "xyz"[axis]] = max(I.phys.tangensOfFrictionAngle for I in O.interactions if I.isReal)
    res["ours"]["xyz"[axis]] = float(triaxial.probe(scene, held, axis)["E"])
with open(out, "w") as f:
    json.dump(res, f, indent=1)
