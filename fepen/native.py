"""fepen's compiled code behind one door (dolfinx's jit.py is the example): every C source fepen builds is named
in one table (KERNELS: its file beside the Python module it serves, its flags, its functions' ctypes signatures),
built once per machine with the system's C compiler into one cache, loaded and bound here, and switched by one
rule.

    kernel(name)   the bound library (built on first use), or None for an optional kernel that is off or does
                   not build (why_not(name) says why); a required kernel that does not build raises
    FEPEN_KERNEL   "python" (also "numpy", "numba"): every optional kernel off, their Python references used
                   (the rigid body's point arithmetic, the batched rigid shots, the deformable step's C passes);
                   the required kernels hold rules that exist only in C (the target law, the material law,
                   the stop rules) and stay on
    FEPEN_KERNEL_CACHE   where the libraries are kept (else $XDG_CACHE_HOME/fepen, ~/.cache/fepen); a folder others
                   can write is never loaded from (a private one is used instead, with one warning)

Every library carries, in its cache name, a hash of its source (and of what it #includes), its flags, the
compiler's version and the CPU's flags: an edited source or another machine builds again.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import re
import stat
import subprocess
from dataclasses import dataclass, field
from pathlib import Path

from fepen.atomic import replacing

__all__ = ["FLAGS", "KERNELS", "Kernel", "cache_dir", "kernel", "library_path", "why_not", "python_only", "load"]

#: no fast-math (NaN and inf must propagate); -fno-math-errno only lets sqrt be one instruction (errno is never
#: read), without which GCC keeps a loop that takes a square root scalar
FLAGS = ["-O3", "-march=native", "-fopenmp-simd", "-fno-math-errno", "-fPIC", "-shared"]
#: no fused multiply-adds: a vector loop's body and its scalar remainder contract differently, so a cell would
#: round otherwise by where it falls in its block (docs/theory.md §3.4), and the batched rigid path must round
#: as numpy does, one operation at a time
NO_CONTRACT = ("-ffp-contract=off",)

_i32, _vp, _dbl = ctypes.c_int32, ctypes.c_void_p, ctypes.c_double


@dataclass(frozen=True)
class Kernel:
    """One C source: where it is (relative to the package), its extra flags, whether fepen can do without it,
    and its functions' signatures ({name: (argtypes, restype)})."""

    source: str
    flags: tuple = ()
    required: bool = False
    functions: dict = field(default_factory=dict)


#: every compiled kernel fepen builds
KERNELS = {
    "target": Kernel("laws/target_kernel.c", (), True, {
        "point_forces": ([_i32, *[_vp] * 10, _i32, _vp, _vp, _vp, _vp, _vp], _i32),
        "cavity_wall_stress": ([_dbl] * 3, _dbl),
        "tunnel_sectors": ([_i32, _vp, _vp, _i32, _vp, _vp], None)}),
    "materials": Kernel("laws/materials_kernel.c", NO_CONTRACT, True, {
        "material_radial_return": ([_dbl] * 5 + [_vp, _vp], _dbl),
        "material_yield_stress": ([_dbl] * 3 + [_vp], _dbl)}),
    "events": Kernel("runs/events_kernel.c", NO_CONTRACT, True, {
        "penetration_outcome": ([_dbl, _dbl, _vp, _vp, _dbl, _dbl, _dbl, _i32, _dbl, _vp], _i32)}),
    "rigid_body": Kernel("laws/rigid_kernel.c", (), False, {
        "rigid_points": ([_i32, *[_vp] * 10], None), "force_moment": ([_i32, _vp, _vp, _vp], None)}),
    "rigid_batch": Kernel("runs/rigid_batch.c", NO_CONTRACT, False, {
        "rigid_batch": ([_i32, _i32, *[_vp] * 8, _i32, _vp, _vp, _vp, _vp, _i32, _vp, _vp, _vp, _i32, _i32, _vp], _i32),
        "batch_law": ([_i32, *[_vp] * 11, _i32, _vp, _vp], None)}),
    "cells": Kernel("solver/cell_kernel.c", NO_CONTRACT, False, {
        "update_begin": ([_i32, _i32, _dbl, _dbl, *[_vp] * 9], None),
        "update_end": ([_i32, *[_vp] * 7], None),
        "nodal_pressure": ([_i32, _vp, _vp, _vp, _i32, _vp], None),
        "scatter_volumes": ([_i32, _vp, _vp, _vp, _dbl, _i32, _i32, _vp], None),
        "scatter_forces": ([_i32, _vp, _vp, _dbl, _i32, _vp], None),
        "kinematics_pass": ([_i32, *[_vp] * 6, _i32, _vp, _vp, _vp, _dbl, _i32, _i32, _vp], None),
        "cell_pass": ([_i32, _vp, _vp, _dbl, _vp, _vp, _vp, _i32, *[_vp] * 8, _dbl, _i32, _vp, _vp], _i32),
        "facet_kinematics": ([_i32, *[_vp] * 11], None)}),
}
PACKAGE = Path(__file__).resolve().parent
_LOADED: dict[str, ctypes.CDLL | None] = {}
_WHY_NOT: dict[str, str] = {}


def python_only() -> bool:
    """FEPEN_KERNEL asks for the Python references of the optional kernels ("python", "numpy" or "numba")."""
    return os.environ.get("FEPEN_KERNEL", "").lower() in ("python", "numpy", "numba")


def kernel(name: str) -> ctypes.CDLL | None:
    """The bound library of a kernel of KERNELS, built and loaded once per process.

    Returns:
        The ctypes library with its functions' signatures set, or None for an optional kernel that
        FEPEN_KERNEL turns off or that does not build (why_not says which).

    Raises:
        RuntimeError: a required kernel that does not build (fepen needs a C compiler: cc, or $CC).
    """
    if name in _LOADED:
        return _LOADED[name]
    k = KERNELS[name]
    lib = None
    if not k.required and python_only():
        _WHY_NOT[name] = f"FEPEN_KERNEL={os.environ.get('FEPEN_KERNEL')}"
    else:
        lib, why = load(PACKAGE / k.source, k.flags)
        if lib is None:
            if k.required:
                raise RuntimeError(f"{k.source} does not build, and fepen needs it ({why}): install a C compiler "
                                   "(cc, or set CC)")
            _WHY_NOT[name] = why
        else:
            for fn, (args, res) in k.functions.items():
                getattr(lib, fn).argtypes = args
                getattr(lib, fn).restype = res
    _LOADED[name] = lib
    return lib


def library_path(name: str) -> str:
    """The file of a kernel's built library (kernel(name) built it)."""
    k = KERNELS[name]
    return str(_build(PACKAGE / k.source, os.environ.get("CC", "cc"), tuple(k.flags)))


def why_not(name: str) -> str | None:
    """Why a kernel is not used (None when it is)."""
    kernel(name)
    return _WHY_NOT.get(name)


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


def _source_bytes(source: Path, seen=None) -> bytes:
    """A source and every file it #includes by a quoted path, for the cache key."""
    seen = set() if seen is None else seen
    if source in seen:
        return b""
    seen.add(source)
    text = source.read_bytes()
    out = text
    for inc in re.findall(rb'#include\s+"([^"]+)"', text):
        path = (source.parent / inc.decode()).resolve()
        if path.is_file():
            out += _source_bytes(path, seen)
    return out


@functools.lru_cache(maxsize=8)
def _compiler(cc: str) -> str:
    """The compiler's version text (asked once per process: a subprocess costs tens of milliseconds)."""
    return subprocess.run([cc, "--version"], capture_output=True, text=True, check=True).stdout


def _build(source: Path, cc: str, extra: tuple = ()) -> Path:
    flags = [*FLAGS, *extra]
    version = _compiler(cc)
    key = hashlib.sha256(_source_bytes(source) + " ".join(flags).encode() + version.encode()
                         + _cpu_flags().encode())
    out = _folder() / f"{source.stem}-{key.hexdigest()[:16]}.so"
    if out.exists() and _private(out):
        return out
    with replacing(out, ".so") as tmp:
        subprocess.run([cc, *flags, str(source), "-lm", "-o", str(tmp)], capture_output=True, text=True,
                       check=True)
    return out


def load(source: Path, extra: tuple = ()) -> tuple[ctypes.CDLL | None, str | None]:
    """Build (once) and load a C source (kernel() for fepen's own; this for a test's).

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
