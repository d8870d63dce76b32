"""Runs true-triaxial states and their probes on a specimen, with results written as they come.

Layout of an output directory:
  probes.csv       one row per state and probe direction (written atomically after each state)
  metadata.json    versions, specimen provenance, parameters
  states/ID.npz    the specimen held at state ID (a checkpoint: a resumed run continues the
                   path from the furthest state already reached)
Rows already in probes.csv are not run again, so an interrupted study resumes where it stopped.
"""
import csv
import os
import time

import numpy as np

from . import atomic, engines, fabric, specimen, specimen_file, triaxial
from .triaxial import AXES

COLUMNS = ["state", "b", "sigma_z_goal", "sigma_x", "sigma_y", "sigma_z", "q", "probe", "sign",
           "d_sigma_x", "d_sigma_y", "d_sigma_z", "d_eps_x", "d_eps_y", "d_eps_z", "E", "nu_1", "nu_2",
           "nu_1_name", "nu_2_name", "gamma", "Zm", "void_ratio", "rotations", "detection", "damping",
           "probe_steps", "probe_wall_time", "state_steps", "state_wall_time"]


def read_rows(path):
    if not os.path.exists(path):
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def _extra_columns(scene):
    """Micro-structure columns (Zm, R, H, B, Nc/V, ...) of the held state."""
    return fabric.fabric_row(scene)


def run_states(specimen_path, states, out, probes=(2, 0, 1), gamma=1e-6, restrain_rotations=False,
               skip_detection=False, damping=0.4, log=print, state_options=None, probe_options=None):
    """states: [(id, b, sigma_z)]; ids name the rows and checkpoints (Table C1 numbering or any)."""
    for i, b, sz in states:
        triaxial.validate_state(b, sz)  # every state checked before any work
    probes = [triaxial.validate_probe(a, gamma) for a in probes]
    if len(set(probes)) != len(probes):
        raise ValueError("each probe axis may be given once")
    base, meta = specimen_file.load(specimen_path)
    os.makedirs(os.path.join(out, "states"), exist_ok=True)
    csv_path = os.path.join(out, "probes.csv")
    rows = read_rows(csv_path)
    done = {(r["state"], r["probe"]) for r in rows}
    columns = list(COLUMNS)
    atomic.write_json(os.path.join(out, "metadata.json"), dict(
        specimen=os.path.abspath(specimen_path), specimen_sha256=meta["sha256"], specimen_seed=meta["seed"],
        specimen_summary=meta.get("summary"), versions=specimen_file.versions(),
        parameters=dict(gamma=gamma, restrain_rotations=restrain_rotations, skip_detection=skip_detection,
                        damping=damping, probes="".join(AXES[a] for a in probes),
                        state_options=_effective(triaxial.reach_state, state_options),
                        probe_options=_effective(triaxial.probe, probe_options)),
        states=[dict(id=i, b=b, sigma_z=sz) for i, b, sz in states]))

    for (b, side), path in sorted(triaxial.paths(states).items(), key=lambda kv: (kv[0][1] != 0, kv[0])):
        scene = None
        for sid, bb, sz in path:
            want = [AXES[a] for a in probes if (str(sid), AXES[a]) not in done]
            ck = os.path.join(out, "states", "%s.npz" % sid)
            if not want and os.path.exists(ck):
                scene = None  # the next state of the path will load this checkpoint
                continue
            t0 = time.time()
            info = dict(steps=0, wall_time=0.0)
            if os.path.exists(ck):
                scene, _ = specimen_file.load(ck)
                log("state %s: checkpoint %s" % (sid, ck))
            else:
                if scene is None:
                    scene = _start_of_path(base, path, sid, out)
                log("state %s: b = %.2f, sigma_z = %.1f kPa ..." % (sid, bb, sz / 1e3))
                info = triaxial.reach_state(scene, bb, sz, damping=damping, **(state_options or {}))
                specimen_file.save(ck, scene, seed=meta["seed"], parameters=dict(state=sid, b=bb, sigma_z=sz),
                                   summary=specimen.state(scene))
                log("state %s: reached in %d steps (%.1f s)" % (sid, info["steps"], info["wall_time"]))
            hold = engines.true_triaxial_stresses(bb, sz)
            st = specimen.state(scene)
            extra = _extra_columns(scene)
            for name in want:
                r = triaxial.probe(scene, hold, name, gamma=gamma, restrain_rotations=restrain_rotations,
                                   skip_detection=skip_detection, damping=damping, **(probe_options or {}))
                nus = sorted(k for k in r if k.startswith("nu_"))
                row = dict(state=sid, b=bb, sigma_z_goal=sz, sigma_x=st["sigma_x"], sigma_y=st["sigma_y"],
                           sigma_z=st["sigma_z"], q=engines.deviatoric_q(bb, sz), probe=name, sign=r["sign"],
                           d_sigma_x=r["d_stress"][0], d_sigma_y=r["d_stress"][1], d_sigma_z=r["d_stress"][2],
                           d_eps_x=r["d_strain"][0], d_eps_y=r["d_strain"][1], d_eps_z=r["d_strain"][2],
                           E=r["E"], nu_1=r[nus[0]], nu_2=r[nus[1]], nu_1_name=nus[0], nu_2_name=nus[1],
                           gamma=r["gamma"], Zm=st["Zm"], void_ratio=st["void_ratio"], rotations=r["rotations"],
                           detection=r["detection"], damping=damping, probe_steps=r["steps"],
                           probe_wall_time=r["wall_time"], state_steps=info["steps"],
                           state_wall_time=info["wall_time"])
                row.update(extra)
                for k in extra:
                    if k not in columns:
                        columns.append(k)
                rows.append(row)
                done.add((str(sid), name))
                log("state %s: probe %s  E = %.1f MPa  %s = %.4f  %s = %.4f  (%d steps, %.1f s)"
                    % (sid, name, r["E"] / 1e6, nus[0], r[nus[0]], nus[1], r[nus[1]], r["steps"], r["wall_time"]))
                atomic.write_csv(csv_path, rows, columns)
            log("state %s: done (%.1f s)" % (sid, time.time() - t0))
    return rows


def _effective(function, options):
    """The keyword values a protocol really runs with: its defaults, overridden by options, so
    the metadata states the tolerances (stress, unbalanced force, steps) behind every row."""
    import inspect
    skip = {"scene", "hold", "axis", "sign", "gamma", "b", "sigma_z", "progress", "restrain_rotations",
            "skip_detection", "damping"}
    out = {k: p.default for k, p in inspect.signature(function).parameters.items()
           if p.default is not inspect.Parameter.empty and k not in skip}
    out.update(options or {})
    return out


def _start_of_path(base, path, sid, out):
    """The scene to continue a path from: the last checkpoint before sid, else the specimen."""
    prev = None
    for s, _, _ in path:
        if str(s) == str(sid):
            break
        ck = os.path.join(out, "states", "%s.npz" % s)
        if os.path.exists(ck):
            prev = ck
    if prev:
        scene, _ = specimen_file.load(prev)
        return scene
    return base.copy()


def parse_states(text):
    """'b:sigma_z,b:sigma_z' (sigma_z in Pa) -> [(id, b, sigma_z)], ids 's1', 's2', ..."""
    out = []
    for k, item in enumerate(t for t in text.split(",") if t.strip()):
        try:
            b, sz = (float(v) for v in item.split(":"))
        except ValueError:
            raise ValueError("state %r: expected b:sigma_z, e.g. 0.5:140e3" % item) from None
        out.append(("s%d" % (k + 1), b, sz))
    if not out:
        raise ValueError("no states given")
    return out


def table_states(ids=None):
    states = triaxial.table_c1_states()
    if ids:
        want = set(ids)
        unknown = want - {i for i, _, _ in states}
        if unknown:
            raise ValueError("Table C1 has states 1-39; unknown: %s" % sorted(unknown))
        states = [s for s in states if s[0] in want]
    return states
