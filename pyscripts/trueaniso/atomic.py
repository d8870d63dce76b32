"""Atomic file writes: a result is either absent or complete, never half-written.

Each writer goes to a temporary file in the destination directory, flushes and fsyncs it, then
renames it over the destination (rename is atomic on POSIX within one file system).
"""
import contextlib
import csv
import io
import json
import math
import os
import tempfile


@contextlib.contextmanager
def atomic_open(path, mode="w"):
    path = os.fspath(path)
    directory = os.path.dirname(os.path.abspath(path))
    os.makedirs(directory, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".tmp-", suffix="-" + os.path.basename(path), dir=directory)
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; results are ordinary files
    try:
        with os.fdopen(fd, mode) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and not exc.filename:  # a write's error names no file: this one
            raise OSError(exc.errno, exc.strerror or str(exc), path) from None
        raise


def write_json(path, obj):
    """`obj` as standard JSON: a number that is not finite (NaN: a magnitude zeta no value in its
    range reproduces, a standard error at a bound) is written null. Python's default wrote NaN,
    which is not JSON: jq, JavaScript and other strict parsers refuse the whole file. Readers
    take null as 'not determined'."""
    text = json.dumps(_finite(json.loads(json.dumps(obj, default=_jsonable))), indent=2, sort_keys=True,
                      allow_nan=False)
    with atomic_open(path, "w") as f:
        f.write(text + "\n")


def _finite(x):
    """x with every non-finite float replaced by None, through dicts and lists."""
    if isinstance(x, float):
        return x if math.isfinite(x) else None
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, list):
        return [_finite(v) for v in x]
    return x


def write_csv(path, rows, fieldnames=None):
    rows = list(rows)
    if fieldnames is None:
        fieldnames = list(rows[0].keys()) if rows else []
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=fieldnames, lineterminator="\n")
    w.writeheader()
    for r in rows:
        w.writerow(r)
    with atomic_open(path, "w") as f:
        f.write(buf.getvalue())


def _jsonable(x):
    try:
        import numpy as np
        if isinstance(x, np.generic):
            return x.item()
        if isinstance(x, np.ndarray):
            return x.tolist()
    except ImportError:  # pragma: no cover
        pass
    raise TypeError("not JSON serialisable: %r" % type(x))
