"""What the analysis of a study checks against the study's own metadata.json before it uses a file
of the study: a state's checkpoint (states/ID.npz) and the rows of its probe table (each row
names its study's specimen: a row of another is refused).

run_states.py refuses a checkpoint of another study when it continues one (study._Run.load); the
report's static solve and every analysis of probes.csv apply the same checks here, so that a file
copied in from another study is refused, not solved or fitted as this study's.
"""
import math

from . import study_dir, validate


def checkpoint_problem(study_meta, checkpoint_meta, sid):
    """Why the checkpoint (its specimen-file metadata) is not state `sid` of the study whose
    metadata.json is `study_meta`, or None."""
    found = validate.problem(checkpoint_meta, "checkpoint")
    if found:
        return "%s: %s (not a checkpoint of a state)" % found
    p = checkpoint_meta["parameters"]
    fp = study_meta["fingerprint"]
    state = (study_meta.get("states") or {}).get(str(sid))
    if str(p["state"]) != str(sid):
        return "it is the checkpoint of state %s, not of state %s" % (p["state"], sid)
    if state is None:
        return "this study's metadata.json does not define state %s" % sid
    if p["specimen"] != fp["specimen"]:
        return "it was reached from another specimen (checksum %s..., this study's %s...)" % (p["specimen"][:12],
                                                                                            fp["specimen"][:12])
    if not (_same(p["b"], state["b"]) and _same(p["sigma_z"], state["sigma_z"])):
        return ("it is b = %.12g, sigma_z = %.12g Pa; this study's state %s is b = %.12g, sigma_z = %.12g Pa"
                % (p["b"], p["sigma_z"], sid, state["b"], state["sigma_z"]))
    if p.get("path", "true-triaxial") != fp.get("path", "true-triaxial"):
        return "it is on the %s path, this study on the %s path" % (p.get("path", "true-triaxial"), fp.get("path"))
    if "study" in p and p["study"] != study_dir.states_key(fp):
        return ("it was made by another study (another friction, path rate, thread count or code: the study's "
                "fingerprint differs)")
    return None


def _same(x, y):
    return math.isclose(float(x), float(y), rel_tol=1e-12, abs_tol=0.0)


def _number(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def specimen_problem(study_meta, rows):
    """Why rows of a probe table (dicts of text, line 2 on) are not of this study's specimen, or
    None: a row whose ``specimen`` cell is not the checksum metadata.json records. Rows of two
    studies of the same states, one table, differ only there. A table without the column (an older
    study's) has nothing to compare and passes: a check that refused it would refuse every such study."""
    own = (study_meta.get("fingerprint") or {}).get("specimen")
    if not own:
        return None
    for line, r in enumerate(rows, start=2):
        theirs = r.get("specimen")
        if theirs is not None and theirs != own:
            return ("line %d: state %s probe %s is a row of specimen %s, this study's metadata.json records "
                    "specimen %s (a row of another study?)" % (line, r.get("state"), r.get("probe"),
                                                              theirs or "(empty)", own))
    return None


def mixed_specimens_problem(rows):
    """Why rows of a probe table are not of one specimen, or None: rows whose ``specimen`` cells name
    two checksums (a table copied or renamed away from its metadata.json, whose rows have nothing
    else to be compared with). Rows without the column pass."""
    first = None
    for line, r in enumerate(rows, start=2):
        theirs = r.get("specimen")
        if theirs is None:
            continue
        if first is None:
            first = (line, theirs)
        elif theirs != first[1]:
            return ("line %d names specimen %s, line %d specimen %s: rows of two studies in one table"
                    % (line, theirs or "(empty)", first[0], first[1] or "(empty)"))
    return None


def rows_problem(study_meta, rows):
    """Why rows of a probe table (dicts of text, line 2 on) are not this study's, or None: a row of
    another specimen (specimen_problem), a state its metadata.json does not define, a row whose b or
    sigma_z goal is not the state's definition, a row on another loading path."""
    found = specimen_problem(study_meta, rows)
    if found:
        return found
    if "states" not in study_meta:  # a metadata.json made by hand without them: nothing to check against
        return None
    states = study_meta["states"]
    path = (study_meta.get("fingerprint") or {}).get("path")
    strange = []
    for line, r in enumerate(rows, start=2):
        sid = str(r.get("state"))
        d = states.get(sid)
        if d is None:
            value = _number(sid)  # '1.0' written by a spreadsheet is state 1
            if value is not None and value.is_integer():
                d = states.get(str(int(value)))
        if d is None:
            strange.append((line, sid))
            continue
        for column, key in (("b", "b"), ("sigma_z_goal", "sigma_z")):
            v = _number(r.get(column))
            if r.get(column) not in (None, "") and v is not None and math.isfinite(v) and not _same(v, d[key]):
                return ("line %d: state %s has %s = %s, but this study defines it with %s = %.12g (a row of another "
                        "study?)" % (line, sid, column, r[column], key, d[key]))
        if path and r.get("path") not in (None, "") and r["path"] != path:
            return "line %d: state %s is on the %s path, this study on the %s path" % (line, sid, r["path"], path)
    if strange:
        ids = sorted({s for _, s in strange}, key=lambda s: (not s.isdigit(), int(s) if s.isdigit() else 0, s))
        return ("rows of state%s %s (line %d%s) that this study's metadata.json does not define (rows of another "
                "study?)" % ("" if len(ids) == 1 else "s", ", ".join(ids[:8]) + (" ..." if len(ids) > 8 else ""),
                            strange[0][0], " and more" if len(strange) > 1 else ""))
    return None
