"""Runs several of the scripts beside it in this one yade-double, one after another, each as if it
were started alone: its own argv (script, arguments, its JSON output last), a new scene (O.reset()),
and the global names of __main__ and of builtins (where YADE puts labels) as they were before it
ran. A script that raises leaves its traceback in OUT.error and the next one still runs. Starting
yade-double takes longer than many of these scripts.
Usage: yade-double -n -x in_one_yade.py JOBS.json
JOBS.json: a list of [script, arg, ..., OUT.json].
"""
import builtins
import json
import sys
import traceback

import __main__
from yade import O


def restore(namespace, before):
    for name in [k for k in namespace if k not in before]:
        del namespace[name]
    namespace.update(before)


with open(sys.argv[1]) as f:
    jobs = json.load(f)
# yade-double runs this script in __main__'s namespace: every name it needs exists before the
# snapshot, so that restoring it keeps them.
saved = {"builtins": dict(vars(builtins))}
saved["main"] = dict(vars(__main__))

for job in jobs:
    script, out = job[0], job[-1]
    O.reset()
    sys.argv = list(job)
    print("in_one_yade: %s" % " ".join(job), flush=True)
    try:
        with open(script) as f:
            code = compile(f.read(), script, "exec")
        exec(code, vars(__main__))
    except BaseException:  # noqa: B902 - SystemExit of a script too: the next script still runs
        with open(out + ".error", "w") as f:
            f.write(traceback.format_exc())
    finally:
        restore(vars(__main__), saved["main"])
        restore(vars(builtins), saved["builtins"])
