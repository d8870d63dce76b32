"""One writer at a time: an advisory lock (flock) on a lock file.

A results directory is locked for the whole run that writes it (``lock.held(out)``); a second run
refuses at once, naming the holder, or waits when asked (``wait=True``, the scripts' ``--wait``).
flock locks belong to the open file: the kernel drops them when the process dies, even by
kill -9, so a stale lock file never blocks anyone (its content is only the holder's description).
Within one process the lock is re-entrant, so a script that holds it can call library functions
that take it too.
"""
import contextlib
import fcntl
import os
import socket
import sys
import time

from .refusal import Refusal

LOCK_NAME = ".lock"
_held = {}  # real path of the lock file -> [fd, depth]


class Busy(Refusal):
    """Another run holds the lock."""


def _holder(fd):
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        return os.read(fd, 4096).decode(errors="replace").strip() or "a run that has not said who it is"
    except OSError:
        return "another run"


@contextlib.contextmanager
def held(directory, wait=False, log=print, name=LOCK_NAME, what=None):
    """Hold the lock of `directory` (created if missing) for the block; `what` names the thing
    locked in messages (default: the results directory)."""
    what = what or "results directory %s" % directory
    os.makedirs(directory, exist_ok=True)
    path = os.path.realpath(os.path.join(directory, name))
    if path in _held:
        _held[path][1] += 1
        try:
            yield path
        finally:
            _held[path][1] -= 1
        return
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o666)
    except OSError as exc:  # a directory, or a file this user cannot write, where the lock file goes
        raise Refusal("%s cannot be locked: its lock file %s cannot be opened (%s)%s"
                      % (what, path, exc.strerror, "; remove or rename that directory" if os.path.isdir(path)
                         else "")) from None
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = _holder(fd)
            if not wait:
                raise Busy("%s is in use by another run (%s); wait for it to end, or pass --wait to queue "
                           "behind it" % (what, holder)) from None
            log("waiting for the run that holds %s (%s) ..." % (what, holder))
            fcntl.flock(fd, fcntl.LOCK_EX)
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, ("pid %d on %s since %s: %s" % (os.getpid(), socket.gethostname(),
                                                     time.strftime("%Y-%m-%d %H:%M:%S"),
                                                     " ".join(sys.argv))).encode())
        _held[path] = [fd, 1]
        try:
            yield path
        finally:
            del _held[path]
            os.ftruncate(fd, 0)
    finally:
        os.close(fd)  # releases the flock


def is_held(directory, name=LOCK_NAME):
    """Whether this process holds the lock of `directory`."""
    return os.path.realpath(os.path.join(directory, name)) in _held
