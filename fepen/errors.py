"""Exceptions that the command line turns into one readable line and an exit code.

Exit codes (contract, docs/results.md):

    0  success
    1  an internal error: a bug in fepen (one line; ``fepen --debug ...`` shows the traceback)
    2  bad input (InputError): one line naming the key or argument and what is allowed
    3  the simulation cannot go on (SimulationError): what, where and when; what it wrote is kept
    4  a fault of the machine (MachineFault): disk full, permission, a file that cannot be read, memory (OutOfMemory:
       a MemoryError, a library that cannot be mapped under ``ulimit -v``), a broken set-up (no C compiler, a
       kernel cache that cannot be written), or a signal (SIGTERM, SIGINT) that stopped the run after a
       checkpoint; ``fepen run --resume DIR`` continues it

How a run ended is one of OUTCOMES; ``stop_outcome(err)`` is the one place an exception is classified, for
summary.json, run.json and the command line alike.
"""

from __future__ import annotations

import errno
import os
import re
import resource  # now, not when memory has run out (its own shared object would then fail to map)
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


class OutOfMemory(MachineFault):
    """Memory ran out: a MemoryError, or a shared object that could not be mapped while a module was imported
    (ImportError, OSError: "failed to map segment", ENOMEM), most often under an address-space limit (``ulimit
    -v``, a batch system's h_vmem). Exit code 4; the message names the limits set (out_of_memory)."""


#: what the dynamic loader and the system say when a library cannot be mapped or memory not allocated
_NO_MEMORY = re.compile(r"(?:([^\s:'\"]+): )?(failed to map segment from shared object|cannot allocate memory)",
                        re.IGNORECASE)
#: the per-process limits on memory: (resource, its name in ulimit, what it bounds, the /proc/self/status field of
#: what the process holds against it)
_LIMITS = (("RLIMIT_AS", "ulimit -v", "address-space", "VmSize"), ("RLIMIT_DATA", "ulimit -d", "data", "VmData"))
_MIB = 1 << 20


def _rlimits() -> list[tuple[str, str, int, str]]:
    """The per-process memory limits that are set (soft limits): (ulimit name, what it bounds, bytes, the
    /proc/self/status field of what the process holds against it)."""
    found = []
    for res, name, what, field in _LIMITS:
        try:
            soft = resource.getrlimit(getattr(resource, res))[0]
        except (AttributeError, ValueError, OSError):
            continue
        if soft != resource.RLIM_INFINITY:
            found.append((name, what, int(soft), field))
    return found


def memory_limits() -> list[tuple[str, str, int, int | None]]:
    """The per-process memory limits that are set (soft limits): ``(ulimit name, what it bounds, the limit in
    bytes, what this process holds against it now in bytes, or None where /proc is not readable)``, e.g.
    ``("ulimit -v", "address-space", 786432000, 534773760)``."""
    held = {}
    try:
        with open("/proc/self/status") as f:
            for line in f:
                key, _, value = line.partition(":")
                if key in ("VmSize", "VmData"):
                    held[key] = 1024 * int(value.split()[0])
    except (OSError, ValueError, IndexError):
        pass
    return [(name, what, soft, held.get(field)) for name, what, soft, field in _rlimits()]


#: limits_text() as the command started (start_within_limits): what a message says when memory has run out so
#: far that it cannot be said afresh
_LIMITS_TEXT = [""]


#: the variables OpenBLAS reads its thread count from, in its order
_BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS")


def start_within_limits() -> None:
    """Before numpy, MPI or gmsh is loaded (fepen.cli.main): under an address-space limit (``ulimit -v``, a batch
    system's h_vmem), OpenBLAS on one thread, unless OPENBLAS_NUM_THREADS, GOTO_NUM_THREADS or OMP_NUM_THREADS
    says otherwise. OpenBLAS starts a thread per core as it loads, each mapping a buffer of its own (gmsh's copy,
    linked into libgmsh: 136 MiB per thread, measured), and the OpenBLAS gmsh carries calls a null pointer when
    that map fails: a segmentation fault as gmsh is imported, not an error (a deformable run under ulimit -v 650
    to 750 MiB; gmsh alone under 150 to 250 MiB). On one thread it starts none. fepen's runs do not use threaded
    BLAS (its tests run with OMP_NUM_THREADS=1)."""
    _LIMITS_TEXT[0] = limits_text()
    limited = any(name == "ulimit -v" for name, *_ in _rlimits())
    if limited and not any(os.environ.get(v) for v in _BLAS_THREADS):
        os.environ["OPENBLAS_NUM_THREADS"] = "1"


#: the least address space fepen's libraries load in (MiB): numpy, MPI and numba's LLVM. Measured on Debian's
#: stack: a rigid run under ulimit -v 450 MiB runs; under 300-400 MiB LLVM or an allocation fails as it loads (a
#: line, exit 4); under 250 MiB Open MPI segfaults loading its components, and at 100-200 MiB its PMIx aborts
#: the process on its shared store (exit 1, both) - whichever library maps first. Below the floor the command
#: stops before loading any of them.
LOAD_FLOOR_MIB = 400


def below_load_floor() -> MemoryError | None:
    """A MemoryError saying why when an address-space limit (ulimit -v) is below LOAD_FLOOR_MIB, else None."""
    for _name, what, limit, _ in _rlimits():
        if what == "address-space" and limit < LOAD_FLOOR_MIB * _MIB:
            return MemoryError(f"fepen's libraries (numpy, MPI, numba) need about {LOAD_FLOOR_MIB} MiB of address "
                               "space to load")
    return None


#: the environment variable a relaunching command sets on the ranks it starts (fepen.studies.processes.relaunch)
RELAUNCHED = "FEPEN_RELAUNCHED"
#: the stop a relaunched rank was asked for (SIGUSR1) before its study caught signals (fepen.runs.interrupts)
EARLY_STOP: list[int] = []


def catch_early_stop() -> None:
    """In a rank that a relaunching command started, from its first line (fepen.cli.main): SIGUSR1, the stop that
    command passes on through mpirun, is recorded (EARLY_STOP) until the study catches signals, which then stops at
    its first shot boundary. Before, a signal in the second or two while a loaded machine imported MPI and
    numpy killed the rank (the default action), and mpirun ended with 138 instead of the study with 4."""
    if os.environ.get(RELAUNCHED) != "1":
        return
    import signal

    signal.signal(signal.SIGUSR1, lambda signum, frame: EARLY_STOP.append(signum))


def limits_text() -> str:
    """The memory limits set, for a message: "the address-space limit ulimit -v is 750 MiB" ("" when none is)."""
    try:
        return ", ".join(f"the {what} limit {name} is {limit / _MIB:.0f} MiB" for name, what, limit, _ in _rlimits())
    except MemoryError:
        return _LIMITS_TEXT[0]


#: what Python says of a C function that failed without raising: an allocation it did not check, under a limit
_NO_EXCEPTION = re.compile(r"without (setting an )?exception|with an exception set")


def _near_a_limit() -> bool:
    """Whether this process maps within a tenth (at least 64 MiB) of a per-process memory limit (memory_limits)."""
    try:
        return any(held is not None and limit - held < max(64 * _MIB, limit / 10)
                   for _, _, limit, held in memory_limits())
    except MemoryError:
        return True


def out_of_memory(err: BaseException) -> OutOfMemory | None:
    """The OutOfMemory an exception means, or None: a MemoryError; an ImportError or OSError whose shared object
    could not be mapped ("failed to map segment from shared object", "cannot allocate memory") or that is ENOMEM;
    a SystemError of a C function that failed without raising ("error return without exception set": measured
    while numba is imported under ulimit -v 400 MiB) when the process maps within a tenth of a memory limit.
    Its message: "out of memory: what failed (the address-space limit ulimit -v is N MiB)"."""
    if isinstance(err, OutOfMemory):
        return err
    if isinstance(err, MemoryError):
        detail = " ".join(str(err).split()) or "a memory allocation failed"
    elif isinstance(err, (ImportError, OSError)):
        found = _NO_MEMORY.search(str(err))
        if found is not None:
            detail = f"loading {os.path.basename(found.group(1))}: {found.group(2)}" if found.group(1) else \
                found.group(2)
        elif isinstance(err, OSError) and err.errno == errno.ENOMEM:
            detail = describe_os_error(err)
        else:
            return None
    elif isinstance(err, SystemError) and _NO_EXCEPTION.search(str(err)) and _near_a_limit():
        detail = f"a library failed without saying why, near the limit (SystemError: {' '.join(str(err).split())})"
    else:
        return None
    limits = limits_text()
    return OutOfMemory(f"out of memory: {detail}" + (f" ({limits})" if limits else ""))


def describe_os_error(err: OSError) -> str:
    """One line for an OSError: what the system said and the file it concerns (the exception's own text when it
    carries no errno: llvmlite's, ctypes')."""
    if err.errno is None and not err.strerror:
        return " ".join(str(err).split()) or type(err).__name__
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
    Outcome("interrupted", 4, True, False, "a signal (SIGTERM, SIGINT, SIGHUP, SIGUSR1) stopped it after a "
                                           "checkpoint, or a study at a shot boundary"),
    Outcome("fault", 4, True, False, "a fault of the machine (MachineFault: disk full, permission, I/O, out of "
                                     "memory, no C compiler or kernel cache)"),
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
    if isinstance(err, (OSError, MemoryError)) or out_of_memory(err) is not None:
        return OUTCOMES["fault"]
    return OUTCOMES["error"]
