"""The base of the failures a user can act on: their str() is one complete line.

Bottom layer (beside files.py and memory.py): any layer raises a subclass, and the command line
prints ``COMMAND error: <the line>`` and exits with `exit_code`, never a traceback.
"""
from __future__ import annotations


class OneLineError(Exception):
    """A failure whose message is one line for the user. exit_code: 2 when the command refuses
    its input (too large, a folder holding other runs), 1 when the computation could not reach
    its result (no equilibrium)."""

    exit_code = 1
