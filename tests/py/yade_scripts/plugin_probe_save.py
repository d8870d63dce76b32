"""A StressProbe saved mid-probe with O.save and loaded with O.load in a new process, against the
same probe run on in the first process (docs/yade-peer.md, "The classes").

Usage: YADE_PREFIX=... yade-double -n -x plugin_probe_save.py SPECIMEN.npz MODE OUT.json
MODE:
  save:N:FILE  import the specimen with our law, start a z probe of the held stresses, run N steps,
               O.save(FILE), then on until the probe ends;
  load:FILE    O.load(FILE) (written by save) and on until the probe ends.
"""
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
from yade import O  # noqa: E402
from yade.wrapper import StressProbe  # noqa: E402

from trueaniso import specimen_file, yade_bridge  # noqa: E402

path, mode, out = sys.argv[1], sys.argv[2], sys.argv[-1]
result = dict(mode=mode)


def frictions():
    """The distinct friction coefficients of the real interactions."""
    return sorted({I.phys.tangensOfFrictionAngle for I in O.interactions if I.isReal})


if mode.startswith("load:"):
    O.load(mode.split(":", 1)[1])
    result["engines"] = [type(e).__name__ for e in O.engines]
    result["laws"] = [type(f).__name__ for e in O.engines if type(e).__name__ == "InteractionLoop"
                      for f in e.lawDispatcher.functors]
    probe = [e for e in O.engines if isinstance(e, StressProbe)][0]
    result["loaded"] = dict(iter=O.iter, stage=probe.stage, steps=probe.steps)
else:
    scene, _ = specimen_file.load(path)
    yade_bridge.yade_scene_from(scene, damping=0.4, law="trueaniso")
    result["held_positions"] = [list(b.state.pos) for b in O.bodies]
    result["friction_before"] = frictions()
    probe = StressProbe(axis="z", label="probe")
    O.engines = O.engines[:-1] + [probe] + O.engines[-1:]
    _, n, file = mode.split(":", 2)
    O.run(int(n), True)
    result["saved"] = dict(iter=O.iter, stage=probe.stage, steps=probe.steps)
    O.save(file)
while not probe.finished and probe.steps < 200_000:
    O.run(500, True)
result.update(stage=probe.stage, E=probe.E, nu=list(probe.nu), steps=probe.steps, message=probe.message,
              friction_after=frictions(), positions=[list(b.state.pos) for b in O.bodies],
              edge=O.cell.hSize[0][0])
with open(out, "w") as f:
    json.dump(result, f)
