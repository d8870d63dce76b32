"""What produced a result: the code version a study is bound to, and the software around it.

``code_version()`` is a SHA-256 over the sources that make the numbers: every file under engines/
(the C++ physics and its build) and pyscripts/trueaniso/ (the package that composes it), by
relative path and content. It changes exactly when that code changes, whether or not the tree is a
git checkout, committed or not; edits to docs, tests, benchmarks, analysis/ (which only reads
results, and is rerun on every study run) or the user scripts (whose options are recorded in the
study's fingerprint) leave it alone. The git commit is recorded beside it for people, not compared.
"""
import functools
import hashlib
import os
import platform
import sys

from . import REPO_ROOT, __version__

SOURCE_DIRS = ("engines", os.path.join("pyscripts", "trueaniso"))
SOURCE_SUFFIXES = (".cpp", ".hpp", ".h", ".py", ".txt", ".cmake")


def source_files(root=REPO_ROOT):
    out = []
    for top in SOURCE_DIRS:
        for d, dirs, files in os.walk(os.path.join(root, top)):
            dirs[:] = sorted(x for x in dirs if x != "__pycache__")
            for name in sorted(files):
                if name.endswith(SOURCE_SUFFIXES):
                    out.append(os.path.relpath(os.path.join(d, name), root))
    return sorted(out)


@functools.lru_cache(maxsize=None)
def code_version(root=REPO_ROOT):
    """'src-' + the first 16 hex digits of the SHA-256 of the sources (module doc)."""
    h = hashlib.sha256()
    files = source_files(root)
    for rel in files:
        h.update(rel.replace(os.sep, "/").encode() + b"\0")
        with open(os.path.join(root, rel), "rb") as f:
            h.update(f.read())
        h.update(b"\0")
    return "src-" + h.hexdigest()[:16] if files else "unknown (no sources beside the package)"


@functools.lru_cache(maxsize=None)
def git_commit(root=REPO_ROOT):
    """The source commit (with '+dirty' for local edits), or None outside a git checkout."""
    import subprocess
    try:
        head = subprocess.run(["git", "-C", root, "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, timeout=10).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None
    return (head + ("+dirty" if dirty else "")) if head else None


def versions():
    """Code, interpreter, libraries, machine and engine threads."""
    import numpy as np

    from . import engines
    out = dict(trueaniso=__version__, code=code_version(), git=git_commit(), python=platform.python_version(),
               numpy=np.__version__, machine=platform.machine(), threads=engines.threads())
    if "yade" in sys.modules:
        try:
            out["yade"] = sys.modules["yade"].config.version
        except AttributeError:
            out["yade"] = "unknown"
    return out
