r"""What a study cost, from its data, and what it would take on a cluster.

    /usr/bin/python3 -m trueaniso.analysis.cost STUDY_DIR [STUDY_DIR ...] [--doc FILE --block NAME]

A study is a run_study.py or run_states.py directory. Its cost is read from what the run wrote:

- the preparation: specimen.json (beside the study's specimen, or copied into the study): its steps,
  wall time and, in files made since trueaniso recorded them, CPU time, peak memory, load and runs
  (trueaniso/run_cost.py);
- the states and probes: probes.csv, each state's steps and wall time once and each probe's, and
  metadata.json's runs, each with the cost of its process when it recorded one (wall and CPU time,
  peak memory, the load's range; a run killed outright records none, and the table counts those);
- the static solves: the statics records' time and, where recorded, peak memory.

**On a cluster** (`pyscripts/slurm/table_c1.sbatch`): a worker walks one loading path at a time,
its states in order, so the study takes at least its longest path. The estimate puts each path's
own time (its states' and probes' wall times as this run measured them) on the worker that frees
first, longest paths first, for 2 workers and for one a path; it assumes the worker's speed of
this run and leaves out the master's start and the statics. Wall times measured beside other jobs
(the load says how many) make every figure an upper bound of a quiet machine's.
"""
import json
import os
import re
import sys

from .. import triaxial
from .results import ResultsError, number, read_metadata, read_probes
from .seeds import preparation_steps

TIME_COLUMNS = ["state", "probe", "state_steps", "probe_steps", "state_wall_time", "probe_wall_time"]


def _specimen_json(study, meta):
    """specimen.json copied into the study, else the one beside the specimen the study ran on."""
    there = os.path.join(study, "specimen.json")
    if os.path.exists(there):
        return json.load(open(there))
    path = ((meta or {}).get("specimen") or {}).get("path")
    beside = os.path.splitext(path)[0] + ".json" if path else None
    if beside and os.path.exists(beside):
        return json.load(open(beside))
    return None


def _number(x):
    try:
        return float(x)
    except (TypeError, ValueError):
        return None


def preparation(spec):
    """The preparation's steps, wall and CPU seconds, peak memory (MB), load range and runs
    (None where the specimen's file records none)."""
    if spec is None:
        return None
    p = spec.get("parameters") or {}
    return dict(steps=preparation_steps(p), wall=_number(p.get("wall_time")), cpu=_number(p.get("cpu_time")),
                peak=_number(p.get("peak_memory_mb")), load=(p.get("load_min"), p.get("load_max")),
                runs=p.get("runs"))


def state_times(rows, path="probe table"):
    """{state: (steps to reach it, steps of its probes, wall seconds of both)}: its state_steps and
    state_wall_time once (every probe row of a state repeats them), each probe row's own added."""
    out = {}
    for r in rows:
        reach, probes, wall = out.get(r["state"]) or (number(r, "state_steps", path), 0.0,
                                                      number(r, "state_wall_time", path))
        out[r["state"]] = (reach, probes + number(r, "probe_steps", path), wall + number(r, "probe_wall_time", path))
    return out


def path_times(meta, per_state):
    """The wall time of each loading path: the sum of its states' (state_times) over the states
    the study defines (metadata.json), grouped as the runs walk them (triaxial.paths)."""
    states = [(int(k) if k.isdigit() else k, float(d["b"]), float(d["sigma_z"])) for k, d in meta["states"].items()]
    return sorted((sum(per_state.get(str(sid), (0, 0, 0.0))[2] for sid, _, _ in path)
                   for path in triaxial.paths(states).values()), reverse=True)


def makespan(paths, workers):
    """The time of the paths on `workers` workers, each path to the worker that frees first,
    longest first (None: one worker a path, the longest path)."""
    if not paths:
        return 0.0
    if workers is None or workers >= len(paths):
        return max(paths)
    free = [0.0] * workers
    for t in sorted(paths, reverse=True):
        k = free.index(min(free))
        free[k] += t
    return max(free)


def runs_cost(meta):
    """The runs' recorded cost: wall and CPU seconds summed, peak memory, the load's range, the
    number of runs with a record and without (killed outright), and whether any left workers out."""
    recorded = [r["cost"] for r in meta.get("runs", []) if isinstance(r.get("cost"), dict)]
    loads = [x for c in recorded for x in (c.get("load_min"), c.get("load_max")) if x is not None]
    return dict(wall=sum(c["wall_time"] for c in recorded) if recorded else None,
                cpu=sum(c["cpu_time"] for c in recorded) if recorded else None,
                peak=max(c["peak_memory_mb"] for c in recorded) if recorded else None,
                load=(min(loads), max(loads)) if loads else (None, None),
                recorded=len(recorded), unrecorded=len(meta.get("runs", [])) - len(recorded),
                workers_left_out=any("cpu_of" in c for c in recorded))


def statics_cost(study):
    """(seconds, peak memory MB or None) of the study's static solves (statics_*.json)."""
    seconds, peak = 0.0, None
    for name in sorted(os.listdir(study)):
        if name.startswith("statics_") and name.endswith(".json"):
            rec = json.load(open(os.path.join(study, name)))
            seconds += float(rec.get("time") or 0)
            c = rec.get("cost") or {}
            if c.get("peak_memory_mb") is not None:
                peak = max(peak or 0.0, c["peak_memory_mb"])
    return seconds, peak


def study_cost(study):
    """Everything the tables say of one study directory."""
    meta = read_metadata(study, required=True)
    csv_path = os.path.join(study, "probes.csv")
    per_state = state_times(read_probes(csv_path, need=TIME_COLUMNS), csv_path)
    spec = _specimen_json(study, meta)
    summary = (meta.get("specimen") or {}).get("summary") or {}
    return dict(study=study, assembly=(meta.get("fingerprint") or {}).get("assembly"), n=summary.get("n"),
                preparation=preparation(spec), reach_steps=int(sum(t[0] for t in per_state.values())),
                probe_steps=int(sum(t[1] for t in per_state.values())),
                rows_wall=sum(t[2] for t in per_state.values()), states=len(per_state), runs=runs_cost(meta),
                statics=statics_cost(study), paths=path_times(meta, per_state))


def name(study):
    """A study's name in the tables: its directory's, with the one above for a seed's folder
    (docs/data/clump2-16000/s1: clump2-16000/s1)."""
    parts = os.path.normpath(os.path.abspath(study)).split(os.sep)
    return "/".join(parts[-2:]) if re.fullmatch(r"s\d+", parts[-1]) else parts[-1]


def _s(x, unit=" s"):
    return "-" if x is None else ("%.0f%s" % (x, unit))


def _h(x):
    return "-" if x is None else ("%.1f h" % (x / 3600.0) if x >= 3600 else "%.0f min" % (x / 60.0))


def _load(pair):
    lo, hi = pair
    return "-" if lo is None else ("%.1f" % lo if lo == hi else "%.1f-%.1f" % (lo, hi))


def table(costs):
    """The two Markdown tables: what each study cost, and the cluster estimate."""
    lines = ["| study | particles | preparation: steps | wall | CPU | peak memory | runs | states + probes: steps "
             "| their rows' wall | runs' wall | runs' CPU | peak memory | load | runs (recorded / not) | statics "
             "| statics' peak memory |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for c in costs:
        p = c["preparation"] or {}
        r = c["runs"]
        lines.append("| %s | %s %s | %s | %s | %s | %s | %s | %s | %s | %s | %s%s | %s | %s | %d / %d | %s | %s |" % (
            name(c["study"]), "{:,}".format(c["n"]) if c["n"] else "?", c["assembly"] or "",
            "{:,}".format(p["steps"]) if p.get("steps") else "-", _s(p.get("wall")), _s(p.get("cpu")),
            _s(p.get("peak"), " MB"), p.get("runs") or "-", "{:,} + {:,}".format(c["reach_steps"], c["probe_steps"]), _s(c["rows_wall"]),
            _s(r["wall"]), _s(r["cpu"]), " (master only)" if r["workers_left_out"] else "", _s(r["peak"], " MB"),
            _load(r["load"]), r["recorded"], r["unrecorded"], _s(c["statics"][0]), _s(c["statics"][1], " MB")))
    lines += ["", "| study | paths | one worker (the rows' wall) | 2 workers | one worker a path (the longest) |",
              "|---|---|---|---|---|"]
    for c in costs:
        lines.append("| %s | %d | %s | %s | %s |" % (
            name(c["study"]), len(c["paths"]), _h(sum(c["paths"])),
            _h(makespan(c["paths"], 2)), _h(makespan(c["paths"], None))))
    return "\n".join(lines)


def main(argv=None):
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help"):
        print(__doc__.strip())
        return 0 if argv else 2
    doc = block = None
    studies = []
    try:
        it = iter(argv)
        for a in it:
            if a in ("--doc", "--block"):
                value = next(it, None)
                if value is None:
                    raise ResultsError("%s needs a value" % a)
                doc, block = (value, block) if a == "--doc" else (doc, value)
            elif a.startswith("-"):
                raise ResultsError("unknown option %s (--doc FILE --block NAME)" % a)
            else:
                studies.append(a)
        if not studies:
            raise ResultsError("no study directory given")
        if doc and not block:
            raise ResultsError("--doc needs --block NAME")
        from .seeds import publish
        publish(table([study_cost(s) for s in studies]), doc, block)
    except (ResultsError, OSError, ValueError, KeyError) as exc:
        sys.stderr.write("error: %s\n" % exc)
        return 2
    return 0


if __name__ == "__main__":
    from trueaniso import cli
    cli.tool(main)  # Ctrl-C, a closed pipe: one line, no traceback
