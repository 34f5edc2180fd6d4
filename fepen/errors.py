"""Exceptions that the command line turns into one readable line and an exit code.

Exit codes (contract): 2 for bad input, 3 for a simulation that became unstable or invalid.
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
