"""What produced a result: the code version a study is bound to, and the software around it.

``code_version()`` hashes the code that makes the numbers, in two parts:

- the engines: the hash of the C++ sources under engines/ that CMake compiled into the module
  (``engines.source_hash()``, cmake/EngineSourceHash.cmake), so it is known wherever the module
  is, installed or in a build tree. In a source tree the same hash is computed from engines/ and
  compared: a module built from other sources than those beside it (edited, not rebuilt) is
  refused, because its numbers would be credited to code that did not make them;
- the package: the .py files of trueaniso itself, wherever it is imported from, but for its
  subpackage trueaniso.analysis;
- the x86-64 level the module was compiled for, when it is not the portable baseline
  (``engines.build_arch()``, CMake's TRUEANISO_ARCH): a build for x86-64-v3 fuses multiply-adds and
  its results differ in the last bits, so its studies and specimens are another code's. The
  baseline adds nothing.

It changes exactly when that code changes, committed or not, in a checkout or an installation;
edits to docs, tests, benchmarks, trueaniso.analysis (which only reads results, and is rerun on
every study run) or the user scripts (whose options are recorded in the study's fingerprint) leave it alone.
The git commit and the release version (``__version__``, the file VERSION, which is not hashed:
the same engines under a new version number make the same numbers) are recorded beside it for
people, not compared.
"""
import functools
import hashlib
import os
import platform
import sys

from . import REPO_ROOT, __version__, _HERE, buildarch, engines
from .refusal import Refusal

ENGINE_SUFFIXES = (".cpp", ".hpp", ".h", ".txt", ".cmake")


class StaleBuild(Refusal):
    """The compiled module was not built from the engine sources beside it."""


def manifest_hash(root, top, suffixes, skip=()):
    """SHA-256 of the lines "path sha256(content)", sorted by path (the scheme of
    cmake/EngineSourceHash.cmake; paths relative to root, '/'-separated); the folders of `top`
    named in `skip` are left out."""
    lines = []
    for d, dirs, files in os.walk(os.path.join(root, top)):
        dirs[:] = [x for x in dirs if x != "__pycache__" and not (d == os.path.join(root, top) and x in skip)]
        for name in files:
            if name.endswith(suffixes):
                full = os.path.join(d, name)
                with open(full, "rb") as f:
                    digest = hashlib.sha256(f.read()).hexdigest()
                lines.append((os.path.relpath(full, root).replace(os.sep, "/"), digest))
    return hashlib.sha256("".join("%s %s\n" % x for x in sorted(lines)).encode()).hexdigest()


def engine_source_hash(root=REPO_ROOT):
    """The engines' hash compiled into the module, checked against engines/ when it is there."""
    compiled = engines.source_hash()
    if os.path.isdir(os.path.join(root, "engines")):
        tree = manifest_hash(root, "engines", ENGINE_SUFFIXES)
        if tree != compiled:
            raise StaleBuild("the compiled module %s was built from other engine sources than %s "
                             "(edited since the last build?); rebuild it: ./setup.sh, or cmake --build build"
                             % (engines.__file__, os.path.join(root, "engines")))
    return compiled


@functools.lru_cache(maxsize=None)
def code_version(root=REPO_ROOT):
    """'src-' + 16 hex digits of the SHA-256 of the engines' and the package's hashes (module doc)."""
    package = manifest_hash(os.path.dirname(_HERE), os.path.basename(_HERE), (".py",), skip=("analysis",))
    parts = engine_source_hash(root) + " " + package
    if engines.build_arch() != buildarch.BASELINE:
        parts += " " + engines.build_arch()
    return "src-" + hashlib.sha256(parts.encode()).hexdigest()[:16]


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
    """Code, interpreter, libraries, machine, the x86-64 level the engines were built for and engine threads."""
    import numpy as np

    out = dict(trueaniso=__version__, code=code_version(), git=git_commit(), python=platform.python_version(),
               numpy=np.__version__, machine=platform.machine(), build=engines.build_arch(),
               threads=engines.threads())
    if "yade" in sys.modules:
        try:
            out["yade"] = sys.modules["yade"].config.version
        except AttributeError:
            out["yade"] = "unknown"
    return out
