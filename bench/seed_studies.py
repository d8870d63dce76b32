"""The seed studies of docs/studies/specimens.md ("Seeds"): the default study (run_study.py, what ./main.sh
runs) of one assembly on several seeds, or their data collected for the manual.

    /usr/bin/python3 bench/seed_studies.py --assembly sphere --n 1000 --seeds 1,2,3 --ids 1-39
    /usr/bin/python3 bench/seed_studies.py --collect results/seeds/sphere-1000-s1 ... --out docs/data/seeds

Without --collect, it runs `pyscripts/run_study.py --assembly A --n N --seed S --ids IDS --threads 1`
into --root/A-N-sS for each seed in turn (each a study: a rerun continues it where it stopped).
--collect copies each study's probes.csv, metadata.json, summary.json and statics records, and
writes specimen.json, the specimen's summary and preparation parameters (steps, wall time, recipe),
into --out/<study's name>: what trueaniso.analysis.seeds reads. The specimens themselves are not
copied (a study's specimen is remade by its command).
"""
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
if HERE not in sys.path:
    sys.path.insert(0, HERE)
import _bench  # noqa: E402,F401  (it makes trueaniso importable)

from trueaniso import cli  # noqa: E402

REPO = os.path.dirname(HERE)
COPIED = ("probes.csv", "metadata.json", "summary.json", "statics_isotropic.json", "statics_state-1.json",
          "statics_state-21.json")


def ids(text):
    """'1-39' or '1,5,21' -> '1,2,...' (run_study.py's form)."""
    try:
        return ",".join(str(i) for i in _bench.state_ids(text))
    except ValueError:
        cli.fail("--ids %r: give Table C1 states as 1-39 or 1,5,21" % text)


def run(o):
    for seed in (int(s) for s in o.seeds.split(",")):
        out = os.path.join(o.root, "%s-%d-s%d" % (o.assembly, o.n, seed))
        cmd = [sys.executable, os.path.join(REPO, "pyscripts", "run_study.py"), "--assembly", o.assembly,
               "--n", str(o.n), "--seed", str(seed), "--ids", ids(o.ids), "--threads", "1",
               "--progress-every", "60", "--out", out]
        print(" ".join(cmd), flush=True)
        rc = subprocess.call(cmd, env=dict(os.environ, OMP_NUM_THREADS="1"))
        if rc:
            return rc
    return 0


def collect(o):
    from trueaniso import specimen_file
    for study in o.collect:
        dest = os.path.join(o.out, os.path.basename(os.path.normpath(study)))
        os.makedirs(dest, exist_ok=True)
        for name in COPIED:
            if os.path.exists(os.path.join(study, name)):
                shutil.copyfile(os.path.join(study, name), os.path.join(dest, name))
        _, meta = specimen_file.read(os.path.join(study, "specimen.npz"))
        specimen_file.write_summary(os.path.join(dest, "specimen.npz"), meta)
        print("collected", dest)
    return 0


def main(argv=None):
    p = cli.Parser(description=cli.description(__doc__))
    p.add_argument("--assembly", default="sphere", help="sphere, clump1 or clump2")
    p.add_argument("--n", type=int, default=1000, help="particles in each specimen")
    p.add_argument("--seeds", default="1,2,3", help="seeds, comma separated")
    p.add_argument("--ids", default="1-39", help="Table C1 states: a range A-B or a comma-separated list")
    p.add_argument("--root", default=os.path.join(REPO, "results", "seeds"), help="where the studies are run")
    p.add_argument("--collect", nargs="+", metavar="STUDY", help="collect these study directories instead of running")
    p.add_argument("--out", default=os.path.join(REPO, "results", "seeds-data"),
                   help="where --collect writes (the manual's data: docs/data/seeds)")
    o = cli.parse(p, argv)
    return collect(o) if o.collect else run(o)


if __name__ == "__main__":
    sys.exit(main())
