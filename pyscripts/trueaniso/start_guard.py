"""Ctrl-C (or a kill, SIGTERM) in an entry point's first second, while Python still loads numpy,
matplotlib and the engines: one line and the signal's status, nothing written, where a
KeyboardInterrupt would be a traceback, numpy's ImportError or a crash. Installed first thing
by every script (``pyscripts/*.py``) and, for the tools run as ``python3 -m trueaniso...``, by the
package itself while Python locates the module (trueaniso/__init__.py); cli.guarded then gives
both signals their meaning for the work when it starts, so this handler never outlives the start.
"""
import os
import signal
import sys

LINE = "error: interrupted while starting; nothing was done\n"


def install(quiet=False):
    """Exit at once on SIGINT or SIGTERM with status 128 + the signal, saying so unless `quiet` (an
    MPI worker: the master says it once for the job)."""
    def handler(number, _frame):
        if not quiet:
            try:
                sys.stderr.write(LINE)
                sys.stderr.flush()
            except (OSError, ValueError):
                pass
        os._exit(128 + number)
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, handler)
