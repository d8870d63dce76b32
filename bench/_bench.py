"""What the benchmarks share (a module, not a script): the packages they import made importable;
the machine line every table states; the table written into a Markdown file between the markers
<!-- NAME:begin --> and <!-- NAME:end --> (a file without them gets the block appended),
atomically; a timed worker run in its own process, ours under /usr/bin/python3 or YADE's under
yade-double, and our stepper timed in it."""
import json
import os
import platform
import re
import subprocess
import sys
import time

# Importing this module makes this checkout's trueaniso (pyscripts/) importable, first on the path,
# whether the script runs under /usr/bin/python3 or yade-double, and whichever checkout setup.sh
# linked for the machine: the one place the benchmarks say where the package is.
_PYSCRIPTS = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "pyscripts")
if _PYSCRIPTS in sys.path:
    sys.path.remove(_PYSCRIPTS)
sys.path.insert(0, _PYSCRIPTS)


def machine():
    """CPU model, cores, Debian release and platform: the line every benchmark table states."""
    model = platform.machine() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            model = next(ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name"))
    except (OSError, StopIteration):
        pass
    debian = ""
    if os.path.exists("/etc/debian_version"):
        with open("/etc/debian_version") as f:
            debian = ", Debian " + f.read().strip()
    return "%s, %d cores%s, %s" % (model, os.cpu_count(), debian, platform.platform())


def replace_block(path, name, body, heading=None):
    """Put `body` between the NAME markers of the Markdown file `path` (created if missing).
    Without markers the block is added at the end of the section `heading` (a line of the file),
    or appended after a new `heading` line when the file has none. The file is replaced
    atomically: a benchmark interrupted while writing leaves the old file whole."""
    from trueaniso import atomic
    begin, end = "<!-- %s:begin -->" % name, "<!-- %s:end -->" % name
    block = "%s\n%s\n%s" % (begin, body.rstrip("\n"), end)
    text = open(path).read() if os.path.exists(path) else ""
    if begin in text:
        text = re.sub(re.escape(begin) + ".*?" + re.escape(end), lambda _: block, text, flags=re.S)
    elif heading and heading in text.split("\n"):
        # Into the heading's own section, before the next heading of its level or above: a second
        # copy of the heading at the end of the file would split one section in two.
        lines = text.split("\n")
        start = lines.index(heading)
        level = heading.split(" ", 1)[0]
        end, fenced = len(lines), False
        for k in range(start + 1, len(lines)):
            fenced ^= lines[k].startswith("```")  # a '# comment' in a code block is no heading
            if not fenced and lines[k].startswith("#") and len(lines[k].split(" ", 1)[0]) <= len(level):
                end = k
                break
        while end > start + 1 and lines[end - 1] == "":
            end -= 1
        lines[end:end] = ["", block]  # the blank lines that ended the section follow it
        text = "\n".join(lines)
    else:
        text += "\n" + ("%s\n\n" % heading if heading else "") + block + "\n"
    with atomic.atomic_open(path) as f:
        f.write(text)


def publish(doc, name, lines, heading=None):
    """A benchmark's result printed, and put into the page `doc` between the NAME markers when one
    was given (--doc; replace_block, with its `heading`): `lines`, joined, or one text. Returns
    the text."""
    text = lines if isinstance(lines, str) else "\n".join(lines)
    print(text)
    if doc:
        replace_block(doc, name, text, heading=heading)
    return text


def time_step_rules(text):
    """--rules of the time-step benchmarks: at least two rules of dem.TIME_STEP_RULES, comma separated,
    the first the reference; refused in one line otherwise."""
    from trueaniso import cli, dem
    rules = text.split(",")
    if len(rules) < 2 or any(r not in dem.TIME_STEP_RULES for r in rules):
        cli.fail("--rules: at least two of %s, comma separated" % ", ".join(dem.TIME_STEP_RULES))
    return rules


def sphere_specimen(path):
    """The number of spheres of the sphere specimen file `path`, checked before any run: a file
    that is not a specimen would fail inside a worker, with its traceback, and a clump specimen be
    stepped and labelled as spheres, or fail on its array lengths. Exits with
    one line of error otherwise."""
    from trueaniso import cli, specimen_file
    try:
        arrays, meta = specimen_file.read(path)
    except specimen_file.SpecimenFileError as exc:
        cli.fail(str(exc))
    assembly = (meta.get("parameters") or {}).get("assembly", "sphere")
    if assembly != "sphere" or len(arrays["radii"]) != len(arrays["positions"]):
        cli.fail("%s is a %s specimen: this benchmark steps sphere specimens only (bench_clumps.py times clumps)"
                 % (path, assembly))
    return len(arrays["positions"])


def writable_doc(path):
    """Exits with one line of error unless the Markdown file `path` can be written (its folder
    exists and takes a new file): a read-only one failed after the timing, in a traceback."""
    import tempfile
    from trueaniso import cli
    folder = os.path.dirname(os.path.abspath(path))
    try:  # the way replace_block writes: a new file beside it, then a rename
        if os.path.isdir(path):
            raise OSError("a directory")
        with tempfile.NamedTemporaryFile(dir=folder, prefix=".tmp-check-"):
            pass
    except OSError as exc:
        cli.fail("--doc %s: cannot write a file there (%s)" % (path, exc.strerror or exc))


def reply(result):
    """A worker's answer to run_worker: one line "BENCH {json}" on standard output."""
    print("BENCH " + json.dumps(result), flush=True)


def run_worker(script, code, threads, args, timeout=7200, build=None):
    """Runs `script --worker CODE ARGS` in its own process with `threads` OpenMP threads (ours
    under /usr/bin/python3, "yade" under yade-double -j THREADS), with the engines of the build
    tree `build` if given (TRUEANISO_BUILD), and returns the dict the worker printed on its line
    "BENCH {json}"; a failed worker stops the benchmark with its error."""
    from trueaniso import cli
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    if build:
        env["TRUEANISO_BUILD"] = build
    cmd = ((["yade-double", "-j", str(threads), "-n", "-x", script] if code == "yade" else ["/usr/bin/python3", script])
           + ["--worker", code] + list(args))
    out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    line = [ln for ln in out.stdout.splitlines() if ln.startswith("BENCH ")]
    if out.returncode != 0 or not line:
        cli.fail("benchmark worker failed: %s\n%s" % (" ".join(cmd), out.stderr[-2000:]), 1)
    return json.loads(line[-1][6:])


def state_ids(text):
    """--ids of the benches: state numbers, ranges A-B and single numbers separated by commas
    ('4,12', '1-39', '1-3,21') -> ints in that order; ValueError on anything else. What states a
    bench takes it checks itself."""
    ids = []
    for piece in str(text).split(","):
        a, _, b = piece.partition("-")
        ids += range(int(a), int(b or a) + 1)
    return ids


def tile_counts(text):
    """--tiles: the tiling counts K, whole numbers separated by commas; one line of error otherwise."""
    from trueaniso import cli
    try:
        return [int(k) for k in str(text).split(",")]
    except ValueError:
        cli.fail("--tiles takes whole numbers separated by commas, not %r" % text)


def loading_servo():
    """A TrueTriaxialServo loading the cell along state 21's path (b = 0.5, sigma_z 140 kPa, 0.5 Pa
    a step) that never settles, stalls or gives up: a study's step for as many steps as a benchmark
    times. It reads the stress, the affine stiffness and the unbalanced force every step."""
    from trueaniso import engines
    servo = engines.TrueTriaxialServo()
    servo.set_goal(0.5, 140e3, 100e3)
    servo.path_rate = 0.5
    servo.settle_steps = servo.hold_steps = servo.stall_steps = servo.max_steps = 10 ** 9
    return servo


def time_ours(scene, dt, steps, warmup=100, damping=0.2, servo=False):
    """Our stepper on `scene` at the fixed time step `dt` (the time stepper off), local damping
    `damping`, with a loading servo in the chain if `servo` (loading_servo): `warmup` steps
    untimed, then `steps` timed. Returns (chain, seconds of the timed steps)."""
    from trueaniso import dem
    scene.dt = dt
    controllers = [loading_servo()] if servo else []
    chain = dem.Chain(scene, damping=damping, controllers=controllers)
    chain.timestep.dead = True
    for c in controllers:
        c.start(scene)
    chain.run(warmup)
    t = time.perf_counter()
    chain.run(steps)
    seconds = time.perf_counter() - t
    for c in controllers:
        if c.status != "loading":
            raise RuntimeError("the benchmark's servo stopped loading (%s): the steps were not a study's" % c.status)
    return chain, seconds


def orthorhombic(scene):
    """The scene itself when its cell is orthorhombic, else tiled(scene, 1) evaluated: its shear
    terms (the six-component servo leaves ~1e-6 of the edge) dropped, for every code alike, since
    lammps_peer writes an orthorhombic box. Prepared specimens always carry such terms."""
    import numpy as np
    from trueaniso import dem
    h = np.array(scene.cell)
    if np.all(h == np.diag(np.diag(h))):
        return scene
    s = tiled(scene, 1)
    dem.refresh(s)
    return s


def grid_rows(scene):
    """The order specimen placement gives (specimen.grid_rows): bodies sorted by a grid of cells
    one largest diameter wide, x fastest, then y, then z."""
    import numpy as np
    from trueaniso import specimen
    h = np.array(scene.cell)
    reduced = np.linalg.solve(h, np.array(scene.positions).T).T % 1.0
    cells = np.maximum(1, (np.diag(h) // (2.0 * np.max(scene.radii))).astype(int))
    return specimen.grid_rows(reduced * cells, 1.0)


def tiled(scene, k):
    """The packing repeated k times along each axis of its (nearly orthorhombic) cell, spheres or
    clumps (each body with its members, mass, inertia, volume and orientation): reduced
    coordinates kept, the cell's diagonal times k (its shear terms, ~1e-6 of the edge, dropped). A
    periodic packing tiled is a packing of k^3 times the particles at the same stress, void ratio
    and Zm; the contacts are found anew, without their shear history."""
    import numpy as np
    from trueaniso import engines
    h = np.array(scene.cell)
    edge = np.diag(h).copy()
    reduced = np.linalg.solve(h, np.array(scene.positions).T).T % 1.0
    t = engines.Scene()
    t.shear_modulus, t.poisson, t.density, t.friction = scene.shear_modulus, scene.poisson, scene.density, scene.friction
    t.cell_size = t.cell_ref_size = edge * k
    shifts = [np.array([i, j, l]) for i in range(k) for j in range(k) for l in range(k)]
    if not scene.has_clumps:
        t.add_spheres(np.vstack([(reduced + s) * edge for s in shifts]), np.tile(np.array(scene.radii), len(shifts)))
        return t
    mb, q = np.array(scene.member_begin), np.array(scene.orientations)
    offsets, radii = np.array(scene.member_offsets), np.array(scene.radii)
    masses, inertia, volumes = np.array(scene.masses), np.array(scene.inertia), np.array(scene.volumes)
    for s in shifts:
        for b in range(scene.num_bodies):
            m = slice(mb[b], mb[b + 1])
            t.add_clump((reduced[b] + s) * edge, q[b], offsets[m], radii[m], float(masses[b]), inertia[b],
                        float(volumes[b]))
    return t
