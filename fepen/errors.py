"""Exceptions that the command line turns into one readable line and an exit code.

Exit codes (contract, docs/results.md):

    0  success
    1  an internal error: a bug in fepen (one line; ``fepen --debug ...`` shows the traceback)
    2  bad input (InputError): one line naming the key or argument and what is allowed
    3  the simulation cannot go on (SimulationError): what, where and when; what it wrote is kept
    4  a fault of the machine (MachineFault): disk full, permission, a file that cannot be read, or a signal
       (SIGTERM, SIGINT) that stopped the run after a checkpoint; ``fepen run --resume DIR`` continues it
"""


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
