"""The seed studies of docs/specimens.md ("Seeds"): the default study (run_study.py, what ./main.sh
runs) of one assembly on several seeds, and their data copied for the manual.

    /usr/bin/python3 bench/seed_studies.py run --assembly sphere --n 1000 --seeds 1,2,3 --ids 1-39
    /usr/bin/python3 bench/seed_studies.py collect results/seeds/sphere-1000-s1 ... --out docs/data/seeds

`run` runs `pyscripts/run_study.py --assembly A --n N --seed S --ids IDS --threads 1` into
results/seeds/A-N-sS for each seed in turn (each a study: a rerun continues it where it stopped).
`collect` copies each study's probes.csv, metadata.json, summary.json and statics records, and
writes specimen.json, the specimen's summary and preparation parameters (steps, wall time, recipe),
into OUT/<study's name>: what trueaniso.analysis.seeds reads. The specimens themselves are not
copied (a study's specimen is remade by its command).
"""
import argparse
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(REPO, "pyscripts"))

COPIED = ("probes.csv", "metadata.json", "summary.json", "statics_isotropic.json", "statics_state-1.json",
          "statics_state-21.json")


def ids(text):
    """'1-39' or '1,5,21' -> '1,2,...' (run_study.py's form)."""
    if "-" in text and "," not in text:
        a, b = (int(x) for x in text.split("-"))
        return ",".join(str(i) for i in range(a, b + 1))
    return text


def run(o):
    for seed in (int(s) for s in o.seeds.split(",")):
        out = os.path.join(o.root, "%s-%d-s%d" % (o.assembly, o.n, seed))
        cmd = [sys.executable, os.path.join(REPO, "pyscripts", "run_study.py"), "--assembly", o.assembly,
               "--n", str(o.n), "--seed", str(seed), "--ids", ids(o.ids), "--threads", "1",
               "--progress-every", "60", "--out", out] + o.extra
        print(" ".join(cmd), flush=True)
        rc = subprocess.call(cmd, env=dict(os.environ, OMP_NUM_THREADS="1"))
        if rc:
            return rc
    return 0


def collect(o):
    from trueaniso import specimen_file
    for study in o.studies:
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
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="what", required=True)
    r = sub.add_parser("run")
    r.add_argument("--assembly", default="sphere")
    r.add_argument("--n", type=int, default=1000)
    r.add_argument("--seeds", default="1,2,3")
    r.add_argument("--ids", default="1-39")
    r.add_argument("--root", default=os.path.join(REPO, "results", "seeds"))
    r.add_argument("extra", nargs="*", help="more options of run_study.py, after --")
    c = sub.add_parser("collect")
    c.add_argument("studies", nargs="+")
    c.add_argument("--out", default=os.path.join(REPO, "docs", "data", "seeds"))
    o = p.parse_args(argv)
    return run(o) if o.what == "run" else collect(o)


if __name__ == "__main__":
    sys.exit(main())
