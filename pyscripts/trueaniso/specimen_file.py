"""Versioned specimen files: one .npz holding the whole mechanical state and its provenance.

Layout (format "trueaniso-specimen", version 1): arrays for bodies, member spheres, cell and
contact history (the tangential forces matter: a probe starts from them), plus a JSON string
``meta`` with material, seed, preparation parameters, the state summary, software versions
and a SHA-256 of the arrays. Loading checks format, version, shapes and checksum before
building anything, and refuses a file that fails any check with one clear message.
"""
import hashlib
import json
import os
import platform
import time
import zipfile

import numpy as np

from . import FORMAT_VERSION, __version__, atomic, engines

FORMAT = "trueaniso-specimen"
_ARRAYS = ("positions", "velocities", "angular_velocities", "orientations", "masses", "inertia",
           "member_begin", "member_body", "member_offsets", "radii", "cell", "cell_ref",
           "velocity_gradient", "c_member1", "c_member2", "c_shift", "c_normal", "c_normal_force",
           "c_shear_force")


class SpecimenFileError(ValueError):
    pass


def _checksum(arrays):
    h = hashlib.sha256()
    for name in _ARRAYS:
        a = np.ascontiguousarray(arrays[name])
        h.update(name.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def scene_arrays(scene):
    c = scene.contact_arrays()
    active = c["normal_force"] > 0
    return dict(
        positions=scene.positions, velocities=scene.velocities,
        angular_velocities=scene.angular_velocities, orientations=scene.orientations,
        masses=scene.masses, inertia=scene.inertia, member_begin=scene.member_begin,
        member_body=scene.member_body, member_offsets=scene.member_offsets, radii=scene.radii,
        cell=scene.cell, cell_ref=scene.cell_ref, velocity_gradient=scene.velocity_gradient,
        c_member1=c["member1"][active], c_member2=c["member2"][active], c_shift=c["shift"][active],
        c_normal=c["normal"][active], c_normal_force=c["normal_force"][active],
        c_shear_force=c["shear_force"][active])


def _git_commit():
    """The source commit (with '+dirty' for local edits), or None outside a git checkout."""
    import subprocess
    top = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    try:
        head = subprocess.run(["git", "-C", top, "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", top, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return (head + ("+dirty" if dirty else "")) if head else None


def versions():
    """What produced a result: code, interpreter, libraries, machine and engine threads."""
    import sys
    out = dict(trueaniso=__version__, git=_git_commit(), python=platform.python_version(),
               numpy=np.__version__, machine=platform.machine(), threads=engines.threads())
    if "yade" in sys.modules:
        try:
            out["yade"] = sys.modules["yade"].config.version
        except AttributeError:
            out["yade"] = "unknown"
    return out


def save(path, scene, seed=None, parameters=None, summary=None):
    """Write a specimen atomically (an existing file is replaced only by a complete new one)."""
    arrays = scene_arrays(scene)
    problem = contents_problem(arrays)
    if problem:
        raise SpecimenFileError("refusing to save %s: %s" % (path, problem))
    meta = dict(format=FORMAT, format_version=FORMAT_VERSION, created=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                seed=seed, parameters=parameters or {}, summary=summary or {}, versions=versions(),
                material=dict(shear_modulus=scene.shear_modulus, poisson=scene.poisson,
                              density=scene.density, friction=scene.friction),
                dt=scene.dt, time=scene.time, step=scene.step, block_rotations=scene.block_rotations,
                sha256=_checksum(arrays))
    with atomic.atomic_open(path, "wb") as f:
        np.savez(f, meta=np.array(json.dumps(meta, default=atomic._jsonable)), **arrays)
    return meta


def read(path):
    """(arrays, meta) after every check; raises SpecimenFileError."""
    if not os.path.isfile(path):
        raise SpecimenFileError("specimen file not found: %s" % path)
    try:
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
    except (zipfile.BadZipFile, ValueError, OSError, EOFError, KeyError) as exc:
        raise SpecimenFileError("corrupt specimen file %s (%s)" % (path, exc)) from None
    except Exception as exc:  # zlib and other decoder errors of a damaged member
        raise SpecimenFileError("corrupt specimen file %s (%s)" % (path, exc)) from None
    if "meta" not in data:
        raise SpecimenFileError("%s is not a trueaniso specimen (no metadata)" % path)
    try:
        meta = json.loads(str(data.pop("meta")))
    except json.JSONDecodeError:
        raise SpecimenFileError("corrupt specimen file %s (metadata unreadable)" % path) from None
    if meta.get("format") != FORMAT:
        raise SpecimenFileError("%s is not a trueaniso specimen (format %r)" % (path, meta.get("format")))
    if meta.get("format_version") != FORMAT_VERSION:
        raise SpecimenFileError("%s has specimen format version %r; this trueaniso reads version %d"
                                % (path, meta.get("format_version"), FORMAT_VERSION))
    missing = [k for k in _ARRAYS if k not in data]
    if missing:
        raise SpecimenFileError("corrupt specimen file %s (missing arrays: %s)" % (path, ", ".join(missing)))
    if _checksum(data) != meta.get("sha256"):
        raise SpecimenFileError("corrupt specimen file %s (checksum mismatch)" % path)
    problem = contents_problem(data)
    if problem:
        raise SpecimenFileError("invalid specimen file %s (%s)" % (path, problem))
    return data, meta


def contents_problem(a):
    """What makes the arrays unusable as a scene, or None. The checksum only proves the file is
    the one written; this proves what was written can be simulated (save() runs it too)."""
    nb = a["positions"].shape[0]
    if nb == 0:
        return "no bodies"
    mb = np.asarray(a["member_begin"])
    if a["positions"].shape != (nb, 3) or mb.shape != (nb + 1,) or mb[0] != 0 or np.any(np.diff(mb) < 1):
        return "inconsistent body/member arrays"
    nm = int(mb[-1])
    if a["radii"].shape != (nm,) or a["member_body"].shape != (nm,) or a["member_offsets"].shape != (nm, 3):
        return "inconsistent body/member arrays"
    for name in ("positions", "velocities", "angular_velocities", "masses", "radii", "cell", "cell_ref",
                 "velocity_gradient", "member_offsets", "c_normal_force", "c_shear_force"):
        if not np.all(np.isfinite(a[name])):
            return "non-finite values in %s" % name
    if np.any(a["radii"] <= 0):
        return "radius <= 0"
    if np.any(a["masses"] <= 0):
        return "mass <= 0"
    problem = cell_problem(a)
    if problem:
        return problem
    nc = a["c_member1"].shape[0]
    for name in ("c_member1", "c_member2"):
        m = a[name]
        if m.shape != (nc,) or (nc and (m.min() < 0 or m.max() >= nm)):
            return "contact member index out of range"
    return None


def cell_problem(a):
    """What makes the saved cell unusable (its shapes; a singular or inverted matrix), or None."""
    for name in ("cell", "cell_ref", "velocity_gradient"):
        if np.shape(a[name]) != (3, 3):
            return "%s must be a 3x3 matrix" % name
    for name in ("cell", "cell_ref"):
        h = np.asarray(a[name], dtype=float)
        scale = np.prod(np.linalg.norm(h, axis=0))
        if not scale > 0 or np.linalg.det(h) <= 1e-6 * scale:
            return "%s is a singular or inverted cell matrix (det %.3g)" % (name, np.linalg.det(h))
    return None


def load(path):
    """A Scene with the saved state (contact history included) and the metadata."""
    a, meta = read(path)
    nb = a["positions"].shape[0]
    mb = a["member_begin"]
    if mb.shape != (nb + 1,) or a["radii"].shape[0] != mb[-1]:
        raise SpecimenFileError("corrupt specimen file %s (inconsistent body/member arrays)" % path)
    s = engines.Scene()
    m = meta["material"]
    s.shear_modulus, s.poisson, s.friction = m["shear_modulus"], m["poisson"], m["friction"]
    s.density = m["density"]
    s.cell = a["cell"]
    s.cell_ref = a["cell_ref"]
    if np.all(np.diff(mb) == 1):
        s.add_spheres(a["positions"], a["radii"])
    else:
        for b in range(nb):
            k = slice(mb[b], mb[b + 1])
            s.add_clump(a["positions"][b], a["orientations"][b], a["member_offsets"][k], a["radii"][k],
                        float(a["masses"][b]), a["inertia"][b])
    s.orientations = a["orientations"]
    s.velocities = a["velocities"]
    s.angular_velocities = a["angular_velocities"]
    s.velocity_gradient = a["velocity_gradient"]
    s.set_contact_history(a["c_member1"], a["c_member2"], a["c_shift"], a["c_normal"],
                          a["c_normal_force"], a["c_shear_force"])
    s.dt, s.time, s.step = meta["dt"], meta["time"], meta["step"]
    s.block_rotations = meta["block_rotations"]
    if not np.allclose(s.masses, a["masses"], rtol=1e-12):
        raise SpecimenFileError("corrupt specimen file %s (masses disagree with radii and density)" % path)
    from . import dem
    dem.refresh(s)  # contact forces, normals and branches for the loaded positions
    return s, meta
