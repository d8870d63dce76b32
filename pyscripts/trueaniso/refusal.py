"""Refusals: a run stops before any work, with one line that says why and what to do.

Bad input, a results directory in use by another run, or one that holds another study are all
refusals; scripts turn them into ``error: ...`` and exit status 2 (``cli.guarded``). This module
has no dependencies so that every other module can raise them.
"""


class Refusal(Exception):
    """A run that must not start (or continue); the message is the one line the user reads."""


class InputError(Refusal, ValueError):
    """Bad input detected before any work starts (a ValueError too, for library callers)."""
