"""The O.engines block of docs/yade-peer.md ("O.engines"), run as written on a specimen moved into
YADE: the page's servo reaches state 21 (test_yade_plugin.py::test_the_yade_page_runs_as_written).

Usage: YADE_PREFIX=... yade-double -n -x page_engines.py SPECIMEN.npz PAGE.md OUT.json
"""
import json
import os
import re
import sys

HERE = os.path.dirname(os.path.abspath(sys.argv[0]))
sys.path[:0] = [HERE, os.path.join(HERE, "..", "..", "..", "pyscripts")]
import yade.wrapper  # noqa: E402
from yade import O, utils  # noqa: E402

from trueaniso import specimen_file, yade_bridge  # noqa: E402

path, page, out = sys.argv[1], sys.argv[2], sys.argv[-1]
blocks = re.findall(r"```python\n(.*?)```", open(page).read(), flags=re.S)
scene, _ = specimen_file.load(path)
yade_bridge.yade_scene_from(scene, damping=0.4, law="trueaniso")
# the names a script run by yade-double has: YADE's classes (the plugin's too), O, utils
namespace = dict(globals(), **{k: getattr(yade.wrapper, k) for k in dir(yade.wrapper) if not k.startswith("_")})
exec(blocks[0], namespace)  # noqa: S102 - the page's own code
# label="servo" names it as YADE names labelled objects (a builtin), or the block assigns it
servo = namespace.get("servo") or getattr(__import__("builtins"), "servo")
with open(out, "w") as f:
    json.dump(dict(blocks=len(blocks), reached=servo.reached, message=servo.message, steps=servo.steps,
                   stress=list(servo.stress), getStress=[-utils.getStress()[i][i] for i in range(3)],
                   engines=[type(e).__name__ for e in O.engines]), f)
