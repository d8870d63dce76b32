"""True-triaxial states and their x, y, z stress probes on a specimen.

    yade-double -n -x pyscripts/run_states.py --specimen S.npz --table-c1 --out results/table-c1
    yade-double -n -x pyscripts/run_states.py --specimen S.npz --states 0.5:140e3,0:60e3 --out results/x
    /usr/bin/python3 pyscripts/run_states.py --specimen S.npz --ids 1,5,21 --out results/y

Writes probes.csv (one row per state and probe direction), metadata.json, and a checkpoint per
state; an interrupted run resumes (see trueaniso/study.py).
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0] if sys.argv[0].endswith(".py") else __file__)))
from trueaniso import cli, engines, study, triaxial  # noqa: E402


def options():
    p = cli.Parser(description=__doc__.splitlines()[0])
    p.add_argument("--specimen", required=True, help="specimen file from prepare_specimen.py")
    p.add_argument("--states", help="b:sigma_z pairs in Pa, comma separated")
    p.add_argument("--table-c1", action="store_true", help="all 39 states of the paper's Table C1")
    p.add_argument("--ids", help="a subset of Table C1 states, e.g. 1,5,21")
    p.add_argument("--gamma", type=float, default=1e-6, help="probe strain gamma (Eq. 12)")
    p.add_argument("--probes", default="zxy", help="probe axes, any of x, y, z")
    p.add_argument("--rotations", choices=("free", "restrained"), default="free")
    p.add_argument("--skip-detection", action="store_true", help="no contact detection during probes")
    p.add_argument("--damping", type=float, default=0.4)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--out", required=True, help="results directory")
    return cli.parse(p)


def main():
    o = options()
    if o.threads:
        engines.set_threads(o.threads)
    chosen = sum(bool(x) for x in (o.states, o.table_c1, o.ids))
    if chosen != 1:
        raise cli.InputError("give exactly one of --states, --table-c1, --ids")
    if not os.path.isfile(o.specimen):
        raise cli.InputError("specimen file not found: %s" % o.specimen)
    if not (math.isfinite(o.gamma) and o.gamma > 0):
        raise cli.InputError("--gamma must be a finite number > 0 (got %r)" % o.gamma)
    if not o.probes or any(c not in "xyz" for c in o.probes) or len(set(o.probes)) != len(o.probes):
        raise cli.InputError("--probes must name each of the axes x, y, z at most once (got %r)" % o.probes)
    if not 0 <= o.damping < 1:
        raise cli.InputError("--damping must lie in [0, 1)")
    try:
        if o.states:
            states = study.parse_states(o.states)
        else:
            ids = [int(v) for v in o.ids.split(",")] if o.ids else None
            states = study.table_states(ids)
        for _, b, sz in states:
            triaxial.validate_state(b, sz)
    except ValueError as exc:
        raise cli.InputError(str(exc)) from None
    from trueaniso import specimen_file
    try:
        specimen_file.read(o.specimen)
    except specimen_file.SpecimenFileError as exc:
        raise cli.InputError(str(exc)) from None
    try:
        study.run_states(o.specimen, states, o.out, probes=["xyz".index(c) for c in o.probes], gamma=o.gamma,
                         restrain_rotations=o.rotations == "restrained", skip_detection=o.skip_detection,
                         damping=o.damping, log=lambda m: print(m, flush=True))
    except triaxial.StateNotReached as exc:
        cli.fail(str(exc), 1)


if __name__ == "__main__" or cli.in_yade():
    cli.guarded(main)
