"""Small C sources of fepen's hot loops, built once per machine with the system's C compiler and loaded with
ctypes (the solver's trial pass, the target law's point forces). Each has a Python (numba or numpy)
reference it is tested against, and is used only when it builds.
"""

from __future__ import annotations

import ctypes
import hashlib
import os
import stat
import subprocess
from pathlib import Path

from fepen.atomic import replacing

__all__ = ["FLAGS", "cache_dir", "load"]

#: no fast-math (NaN and inf must propagate); -fno-math-errno only lets sqrt be one instruction (errno is never
#: read), without which GCC keeps a loop that takes a square root scalar
FLAGS = ["-O3", "-march=native", "-fopenmp-simd", "-fno-math-errno", "-fPIC", "-shared"]


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


def _private(path: Path) -> bool:
    """Whether only this user (or root) can have written ``path``: owned by them, not a link, not writable by
    the group or others. A library that others could have replaced is code others could run as this user."""
    try:
        st = os.lstat(path)
    except OSError:
        return False
    return (not stat.S_ISLNK(st.st_mode) and st.st_uid in (os.getuid(), 0)
            and not st.st_mode & (stat.S_IWGRP | stat.S_IWOTH))


_own_dir: list[Path] = []


def _folder() -> Path:
    """cache_dir(), or, when others can write it, a private folder of this process's (one warning): a library
    is never loaded from where another user could have put it."""
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    if _private(folder):
        return folder
    if not _own_dir:
        import logging
        import tempfile

        _own_dir.append(Path(tempfile.mkdtemp(prefix="fepen-kernels-")))
        logging.getLogger("fepen").warning(f"the kernel cache {folder} can be written by other users: fepen builds "
                                           f"its C kernels in {_own_dir[0]} for this process instead")
    return _own_dir[0]


def _build(source: Path, cc: str, extra: tuple = ()) -> Path:
    flags = [*FLAGS, *extra]
    version = subprocess.run([cc, "--version"], capture_output=True, text=True, check=True).stdout
    key = hashlib.sha256(source.read_bytes() + " ".join(flags).encode() + version.encode() + _cpu_flags().encode())
    out = _folder() / f"{source.stem}-{key.hexdigest()[:16]}.so"
    if out.exists() and _private(out):
        return out
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
