r"""Versioned specimen files: one .npz holding the whole mechanical state and its provenance.

Layout (format "trueaniso-specimen", version 4): arrays for bodies, member spheres, cell (the
3x3 matrix hSize whose columns are the cell vectors, its reference and the velocity gradient) and
contact history (the tangential forces matter: a probe starts from them), plus a JSON string
``meta`` with material, time step, rotation blocking, seed, preparation parameters, the state
summary and software versions. ``meta["sha256"]`` is a SHA-256 of the whole content: every array
(name, dtype, shape, bytes) and every other metadata field, so an edited material or
``block_rotations`` fails the check just as an edited radius does.

A clump is a body with several members: ``member_offsets`` (its principal frame) and ``radii`` are
its template scaled to its size, ``masses`` and ``inertia`` its mass and principal moments, and
``volumes`` its solid volume (the void ratio's). The volume is stored, not recomputed on load, so
that every process that loads the file gets the same bits: the union of the members (by CGAL,
cached once per shape) rounds differently with the clump of the shape a process meets first, and a
resumed study's void ratios would differ from an uninterrupted run's. A stored volume is checked
against the union (1e-9) and a sphere's against $\frac{4}{3}\pi r^3$; a sphere's volume is computed
from its radius. A version-3 file (no volumes) is read with the union's volumes. A clump whose
members do not overlap into one body is refused like any other invalid field.

Loading checks format, version, checksum, then every field (``meta_problem``, ``contents_problem``,
and after the scene is built ``contacts_problem``) before anything is simulated, and refuses a
file that fails any check with one line naming the field. Version-1 files (whose checksum left the
metadata out) are refused with the way out: prepare the specimen again. Version-2 files (an
orthorhombic cell stored as three edge lengths) are read, their checksum verified over the arrays
they hold, and their cell turned into the diagonal matrix.

A specimen written by prepare_specimen.py has a ``.json`` summary beside it, derived from the
``.npz`` (``write_summary``); a missing one is written again from the ``.npz`` (``ensure_summary``),
so a run killed between the two writes loses nothing.
"""
import hashlib
import json
import math
import os
import time
import zipfile

import numpy as np

from . import FORMAT_VERSION, atomic, derived, engines, validate
from .provenance import versions

FORMAT = "trueaniso-specimen"
_ARRAYS_V3 = ("positions", "velocities", "angular_velocities", "orientations", "masses", "inertia",
              "member_begin", "member_body", "member_offsets", "radii", "cell", "cell_ref",
              "velocity_gradient", "c_member1", "c_member2", "c_shift", "c_normal", "c_normal_force",
              "c_shear_force")
_ARRAYS = _ARRAYS_V3 + ("volumes",)  # version 4: each body's solid volume (module doc)
_VOLUME_TOLERANCE = 1e-9  # stored against recomputed volume: rounding is 1e-15, a wrong file 1e-3 and more
# Version 2 stored an orthorhombic cell: its edge lengths, reference lengths and diagonal strain
# rates. Such a file is still read (its checksum over these names), as the diagonal matrices.
# Rolling resistance (docs/rolling.md): a scene with it on also stores its rolling moments, and
# its material names beta and eta_r; a scene without it is written exactly as before.
_ROLLING = "c_rolling_moment"
_ARRAYS_V2 = tuple({"cell": "cell_size", "cell_ref": "cell_ref_size", "velocity_gradient": "strain_rate"}.get(k, k)
                   for k in _ARRAYS_V3)


__all__ = ["load", "save", "read", "SpecimenFileError"]


class SpecimenFileError(ValueError):
    """A specimen file that cannot be read or does not pass its checks; the message names why."""


def _canonical_meta(meta):
    """The metadata as hashed: every field but the checksum itself, in one canonical JSON text
    (sorted keys; floats as Python writes them, which round-trip exactly)."""
    rest = {k: v for k, v in meta.items() if k != "sha256"}
    return json.dumps(json.loads(json.dumps(rest, default=atomic._jsonable)), sort_keys=True,
                      separators=(",", ":")).encode()


def _checksum(arrays, meta, names=_ARRAYS):
    h = hashlib.sha256()
    for name in names:
        a = np.ascontiguousarray(arrays[name])
        h.update(name.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(b"meta")
    h.update(_canonical_meta(meta))
    return h.hexdigest()


def _rolling(material):
    return material.get("rolling_stiffness", 0.0) > 0


def _names(meta):
    """The arrays a file of this metadata holds (and its checksum covers)."""
    names = {2: _ARRAYS_V2, 3: _ARRAYS_V3}.get(meta.get("format_version"), _ARRAYS)
    m = meta.get("material")
    return names + (_ROLLING,) if isinstance(m, dict) and _number(m.get("rolling_stiffness", 0.0), 0) and \
        _rolling(m) else names


def scene_arrays(scene):
    c = scene.contact_arrays()
    active = c["normal_force"] > 0
    rolling = {_ROLLING: c["rolling_moment"][active]} if scene.rolling_stiffness > 0 else {}
    return dict(**rolling,
        positions=scene.positions, velocities=scene.velocities,
        angular_velocities=scene.angular_velocities, orientations=scene.orientations,
        masses=scene.masses, inertia=scene.inertia, volumes=scene.volumes, member_begin=scene.member_begin,
        member_body=scene.member_body, member_offsets=scene.member_offsets, radii=scene.radii,
        cell=scene.cell, cell_ref=scene.cell_ref, velocity_gradient=scene.velocity_gradient,
        c_member1=c["member1"][active], c_member2=c["member2"][active], c_shift=c["shift"][active],
        c_normal=c["normal"][active], c_normal_force=c["normal_force"][active],
        c_shear_force=c["shear_force"][active])


def save(path, scene, seed=None, parameters=None, summary=None):
    """Write a scene as a specimen file, atomically: an existing file is replaced only by a complete new one.

    Args:
        path: the .npz to write.
        scene: the engines' Scene, at rest at its state.
        seed: the seed it was made with (recorded; None: not known).
        parameters: how it was made (recorded as given, e.g. the log of `specimen.prepare_spheres`).
        summary: what it is (recorded as given, e.g. `specimen.state`).

    Returns:
        dict: the metadata written, its ``sha256`` the checksum of the whole content.

    Raises:
        SpecimenFileError: a scene that could not be simulated again once read (its arrays or
            metadata fail the checks `load` makes); nothing is written.

    Example:
        >>> import os, tempfile
        >>> from trueaniso import specimen_file
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> path = os.path.join(tempfile.mkdtemp(), "copy.npz")
        >>> written = specimen_file.save(path, scene, seed=meta["seed"])
        >>> specimen_file.load(path)[0].num_bodies
        150
    """
    arrays = scene_arrays(scene)
    problem = contents_problem(arrays)
    if problem:
        raise SpecimenFileError("refusing to save %s: %s" % (path, problem))
    meta = dict(format=FORMAT, format_version=FORMAT_VERSION, created=time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                seed=seed, parameters=parameters or {}, summary=summary or {}, versions=versions(),
                material=dict(shear_modulus=scene.shear_modulus, poisson=scene.poisson,
                              density=scene.density, friction=scene.friction,
                              **(dict(rolling_stiffness=scene.rolling_stiffness, rolling_friction=scene.rolling_friction)
                                 if scene.rolling_stiffness > 0 else {})),
                dt=scene.dt, time=scene.time, step=scene.step, block_rotations=bool(scene.block_rotations),
                # Stored where it is not dt itself (a longer step than the reference rule's), so a
                # file made under the reference rule is the same bytes with or without the field.
                **({} if scene.reference_dt in (0.0, scene.dt) else dict(reference_dt=scene.reference_dt)))
    problem = meta_problem(json.loads(json.dumps(meta, default=atomic._jsonable)))
    if problem:
        raise SpecimenFileError("refusing to save %s: %s" % (path, problem))
    meta["sha256"] = _checksum(arrays, meta, _names(meta))
    with atomic.atomic_open(path, "wb") as f:
        np.savez(f, meta=np.array(json.dumps(meta, default=atomic._jsonable)), **arrays)
    return meta


def read(path):
    """The arrays and metadata of a specimen file, after every check (module doc), without a scene.

    Returns:
        (arrays, meta): dict of numpy arrays by name, and the metadata dict.

    Raises:
        SpecimenFileError: a missing, unreadable or corrupt file, or one that fails a check, with one
            line naming the field.

    Example:
        >>> from trueaniso import specimen_file
        >>> arrays, meta = specimen_file.read("tests/data/spheres-150-s4.npz")
        >>> arrays["positions"].shape, meta["format_version"]
        ((150, 3), 4)
    """
    if os.path.isdir(path):
        raise SpecimenFileError("%s is a directory, not a specimen file (.npz)" % path)
    if not os.path.isfile(path):
        raise SpecimenFileError("specimen file not found: %s" % path)
    # An .npz is a zip archive; np.load reads anything else as a pickle it then refuses ("Cannot
    # load file containing pickled data"), which named the wrong problem.
    try:
        with open(path, "rb") as f:
            magic = f.read(4)
    except OSError as exc:
        raise SpecimenFileError("cannot read specimen file %s (%s)" % (path, exc.strerror)) from None
    if magic != b"PK\x03\x04":
        raise SpecimenFileError("%s is not a specimen file (.npz, a zip archive)%s"
                                % (path, ": it is empty" if not magic else ""))
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
    if not isinstance(meta, dict):
        raise SpecimenFileError("%s: metadata: must be a table (JSON object), not %s" % (path, type(meta).__name__))
    if meta.get("format") != FORMAT:
        raise SpecimenFileError("%s is not a trueaniso specimen (format %r)" % (path, meta.get("format")))
    if meta.get("format_version") == 1:
        raise SpecimenFileError("%s is a version-1 specimen file, whose checksum leaves its metadata (material, "
                                "time step, rotation blocking) unchecked; prepare the specimen again with this "
                                "trueaniso (prepare_specimen.py --force)" % path)
    if meta.get("format_version") not in (2, 3, FORMAT_VERSION):
        raise SpecimenFileError("%s has specimen format version %r; this trueaniso reads versions 2 to %d"
                                % (path, meta.get("format_version"), FORMAT_VERSION))
    names = _names(meta)
    missing = [k for k in names if k not in data]
    if missing:
        raise SpecimenFileError("corrupt specimen file %s (missing arrays: %s)" % (path, ", ".join(missing)))
    if _ROLLING in data and _ROLLING not in names:  # not covered by the checksum: never trusted
        raise SpecimenFileError("corrupt specimen file %s (rolling moments stored, but its material has no rolling "
                                "resistance)" % path)
    if "volumes" in data and "volumes" not in names:  # likewise: a version-3 file holds none
        raise SpecimenFileError("corrupt specimen file %s (volumes stored in a version-%s file, which has none)"
                                % (path, meta.get("format_version")))
    if not isinstance(meta.get("sha256"), str) or _checksum(data, meta, names) != meta["sha256"]:
        raise SpecimenFileError("corrupt specimen file %s (checksum mismatch: arrays or metadata were changed "
                                "after it was written)" % path)
    validate.check(meta, "specimen", path, SpecimenFileError)
    found = validate.arrays_problem(data)
    if found:
        raise SpecimenFileError("%s: %s: %s" % (path, *found))
    if meta["format_version"] == 2:
        for new, old in (("cell", "cell_size"), ("cell_ref", "cell_ref_size"), ("velocity_gradient", "strain_rate")):
            v = np.asarray(data.pop(old))
            data[new] = np.diag(v) if v.shape == (3,) else v  # a wrong shape is named by contents_problem
    problem = (meta_problem(meta) or contents_problem(data) or derived.clump_problem(data, meta)
               or derived.recipe_problem(meta) or volumes_problem(data))
    if problem:
        raise SpecimenFileError("invalid specimen file %s (%s)" % (path, problem))
    return data, meta


# The clumps' members and volumes already checked in this process, by their bytes: a study reads
# its specimen again at every state and probe, with the same members (4000 clumps: 27 ms a read).
_VOLUMES_CHECKED = {}


def volumes_problem(a):
    """A stored clump volume that disagrees with its members' union (CGAL, cached once per shape),
    or None. Checked when a file is read, so that a study refuses such a specimen before it writes
    anything, not when the scene is built, after the study has begun."""
    if "volumes" not in a:
        return None
    digest = hashlib.sha256()
    for name in ("member_begin", "member_offsets", "radii", "volumes"):
        x = np.ascontiguousarray(a[name])
        digest.update(repr((name, x.dtype.str, x.shape)).encode())
        digest.update(x.tobytes())
    key = digest.hexdigest()
    if key not in _VOLUMES_CHECKED:
        _VOLUMES_CHECKED[key] = _volumes_problem(a)
    return _VOLUMES_CHECKED[key]


def _volumes_problem(a):
    mb = a["member_begin"]
    for b in np.flatnonzero(np.diff(mb) > 1):
        k = slice(mb[b], mb[b + 1])
        try:
            union = engines.clump_volume(a["member_offsets"][k], a["radii"][k])
        except (ValueError, RuntimeError) as exc:
            return "body %d: %s" % (b, exc)
        if abs(a["volumes"][b] / union - 1) > _VOLUME_TOLERANCE:
            return "body %d: its volume %.17g disagrees with its members' union %.17g" % (b, a["volumes"][b], union)
    return None


def _number(x, low=-math.inf, high=math.inf, low_open=False, high_open=False):
    """Whether x is a finite real number (not a bool) within the bounds."""
    if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
        return False
    return (x > low if low_open else x >= low) and (x < high if high_open else x <= high)


def meta_problem(meta):
    """What makes the metadata unusable, or None: the first field that does not fit
    schemas/specimen.schema.json, as 'field: what' (a metadata not yet sealed is checked as if it
    were)."""
    if not isinstance(meta, dict):
        return "metadata: must be a table (JSON object)"
    found = validate.problem(dict(meta, sha256=meta.get("sha256", "0" * 64)), "specimen")
    return "%s: %s" % found if found else None


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
    if not np.array_equal(a["member_body"], np.repeat(np.arange(nb), np.diff(mb))):
        return "inconsistent body/member arrays (member_body does not follow member_begin)"
    shapes = dict(velocities=(nb, 3), angular_velocities=(nb, 3), orientations=(nb, 4), masses=(nb,),
                  inertia=(nb, 3), **({"volumes": (nb,)} if "volumes" in a else {}))
    for name, shape in shapes.items():
        if a[name].shape != shape:
            return "%s has shape %s, not %s" % (name, a[name].shape, shape)
    problem = cell_problem(a)
    if problem:
        return problem
    for name in ("positions", "velocities", "angular_velocities", "orientations", "masses", "inertia", "radii",
                 "member_offsets", "c_normal", "c_normal_force", "c_shear_force",
                 *((_ROLLING,) if _ROLLING in a else ()), *(("volumes",) if "volumes" in a else ())):
        problem = _float_problem(a[name], name)
        if problem:
            return problem
    if np.any(a["radii"] <= 0):
        return "radius <= 0"
    if np.any(a["masses"] <= 0):
        return "mass <= 0"
    if np.any(a["inertia"] <= 0):
        return "moment of inertia <= 0"
    if "volumes" in a:
        v = a["volumes"]
        if np.any(v <= 0):
            return "volume <= 0"
        single = np.diff(mb) == 1
        r = a["radii"][mb[:-1][single]]
        if np.any(np.abs(v[single] / (4.0 / 3.0 * np.pi * r ** 3) - 1) > _VOLUME_TOLERANCE):
            return "a sphere's volume disagrees with its radius"
    if np.any(np.abs(np.linalg.norm(a["orientations"], axis=1) - 1) > 1e-6):
        return "orientations are not unit quaternions"
    problem = clump_members_problem(a["member_begin"], a["member_offsets"], a["radii"])
    if problem:
        return problem
    # Two bodies at one place (a copied body): their contact has no normal. Compared in the cell's
    # reduced coordinates (wrapped into [0, 1)), so that periodic images count as one place.
    r_min = float(a["radii"].min())
    h = np.asarray(a["cell"], dtype=float)
    wrapped = np.mod(a["positions"] @ np.linalg.inv(h).T, 1.0) @ h.T
    key = np.round(wrapped / (1e-6 * r_min))
    if len(np.unique(key, axis=0)) != nb:
        return "duplicate bodies (two bodies at the same place)"
    nc = a["c_member1"].shape[0]
    shapes = dict(c_member2=(nc,), c_shift=(nc, 3), c_normal=(nc, 3), c_normal_force=(nc,), c_shear_force=(nc, 3))
    if _ROLLING in a:
        shapes[_ROLLING] = (nc, 3)
    for name, shape in shapes.items():
        if a[name].shape != shape:
            return "contact arrays of different lengths (%s has shape %s, not %s)" % (name, a[name].shape, shape)
    for name in ("c_member1", "c_member2", "c_shift"):
        if not np.issubdtype(a[name].dtype, np.integer):
            return "%s must hold integers" % name
    for name in ("c_member1", "c_member2"):
        m = a[name]
        if nc and (m.min() < 0 or m.max() >= nm):
            return "contact member index out of range"
    if nc == 0:
        return None
    body = a["member_body"]
    if np.any(body[a["c_member1"]] == body[a["c_member2"]]):
        return "a contact of a body with itself"
    if np.any(a["c_normal_force"] <= 0):
        return "a contact with normal force <= 0 (only active contacts are saved)"
    if np.any(np.abs(np.linalg.norm(a["c_normal"], axis=1) - 1) > 1e-6):
        return "contact normals are not unit vectors"
    lo = np.minimum(a["c_member1"], a["c_member2"])
    hi = np.maximum(a["c_member1"], a["c_member2"])
    sign = np.where(a["c_member1"] <= a["c_member2"], 1, -1)[:, None]
    pairs = np.column_stack([lo, hi, sign * a["c_shift"]])
    if len(np.unique(pairs, axis=0)) != nc:
        return "a contact listed twice"
    return None


def clump_members_problem(member_begin, offsets, radii):
    """A clump whose members are not one rigid body, or None. Each clump's member balls must
    overlap (strictly) into one connected union, as the engines' ClumpTemplate demands; checked
    here too so that a file is refused as a whole, naming the body, before a scene is built. The
    clumps of one member count are checked together, as arrays (a study reads its specimen
    again at every state and probe: a loop over 4000 clumps took 0.2 s a read)."""
    mb = np.asarray(member_begin)
    count = np.diff(mb)
    offsets, radii = np.asarray(offsets), np.asarray(radii)
    first = None
    for k in np.unique(count[count > 1]):
        bodies = np.flatnonzero(count == k)
        members = mb[bodies][:, None] + np.arange(k)  # (clumps, k)
        o, r = offsets[members], radii[members]
        gap = np.linalg.norm(o[:, :, None, :] - o[:, None, :, :], axis=3)
        touch = gap < r[:, :, None] + r[:, None, :]
        seen = np.zeros(r.shape, bool)
        seen[:, 0] = True
        for _ in range(k):
            seen = seen | np.any(touch & seen[:, :, None], axis=1)
        apart = np.flatnonzero(~seen.all(axis=1))
        if apart.size and (first is None or bodies[apart[0]] < first[0]):
            first = (bodies[apart[0]], seen[apart[0]])
    if first is None:
        return None
    b, seen = first
    return ("clump %d: its %d members do not overlap into one body (members %s touch no other)"
            % (b, len(seen), np.flatnonzero(~seen).tolist()))


def contacts_problem(scene, a):
    """Saved contacts whose members do not touch with the saved periodic shift (an absurd shift,
    or edited positions): an active contact overlaps, so its centre distance is below r1 + r2;
    1.1 (r1 + r2) leaves room for the last step's motion, and a shift wrong by one cell puts the
    members at least 1.4 (r1 + r2) apart (the cell is longer than 2.4 largest diameters)."""
    if a["c_member1"].shape[0] == 0:
        return None
    pos = np.asarray(scene.member_positions)
    r = np.asarray(scene.radii)
    m1, m2 = a["c_member1"], a["c_member2"]
    d = pos[m2] + a["c_shift"] @ np.asarray(a["cell"]).T - pos[m1]  # image of member 2: + hSize shift
    far = np.linalg.norm(d, axis=1) > 1.1 * (r[m1] + r[m2])
    if np.any(far):
        k = int(np.argmax(far))
        return ("contact %d (members %d, %d, shift %s) joins spheres that do not touch"
                % (k, m1[k], m2[k], a["c_shift"][k].tolist()))
    return None


def _float_problem(x, name):
    """An array that is not of finite floating-point numbers, named as what it is (an integer
    array is not called non-finite)."""
    if not np.issubdtype(x.dtype, np.floating):
        return "%s must hold floating-point numbers, not %s" % (name, x.dtype)
    if not np.all(np.isfinite(x)):
        return "non-finite values in %s" % name
    return None


def cell_problem(a):
    """What makes the saved cell unusable (its shapes; a singular or inverted matrix), or None."""
    for name in ("cell", "cell_ref", "velocity_gradient"):
        if np.shape(a[name]) != (3, 3):
            return "%s must be a 3x3 matrix" % name
        problem = _float_problem(np.asarray(a[name]), name)
        if problem:
            return problem
    for name in ("cell", "cell_ref"):
        h = np.asarray(a[name], dtype=float)
        scale = np.prod(np.linalg.norm(h, axis=0))
        if not scale > 0 or np.linalg.det(h) <= 1e-6 * scale:
            return "%s is a singular or inverted cell matrix (det %.3g)" % (name, np.linalg.det(h))
    return None


def load(path):
    """A specimen file as a Scene with its saved state, contact history included, after every check.

    Returns:
        (scene, meta): the engines' Scene and the file's metadata (its material, seed, how it was
        made, ``sha256``).

    Raises:
        SpecimenFileError: as `read`, and a contact whose members do not touch.

    Example:
        >>> from trueaniso import specimen_file
        >>> scene, meta = specimen_file.load("tests/data/spheres-150-s4.npz")
        >>> scene.num_bodies, meta["seed"], meta["material"]["friction"]
        (150, 4, 0.5)
    """
    a, meta = read(path)
    nb = a["positions"].shape[0]
    mb = a["member_begin"]
    if mb.shape != (nb + 1,) or a["radii"].shape[0] != mb[-1]:
        raise SpecimenFileError("corrupt specimen file %s (inconsistent body/member arrays)" % path)
    s = engines.Scene()
    m = meta["material"]
    s.shear_modulus, s.poisson, s.friction = m["shear_modulus"], m["poisson"], m["friction"]
    s.density = m["density"]
    s.rolling_friction = m.get("rolling_friction", 0.0)
    s.rolling_stiffness = m.get("rolling_stiffness", 0.0)
    s.cell = a["cell"]
    s.cell_ref = a["cell_ref"]
    if np.all(np.diff(mb) == 1):
        s.add_spheres(a["positions"], a["radii"])
    else:
        # Clumps carry their members (offsets in the body's principal frame, radii), mass,
        # principal inertia and (version 4) solid volume, checked against the union's by read();
        # a version-3 file takes the union's (volume 0: CGAL, once per shape).
        volumes = a.get("volumes")
        for b in range(nb):
            k = slice(mb[b], mb[b + 1])
            try:
                s.add_clump(a["positions"][b], a["orientations"][b], a["member_offsets"][k], a["radii"][k],
                            float(a["masses"][b]), a["inertia"][b], 0.0 if volumes is None else float(volumes[b]))
            except (ValueError, RuntimeError) as exc:
                raise SpecimenFileError("invalid specimen file %s (body %d: %s)" % (path, b, exc)) from None
    s.orientations = a["orientations"]
    s.velocities = a["velocities"]
    s.angular_velocities = a["angular_velocities"]
    s.velocity_gradient = a["velocity_gradient"]
    problem = contacts_problem(s, a)
    if problem:
        raise SpecimenFileError("invalid specimen file %s (%s)" % (path, problem))
    s.set_contact_history(a["c_member1"], a["c_member2"], a["c_shift"], a["c_normal"],
                          a["c_normal_force"], a["c_shear_force"], a.get(_ROLLING))
    s.dt, s.time, s.step = meta["dt"], meta["time"], meta["step"]
    s.reference_dt = meta.get("reference_dt", meta["dt"])
    s.block_rotations = meta["block_rotations"]
    if not np.allclose(s.masses, a["masses"], rtol=1e-12):
        raise SpecimenFileError("corrupt specimen file %s (masses disagree with radii and density)" % path)
    from . import dem
    dem.refresh(s)  # contact forces, normals and branches for the loaded positions
    problem = derived.time_step_problem(s, meta)  # on the refreshed contacts, as a chain derives it
    if problem:
        raise SpecimenFileError("invalid specimen file %s (%s)" % (path, problem))
    return s, meta


def summary_path(path):
    """The .json summary beside a specimen .npz."""
    return path[:-4] + ".json" if path.endswith(".npz") else path + ".json"


def write_summary(path, meta):
    """Write the .json summary derived from a specimen's metadata (atomically)."""
    atomic.write_json(summary_path(path), dict(
        specimen=os.path.basename(path), sha256=meta["sha256"], summary=meta.get("summary"),
        parameters=meta.get("parameters"), versions=meta.get("versions"),
        note="derived from the .npz beside it; written again from it when missing"))


def ensure_summary(path, meta):
    """Write the .json summary when it is missing (a run stopped between the two writes);
    returns whether it was written."""
    if os.path.exists(summary_path(path)):
        return False
    write_summary(path, meta)
    return True
