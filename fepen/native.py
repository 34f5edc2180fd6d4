"""Small C sources of fepen's hot loops, built once per machine with the system's C compiler and loaded with
ctypes (the solver's trial pass, the target law's point forces). Each has a Python (numba or numpy)
reference it is tested against, and is used only when it builds.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import subprocess
from pathlib import Path

from fepen.atomic import replacing

__all__ = ["FLAGS", "cache_dir", "load"]

FLAGS = ["-O3", "-march=native", "-fopenmp-simd", "-fPIC", "-shared"]


def _cpu_flags() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("flags"):
                return line
    except OSError:
        pass
    return os.uname().machine


def cache_dir() -> Path:
    """Where the built libraries are kept ($FEPEN_KERNEL_CACHE, else ~/.cache/fepen)."""
    env = os.environ.get("FEPEN_KERNEL_CACHE")
    if env:
        return Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "fepen"


def _build(source: Path, cc: str, extra: tuple = ()) -> Path:
    flags = [*FLAGS, *extra]
    version = subprocess.run([cc, "--version"], capture_output=True, text=True, check=True).stdout
    key = hashlib.sha256(source.read_bytes() + " ".join(flags).encode() + version.encode() + _cpu_flags().encode())
    out = cache_dir() / f"{source.stem}-{key.hexdigest()[:16]}.so"
    if out.exists():
        return out
    out.parent.mkdir(parents=True, exist_ok=True)
    with replacing(out, ".so") as tmp:
        subprocess.run([cc, *flags, str(source), "-lm", "-o", str(tmp)], capture_output=True, text=True,
                       check=True)
    return out


def load(source: Path, extra: tuple = ()) -> tuple[ctypes.CDLL | None, str | None]:
    """Build (once) and load a C source.

    Args:
        source: the .c file. extra: compiler flags after FLAGS (e.g. "-ffp-contract=off" for a kernel that
            must round as numpy does, one operation at a time).

    Returns:
        (the library, None), or (None, why it could not be built or loaded).
    """
    try:
        return ctypes.CDLL(str(_build(source, os.environ.get("CC", "cc"), tuple(extra)))), None
    except (OSError, subprocess.CalledProcessError) as err:
        detail = (getattr(err, "stderr", "") or str(err)).strip()
        return None, f"{source.name} not built ({detail.splitlines()[-1] if detail else err})"
