"""Exceptions that the command line turns into one readable line and an exit code.

Exit codes (contract, docs/results.md):

    0  success
    1  an internal error: a bug in fepen (one line; ``fepen --debug ...`` shows the traceback)
    2  bad input (InputError): one line naming the key or argument and what is allowed
    3  the simulation cannot go on (SimulationError): what, where and when; what it wrote is kept
    4  a fault of the machine (MachineFault): disk full, permission, a file that cannot be read, or a signal
       (SIGTERM, SIGINT) that stopped the run after a checkpoint; ``fepen run --resume DIR`` continues it

How a run ended is one of OUTCOMES; ``stop_outcome(err)`` is the one place an exception is classified, for
summary.json, run.json and the command line alike.
"""

from __future__ import annotations

from dataclasses import dataclass


class InputError(ValueError):
    """Bad input: names the scene key and what is allowed. The command line exits with code 2."""

    exit_code = 2

    def __init__(self, key: str, message: str):
        self.key, self.message = key, message
        super().__init__(f"{key}: {message}" if key else message)

    def __reduce__(self):  # picklable, so that it crosses a process pool whole
        return (type(self), (self.key, self.message))


class SimulationError(RuntimeError):
    """The simulation became unstable or invalid (NaN, inverted element, collapsed step). Exit code 3.

    The message says where (element, position) and when (step, time)."""

    exit_code = 3


class BeyondMethod(SimulationError):
    """The run reached a state the method does not model (a projectile that would fracture or erode):
    fepen stops rather than report numbers. Exit code 3, message starting "beyond the method"."""

    def __init__(self, message: str):
        super().__init__(f"beyond the method: {message}")


class MachineFault(OSError):
    """A fault of the machine, not of the input or the physics: no space left, no permission, an I/O error,
    or a signal that stopped the run (Interrupted). Exit code 4. The message says what failed and where; the
    files written before are complete (each is replaced whole, fepen.atomic)."""

    exit_code = 4

    def __init__(self, message: str):
        super().__init__(message)
        self.message = message

    def __str__(self) -> str:
        return self.message

    def __reduce__(self):
        return (type(self), (self.message,))


class Interrupted(MachineFault):
    """A signal (SIGTERM from a scheduler, SIGINT from Ctrl-C) stopped the run after it wrote a checkpoint.
    Exit code 4; ``fepen run --resume DIR`` finishes it with the same results."""


def describe_os_error(err: OSError) -> str:
    """One line for an OSError: what the system said and the file it concerns."""
    import errno
    import os

    what = {errno.ENOSPC: "no space left on device", errno.EDQUOT: "disk quota exceeded",
            errno.EACCES: "permission denied", errno.EPERM: "operation not permitted",
            errno.EROFS: "read-only file system", errno.EIO: "input/output error"}.get(
        err.errno, err.strerror or os.strerror(err.errno or 0) or type(err).__name__)
    path = f" ({err.filename})" if err.filename else ""
    note = " (injected)" if "injected" in (err.strerror or "") else ""
    return f"{what}{path}{note}"


@dataclass(frozen=True)
class Outcome:
    """How a run ended.

    Attributes:
        name: summary.json's and run.json's ``outcome``.
        exit_code: the command's exit code.
        resumable: ``fepen run --resume DIR`` can finish the run (a rigid run: runs it again).
        result: the run reports a result (Hx_mm, depth_mm, ...); a stop reports none.
        meaning: one line for docs/results.md.
    """

    name: str
    exit_code: int
    resumable: bool
    result: bool
    meaning: str


#: every outcome a run can have, by name (docs/results.md "Exit codes" is built on this table)
OUTCOMES = {o.name: o for o in (
    Outcome("embedded", 0, False, True, "stopped in the target"),
    Outcome("perforated", 0, False, True, "left through the rear face of a finite target"),
    Outcome("ricochet", 0, False, True, "left through the front face after entering"),
    Outcome("rebound", 0, False, True, "came off the rigid wall"),
    Outcome("eroded", 0, False, True, "erosion left less than 5 % of the projectile's mass"),
    Outcome("ended", 0, False, True, "reached run.end_time before any of the above"),
    Outcome("bad-input", 2, False, False, "the input was refused (InputError) after the run had started"),
    Outcome("stopped", 3, False, False, "the simulation could not go on (SimulationError)"),
    Outcome("interrupted", 4, True, False, "a signal (SIGTERM, SIGINT) stopped it after a checkpoint"),
    Outcome("fault", 4, True, False, "a fault of the machine (MachineFault: disk full, permission, I/O)"),
    Outcome("error", 1, False, False, "an internal error: a bug in fepen"),
)}


def stop_outcome(err: BaseException) -> Outcome:
    """The outcome of a run that an exception stopped (OUTCOMES)."""
    if isinstance(err, (Interrupted, KeyboardInterrupt)):
        return OUTCOMES["interrupted"]
    if isinstance(err, InputError) or (isinstance(err, ValueError) and "null byte" in str(err)):
        return OUTCOMES["bad-input"]
    if isinstance(err, SimulationError):
        return OUTCOMES["stopped"]
    if isinstance(err, (OSError, MemoryError)):
        return OUTCOMES["fault"]
    return OUTCOMES["error"]
