"""fepen's compiled code behind one door (dolfinx's jit.py is the example): every C source fepen builds is named
in one table (KERNELS: its file beside the Python module it serves, its header, its flags, the functions Python
binds), built once per machine with the system's C compiler into one cache, loaded and bound here, and switched
by one rule. A kernel's interface is its header: the ctypes signatures are read from its prototypes
(c_prototypes), and every layout Python shares with it (a parameter vector, a buffer, result codes) is read from
its enums (c_enums, enum_values) or, where Python keeps a list of names, held to them member by member when the
kernel is loaded (shares, check_layout): a header and its Python that disagree stop fepen with a LayoutError
naming both.

    kernel(name)   the bound library (built on first use), or None for an optional kernel that is off or does
                   not build (why_not(name) says why); a required kernel that does not build raises
    FEPEN_KERNEL   "python" (also "numpy", "numba"): every optional kernel off, their Python references used
                   (the rigid body's point arithmetic, the batched rigid shots, the deformable step's C passes);
                   the required kernels hold rules that exist only in C (the target law, the material law,
                   the stop rules) and stay on
    FEPEN_KERNEL_CACHE   where the libraries are kept (else $XDG_CACHE_HOME/fepen, ~/.cache/fepen); a folder others
                   can write is never loaded from (a private one is used instead, with one warning)
    CC             the C compiler's command line, split as a shell splits it: CC="gcc -O2", CC="ccache gcc"
                   (default: cc)

Every library carries, in its cache name, a hash of its source (and of what it #includes), its flags and the
CPU's flags, then a hash of the compiler (its ``--version`` text, which a wrapper such as ccache passes through)
and one of the options CC adds, if any: an edited source, another machine, another compiler or other options
build again. Where the compiler cannot be run (not installed, CC naming no program), a library of the same
source, flags, CPU and CC options that an earlier compiler built is loaded; with none, the required kernels stop
fepen with a MachineFault (exit 4) naming the compiler and what to do, as a kernel cache that is not a directory
or cannot be written does.
"""

from __future__ import annotations

import ctypes
import functools
import hashlib
import os
import re
import shlex
import stat
import subprocess
from dataclasses import dataclass
from pathlib import Path

from fepen.atomic import replacing
from fepen.errors import MachineFault, OutOfMemory, describe_os_error, out_of_memory

__all__ = ["FLAGS", "KERNELS", "Kernel", "cache_dir", "compiler", "kernel", "library_path", "why_not", "python_only",
           "load", "c_enums", "c_prototypes", "enum_values", "check_layout", "shares", "check_layouts", "signatures",
           "LayoutError", "C_TYPES"]

#: no fast-math (NaN and inf must propagate); -fno-math-errno only lets sqrt be one instruction (errno is never
#: read), without which GCC keeps a loop that takes a square root scalar
FLAGS = ["-O3", "-march=native", "-fopenmp-simd", "-fno-math-errno", "-fPIC", "-shared"]
#: no fused multiply-adds: a vector loop's body and its scalar remainder contract differently, so a cell would
#: round otherwise by where it falls in its block (docs/theory.md §3.4), and the batched rigid path must round
#: as numpy does, one operation at a time
NO_CONTRACT = ("-ffp-contract=off",)


@dataclass(frozen=True)
class Kernel:
    """One C source: where it and its header are (relative to the package), its extra flags, whether fepen can
    do without it, and the functions Python binds, by name: their ctypes signatures are the header's prototypes
    (c_prototypes), as ffcx's jit reads its declarations instead of typing them again."""

    source: str
    header: str
    flags: tuple = ()
    required: bool = False
    functions: tuple = ()


#: every compiled kernel fepen builds
KERNELS = {
    "target": Kernel("laws/target_kernel.c", "laws/target_kernel.h", (), True,
                     ("point_forces", "cavity_wall_stress", "tunnel_sectors", "tunnel_probe", "strength_field")),
    "materials": Kernel("laws/materials_kernel.c", "laws/materials_kernel.h", NO_CONTRACT, True,
                        ("material_radial_return", "material_yield_stress")),
    "events": Kernel("runs/events_kernel.c", "runs/events_kernel.h", NO_CONTRACT, True, ("penetration_outcome",)),
    "rigid_body": Kernel("laws/rigid_kernel.c", "laws/rigid_kernel.h", (), False, ("rigid_points", "force_moment")),
    "rigid_batch": Kernel("runs/rigid_batch.c", "runs/rigid_batch.h", NO_CONTRACT, False,
                          ("rigid_batch", "rigid_step", "rigid_stop_back", "batch_law")),
    "cells": Kernel("solver/cell_kernel.c", "solver/cell_kernel.h", NO_CONTRACT, False,
                    ("update_begin", "update_end", "nodal_pressure", "scatter_volumes", "scatter_forces",
                     "kinematics_pass", "cell_pass", "facet_kinematics")),
}
PACKAGE = Path(__file__).resolve().parent
_LOADED: dict[str, ctypes.CDLL | None] = {}
_WHY_NOT: dict[str, str] = {}


def c_enums(source) -> dict[str, int]:
    """The values of every ``enum { ... };`` member in a C source file, read from the text (as ffcx reads its
    declarations from its header): the layouts the Python side shares with a kernel are declared once, in C.
    Comments are dropped; a member is its predecessor + 1 or its ``= expression`` of integers and earlier
    members (+, -, *).

    Args:
        source: the .c or .h file (a path).

    Returns:
        {member: value}.
    """
    text = _code(source)
    out: dict[str, int] = {}
    for body in re.findall(r"\benum\s*(?:\w+\s*)?\{([^}]*)\}", text):
        value = -1
        for item in (x.strip() for x in body.split(",")):
            if not item:
                continue
            name, _, expr = (t.strip() for t in item.partition("="))
            if expr:
                if not re.fullmatch(r"[\w\s+*-]+", expr):
                    raise ValueError(f"{source}: enum member {name} = {expr}: not an integer expression")
                value = int(eval(expr, {"__builtins__": {}}, dict(out)))  # noqa: S307 - integers and names only
            else:
                value += 1
            out[name] = value
    return out


def _code(source) -> str:
    """A C file's text without its comments."""
    text = re.sub(r"/\*.*?\*/", " ", Path(source).read_text(), flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


#: the C types of a prototype's values as ctypes takes them (any pointer is a c_void_p; void, a result only, is
#: None): what fepen's headers use, nothing more
C_TYPES = {"int32_t": ctypes.c_int32, "int": ctypes.c_int32, "double": ctypes.c_double}
_QUALIFIERS = {"const", "restrict", "volatile", "__restrict", "__restrict__"}


class LayoutError(RuntimeError):
    """A C header and the Python that shares its layout or calls its functions disagree (a bug of fepen's own:
    the message names the header and the member or function)."""


def _c_type(header, function: str, decl: str, result: bool = False):
    """The ctypes type of one declaration (a parameter with or without its name, or a result's type)."""
    tokens = [w for w in re.findall(r"\w+|\*|\S", decl) if w not in _QUALIFIERS]
    stars = tokens.count("*")
    words = [w for w in tokens if w != "*"]
    if not words or not all(re.fullmatch(r"\w+", w) for w in words):
        raise LayoutError(f"{header}: {function}: cannot read the declaration {decl.strip()!r}")
    base = " ".join(words if result or len(words) == 1 else words[:-1])
    if stars:
        return ctypes.c_void_p
    if result and base == "void":
        return None
    if base not in C_TYPES:
        raise LayoutError(f"{header}: {function}: the C type {base!r} of {decl.strip()!r} has no ctypes type here "
                          f"(fepen.native.C_TYPES knows {', '.join(C_TYPES)} and pointers)")
    return C_TYPES[base]


def c_prototypes(header) -> dict[str, tuple[list, object]]:
    """The ctypes signatures of the functions a C header declares, read from its prototypes (as ffcx's jit reads
    its declarations rather than typing them again): int32_t and int are c_int32, double c_double, any pointer
    c_void_p, a void result None. Preprocessor lines, comments, enums and typedefs are passed over.

    Args:
        header: the .h file (a path).

    Returns:
        {function: (argtypes, restype)}, in the header's order.

    Raises:
        LayoutError: a declaration this reader does not know (another C type, a function pointer, a definition),
            naming the header and the function.
    """
    text = "\n".join(ln for ln in _code(header).splitlines() if not ln.lstrip().startswith("#"))
    out: dict[str, tuple[list, object]] = {}
    for statement in (" ".join(s.split()) for s in text.split(";")):
        if "(" not in statement or statement.startswith(("typedef", "enum")):
            continue
        m = re.fullmatch(r"([\w\s*]+?)\s*\b(\w+)\s*\(([^()]*)\)", statement)
        if m is None:
            name = re.search(r"(\w+)\s*\(", statement)
            raise LayoutError(f"{header}: {name.group(1) if name else statement[:40]}: not a prototype this reader "
                              f"knows: {statement[:80]!r}")
        result, name, params = m.groups()
        params = [] if params.strip() in ("", "void") else params.split(",")
        out[name] = ([_c_type(header, name, d) for d in params], _c_type(header, name, result, result=True))
    return out


def enum_values(header, *names: str) -> tuple[int, ...]:
    """The values of the named members of a header's enums (c_enums), in the order asked.

    Raises:
        LayoutError: a member the header does not declare, naming the header and the member."""
    enums = c_enums(header)
    missing = [n for n in names if n not in enums]
    if missing:
        raise LayoutError(f"{header} declares no enum member {missing[0]} (fepen's Python reads it)")
    return tuple(enums[n] for n in names)


def check_layout(header, prefix: str, members) -> None:
    """Python's copy of one of a header's enums against the header, member by member: each member where the
    widths before it put it, every member of the header's enum with that prefix named, in its order, and
    ``{prefix}COUNT`` the total.

    Args:
        header: the .h file. prefix: the enum's members' prefix ("S_"). members: (member, width) pairs, in
            Python's order (a width of 3: a member that holds three numbers).

    Raises:
        LayoutError: naming the header and the first member that disagrees (its value in each).
    """
    enums = c_enums(header)
    at = 0
    for member, width in members:
        if member not in enums:
            raise LayoutError(f"{header} declares no enum member {member}, which fepen's Python puts at {at}")
        if enums[member] != at:
            raise LayoutError(f"{header}: enum member {member} is {enums[member]}, but fepen's Python puts it at {at}")
        at += width
    named = {m for m, _ in members}
    extra = [m for m in enums if m.startswith(prefix) and m not in named and m != prefix + "COUNT"]
    if extra:
        raise LayoutError(f"{header}: enum member {extra[0]} = {enums[extra[0]]} is not in fepen's Python copy")
    count = enums.get(prefix + "COUNT")
    if count != at:
        raise LayoutError(f"{header}: enum member {prefix}COUNT is {count}, but fepen's Python has {at} numbers")


#: the layouts Python shares with each kernel (shares()): checked when the kernel is loaded
_SHARED: dict[str, list[tuple[str, tuple]]] = {}


def shares(name: str, prefix: str, members) -> None:
    """Declare that Python lays out one of a kernel's enums (its header's members with ``prefix``) as
    ``members`` ((member, width) pairs, in order): check_layout holds the two together when the kernel is
    loaded, and at once when it already is.

    Raises:
        LayoutError: the kernel is loaded and its header disagrees."""
    entry = (prefix, tuple((m, int(w)) for m, w in members))
    _SHARED.setdefault(name, []).append(entry)
    if _LOADED.get(name) is not None:
        check_layout(PACKAGE / KERNELS[name].header, *entry)


def check_layouts(name: str) -> None:
    """Every layout Python shares with the kernel ``name`` (shares()) against its header.

    Raises:
        LayoutError: the first that disagrees."""
    for prefix, members in _SHARED.get(name, ()):
        check_layout(PACKAGE / KERNELS[name].header, prefix, members)


def signatures(name: str) -> dict[str, tuple[list, object]]:
    """The ctypes signatures of the functions a kernel binds, from its header's prototypes.

    Raises:
        LayoutError: a function the header does not declare, or a declaration c_prototypes cannot read."""
    k = KERNELS[name]
    declared = c_prototypes(PACKAGE / k.header)
    missing = [fn for fn in k.functions if fn not in declared]
    if missing:
        raise LayoutError(f"{PACKAGE / k.header} declares no function {missing[0]} (fepen.native.KERNELS[{name!r}] "
                          "binds it)")
    return {fn: declared[fn] for fn in k.functions}


def python_only() -> bool:
    """FEPEN_KERNEL asks for the Python references of the optional kernels ("python", "numpy" or "numba")."""
    return os.environ.get("FEPEN_KERNEL", "").lower() in ("python", "numpy", "numba")


def kernel(name: str) -> ctypes.CDLL | None:
    """The bound library of a kernel of KERNELS, built and loaded once per process.

    Returns:
        The ctypes library with its functions' signatures set, or None for an optional kernel that
        FEPEN_KERNEL turns off or that does not build (why_not says which).

    Raises:
        MachineFault: a required kernel that neither builds nor was built before (no C compiler, a cache that
            cannot be written: the message names the compiler or the variable and what to do); OutOfMemory: a
            library that cannot be mapped (ulimit -v), optional or not; LayoutError: its header and the Python
            that binds it or shares its layouts disagree.
    """
    if name in _LOADED:
        return _LOADED[name]
    k = KERNELS[name]
    lib = None
    if not k.required and python_only():
        _WHY_NOT[name] = f"FEPEN_KERNEL={os.environ.get('FEPEN_KERNEL')}"
    else:
        try:
            lib = _load(PACKAGE / k.source, tuple(k.flags))
        except MachineFault as err:
            if k.required or isinstance(err, OutOfMemory):
                raise
            _WHY_NOT[name] = str(err)
        else:
            for fn, (args, res) in signatures(name).items():
                getattr(lib, fn).argtypes = args
                getattr(lib, fn).restype = res
            check_layouts(name)
    _LOADED[name] = lib
    return lib


def library_path(name: str) -> str:
    """The file of a kernel's built library (kernel(name) built it)."""
    k = KERNELS[name]
    return str(_build(PACKAGE / k.source, tuple(compiler()), tuple(k.flags)))


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
    """Where the built libraries are kept ($FEPEN_KERNEL_CACHE, else $XDG_CACHE_HOME/fepen, ~/.cache/fepen).

    Raises:
        MachineFault: none of the three is known (no HOME, and no home directory in the user database)."""
    env = os.environ.get("FEPEN_KERNEL_CACHE")
    if env:
        return Path(env)
    try:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    except RuntimeError:  # Path.home(): "Could not determine home directory"
        raise MachineFault("no home directory to keep fepen's C kernels in: set FEPEN_KERNEL_CACHE to a directory "
                           "this user can write") from None
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


def _cache_fault(folder: Path, err: OSError) -> MachineFault:
    """The MachineFault of a kernel cache that cannot be made or written, naming the variable that chose it."""
    memory = out_of_memory(err)
    if memory is not None:
        return memory
    env = os.environ
    if env.get("FEPEN_KERNEL_CACHE"):
        where, do = f"FEPEN_KERNEL_CACHE={env['FEPEN_KERNEL_CACHE']}", "set FEPEN_KERNEL_CACHE to a directory"
    elif env.get("XDG_CACHE_HOME"):
        where = f"{folder} (from XDG_CACHE_HOME={env['XDG_CACHE_HOME']})"
        do = "set XDG_CACHE_HOME, or FEPEN_KERNEL_CACHE, to a directory"
    else:
        where, do = str(folder), "set FEPEN_KERNEL_CACHE to a directory"
    what = ("is not a directory" if isinstance(err, (FileExistsError, NotADirectoryError))
            else f"cannot be written ({describe_os_error(OSError(err.errno, err.strerror))})")  # the folder named
    return MachineFault(f"the C kernels' cache {where} {what}: {do} this user can write (fepen builds its C "
                        "kernels there, once per machine)")


def _folder() -> Path:
    """cache_dir(), or, when others can write it, a private folder of this process's (one warning): a library
    is never loaded from where another user could have put it.

    Raises:
        MachineFault: the cache is not a directory (FEPEN_KERNEL_CACHE or XDG_CACHE_HOME naming a file) or
            cannot be made."""
    folder = cache_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise _cache_fault(folder, err) from None
    if not folder.is_dir():  # a link to a file
        raise _cache_fault(folder, NotADirectoryError(20, "Not a directory", str(folder)))
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


def compiler() -> list[str]:
    """The C compiler's command line: $CC split as a shell splits it (CC="gcc -O2", CC="ccache gcc"), else cc.

    Raises:
        MachineFault: CC that is not a command line (an unclosed quote)."""
    text = os.environ.get("CC", "")
    try:
        words = shlex.split(text)
    except ValueError as err:
        raise MachineFault(f"CC={text!r} is not a command line ({err}): set CC to a C compiler, e.g. CC=gcc") from None
    return words or ["cc"]


def _named(cc: tuple) -> str:
    """The compiler as a message names it: "CC='gcc -O2'", or "'cc'" when CC is not set."""
    return f"CC={os.environ['CC']!r}" if os.environ.get("CC", "").strip() else repr(shlex.join(cc))


def _options(cc: tuple) -> str:
    """The options CC adds to the compiler (CC="gcc -O2": "-O2"; CC="ccache gcc": none): its libraries are other
    libraries, named apart (_build)."""
    return " ".join(w for w in cc[1:] if w.startswith("-"))


@functools.lru_cache(maxsize=8)
def _identity(cc: tuple) -> tuple[str | None, str]:
    """What names the compiler in a library's cache name: its ``--version`` text (a wrapper such as ccache answers
    with the compiler's); a program that has no --version is named by its command line. Asked once per process
    (a subprocess costs tens of milliseconds).

    Returns:
        (the identity, "") or, when the compiler cannot be run, (None, why: "not found", "permission denied").
    """
    try:
        answer = subprocess.run([*cc, "--version"], capture_output=True, text=True)
    except OSError as err:
        memory = out_of_memory(err)
        if memory is not None:
            raise memory from err
        return None, f"{cc[0]}: not found" if isinstance(err, FileNotFoundError) else describe_os_error(err)
    return (answer.stdout if answer.returncode == 0 and answer.stdout.strip() else shlex.join(cc)), ""


def _hash(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:8]


def _built_before(folder: Path, stem: str, base: str, options: str) -> Path | None:
    """The newest private library of this source, flags, CPU and CC options that any compiler built, or None."""
    tail = f"-{_hash(options)}.so" if options else ".so"
    found = [p for p in folder.glob(f"{stem}-{base}-*.so") if _private(p) and p.is_file()
             and p.name.endswith(tail) and len(p.name) == len(f"{stem}-{base}-") + 8 + len(tail)]
    return max(found, key=lambda p: p.stat().st_mtime_ns, default=None)


def _build(source: Path, cc: tuple, extra: tuple = ()) -> Path:
    """The library of ``source`` built by the compiler ``cc`` (its words) with FLAGS and ``extra``: from the cache,
    else built into it (replaced whole), else, when ``cc`` cannot be run, one an earlier compiler built.

    Raises:
        MachineFault: no compiler and no library built before, a compiler that fails, a cache that cannot be
            written (each naming what to do); OutOfMemory.
    """
    flags = [*FLAGS, *extra]
    folder = _folder()
    base = hashlib.sha256(_source_bytes(source) + " ".join(flags).encode() + _cpu_flags().encode()).hexdigest()[:16]
    identity, why = _identity(cc)
    options = _options(cc)
    if identity is None:  # no compiler: a library of this very source, flags, CPU and CC options serves
        built = _built_before(folder, source.stem, base, options)
        if built is not None:
            return built
        what = ("set CC to a C compiler that runs (e.g. CC=gcc), or install one" if "CC=" in _named(cc) else
                "install a C compiler (gcc or clang), or set CC to one")
        raise MachineFault(f"the C compiler {_named(cc)} cannot be run ({why}), and fepen's C kernel {source.name} "
                           f"is not built yet in {folder}: {what}; fepen builds its kernels once per machine")
    out = folder / f"{source.stem}-{base}-{_hash(identity)}{'-' + _hash(options) if options else ''}.so"
    if out.exists() and _private(out):
        return out
    try:
        with replacing(out, ".so") as tmp:
            done = subprocess.run([*cc, *flags, str(source), "-lm", "-o", str(tmp)], capture_output=True, text=True)
            if done.returncode != 0:
                said = (done.stderr or done.stdout).strip().splitlines()
                said = [ln for ln in said if "error" in ln.lower()] or said[-1:] or ["no message"]
                raise MachineFault(f"the C compiler {_named(cc)} failed on fepen's C kernel {source.name} (exit "
                                   f"{done.returncode}: {said[0].strip()}): set CC to a working C compiler (gcc or "
                                   "clang)")
    except MachineFault:
        raise
    except OSError as err:  # the cache that cannot be written, a full disk, no memory to start the compiler
        raise _cache_fault(folder, err) from None
    return out


def _load(source: Path, extra: tuple = ()) -> ctypes.CDLL:
    """Build (once) and load a C source.

    Raises:
        MachineFault: as _build, or a library that does not load; OutOfMemory: one that cannot be mapped."""
    path = _build(source, tuple(compiler()), tuple(extra))
    try:
        return ctypes.CDLL(str(path))
    except OSError as err:
        memory = out_of_memory(err)
        if memory is not None:
            raise memory from err
        raise MachineFault(f"fepen's C kernel {path} does not load ({describe_os_error(err)}): remove it, and "
                           "fepen builds it again") from err


def load(source: Path, extra: tuple = ()) -> tuple[ctypes.CDLL | None, str | None]:
    """Build (once) and load a C source (kernel() for fepen's own; this for a test's).

    Args:
        source: the .c file. extra: compiler flags after FLAGS (e.g. "-ffp-contract=off" for a kernel that
            must round as numpy does, one operation at a time).

    Returns:
        (the library, None), or (None, why it could not be built or loaded: the MachineFault's message).

    Raises:
        OutOfMemory: the library cannot be mapped (ulimit -v): the process has no memory to go on with.
    """
    try:
        return _load(source, tuple(extra)), None
    except OutOfMemory:
        raise
    except MachineFault as err:
        return None, str(err)
