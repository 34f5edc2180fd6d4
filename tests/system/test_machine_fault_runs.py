"""The machine's faults are exit 4 and named (issue 57 item 7), as whole processes: a C compiler given with
arguments or behind a wrapper, a missing compiler, a kernel cache that is a file or cannot be written, and an
address-space limit (``ulimit -v``, a batch system's h_vmem) too small for the libraries, for the mesh, or met
after the run directory is claimed. Each is one line on stderr and exit 4 (or a run that works), never exit 1,
a traceback or a segmentation fault; a claimed directory is left with run.json's outcome "fault" and neither
lock nor reserve. Each test takes a few seconds."""

import json
import os
import shlex
import shutil
import subprocess
import sys

import pytest

from fepen.studies import processes

RIGID = ["run", "--set", "effects.fidelity=rigid"]
DEFORMABLE = ["run", "--set", "mesh.size=0.006", "--set", "run.end_time=1e-4"]
LOCK, RESERVE = ".fepen.lock", ".fepen.reserve"
MIB = 1024  # ulimit -v counts KiB


def fepen(*args, limit_mib: float | None = None, script: str | None = None, timeout: float = 120, **env):
    """``python -m fepen ARGS`` (or ``python -c SCRIPT ARGS``) in bash, under ``ulimit -v LIMIT_MIB`` when given,
    with ``env`` added to the environment (a value None removes the variable)."""
    cmd = [sys.executable, *(["-c", script] if script else ["-m", "fepen"]), *map(str, args)]
    line = f"exec {shlex.join(cmd)}"
    if limit_mib is not None:
        line = f"ulimit -v {int(limit_mib * MIB)}; {line}"
    environment = processes.mpi_env()
    for key, value in env.items():
        if value is None:
            environment.pop(key, None)
        else:
            environment[key] = str(value)
    return subprocess.run(["bash", "-c", line], env=environment, capture_output=True, text=True,
                          cwd=processes.ROOT, timeout=timeout)


def one_fault_line(r, *words) -> str:
    """Exit 4 and one line on stderr, "fepen: stopped by a fault of the machine: ...", holding ``words``."""
    lines = r.stderr.splitlines()
    assert r.returncode == 4 and len(lines) == 1, (r.returncode, r.stderr[-3000:])
    assert lines[0].startswith("fepen: stopped by a fault of the machine: "), lines
    for w in words:
        assert w in lines[0], lines[0]
    return lines[0]


def left_clean(out, outcome="fault", exit_code=4) -> None:
    """A claimed directory after a stop: run.json's outcome and exit code, no lock, no reserve."""
    record = json.loads((out / "run.json").read_text())
    assert (record["outcome"], record["exit_code"]) == (outcome, exit_code), record
    assert not (out / LOCK).exists() and not (out / RESERVE).exists(), sorted(os.listdir(out))


def _gcc() -> str:
    found = shutil.which("gcc") or shutil.which("cc")
    assert found, "a C compiler is needed to build fepen's kernels"
    return found


def test_a_cc_with_arguments_and_a_wrapped_cc_run(tmp_path):
    """Before: CC="gcc -O2" and CC="ccache gcc" were each taken as one program name: "internal error ...
    RuntimeError: laws/target_kernel.c does not build ... No such file or directory: 'gcc -O2'", exit 1, even
    with every kernel built. Now both run (a wrapper script of our own plays ccache); the wrapper's libraries
    are the plain compiler's (one cache name), the option's their own."""
    wrap = tmp_path / "wrap"
    wrap.write_text('#!/bin/sh\nexec "$@"\n')
    wrap.chmod(0o755)
    cache, gcc = tmp_path / "kernels", _gcc()
    for i, cc in enumerate((f"{gcc} -O2", f"{wrap} {gcc}", gcc)):
        r = fepen(*RIGID, "--out", tmp_path / f"out{i}", CC=cc, FEPEN_KERNEL_CACHE=cache)
        assert r.returncode == 0 and not r.stderr.strip(), (cc, r.stderr[-2000:])
        assert json.loads((tmp_path / f"out{i}" / "summary.json").read_text())["outcome"] == "embedded"
    built = sorted(p.name for p in cache.glob("target_kernel-*.so"))  # -O2's, and gcc's (wrapped or not)
    assert len(built) == 2 and built[0].split("-")[:2] == built[1].split("-")[:2], built


def test_a_built_kernel_runs_without_the_compiler_and_none_built_is_exit_4(tmp_path):
    """Before: CC=/nonexistent stopped every run with exit 1 ("internal error ... No such file or directory:
    '/nonexistent'"), kernels built or not. Now the built kernels load without it (exit 0), and with none
    built it is exit 4 naming CC and what to do; a PATH without any C compiler names cc."""
    cache = tmp_path / "kernels"
    assert fepen(*RIGID, "--out", tmp_path / "built", FEPEN_KERNEL_CACHE=cache).returncode == 0
    r = fepen(*RIGID, "--out", tmp_path / "a", CC="/nonexistent", FEPEN_KERNEL_CACHE=cache)
    assert r.returncode == 0 and not r.stderr.strip(), r.stderr[-2000:]
    r = fepen(*RIGID, "--out", tmp_path / "b", CC="/nonexistent", FEPEN_KERNEL_CACHE=tmp_path / "empty")
    one_fault_line(r, "the C compiler CC='/nonexistent' cannot be run", "set CC to a C compiler that runs")
    bare = tmp_path / "bin"  # a PATH with everything of /usr/bin but the C compilers
    bare.mkdir()
    for entry in os.scandir("/usr/bin"):
        if not entry.name.startswith(("cc", "gcc", "c89", "c99", "clang", "tcc", "x86_64-linux-gnu-gcc")):
            os.symlink(entry.path, bare / entry.name)
    r = fepen(*RIGID, "--out", tmp_path / "c", CC=None, PATH=bare, FEPEN_KERNEL_CACHE=tmp_path / "empty2")
    one_fault_line(r, "the C compiler 'cc' cannot be run (cc: not found)", "install a C compiler")


@pytest.mark.parametrize("variable", ["FEPEN_KERNEL_CACHE", "XDG_CACHE_HOME"])
def test_a_kernel_cache_that_is_a_file_is_exit_4_naming_the_variable(tmp_path, variable):
    """Before: exit 1, "internal error ... [Errno 17] File exists: '/tmp/afile'" ("[Errno 20] Not a directory:
    '/tmp/afile/fepen'" for XDG_CACHE_HOME) inside "install a C compiler". Now exit 4 naming the variable."""
    afile = tmp_path / "afile"
    afile.write_text("")
    r = fepen(*RIGID, "--out", tmp_path / "out", **{"FEPEN_KERNEL_CACHE": None, variable: afile})
    one_fault_line(r, f"{variable}={afile}", "is not a directory", f"set {variable}")


def test_a_kernel_cache_that_cannot_be_written_is_exit_4(tmp_path):
    """Before: exit 1 ("internal error ... [Errno 13] Permission denied", as root on an immutable directory
    "[Errno 1] Operation not permitted"). Now exit 4 naming FEPEN_KERNEL_CACHE. A directory this user cannot
    write: mode 555, or, as root, one the kernel refuses to anyone (chattr +i; else /sys, which refuses a new
    directory)."""
    cache, immutable = tmp_path / "ro", False
    cache.mkdir()
    if os.geteuid() != 0:
        cache.chmod(0o555)
    else:
        immutable = subprocess.run(["chattr", "+i", str(cache)], capture_output=True).returncode == 0 \
            if shutil.which("chattr") else False
        if not immutable:
            cache = "/sys/fepen-kernels"
    try:
        r = fepen(*RIGID, "--out", tmp_path / "out", FEPEN_KERNEL_CACHE=cache)
    finally:
        if immutable:
            subprocess.run(["chattr", "-i", str(cache)], check=True)
        elif os.geteuid() != 0:
            cache.chmod(0o755)
    one_fault_line(r, f"FEPEN_KERNEL_CACHE={cache} cannot be written", "to a directory this user can write")


@pytest.mark.parametrize("limit", [100, 200, 300])
def test_a_limit_too_small_for_the_libraries_is_exit_4_naming_it(tmp_path, limit):
    """ulimit -v 100, 200, 300 MiB: numpy, LAPACK or LLVM cannot be mapped as they are imported. Before: exit
    1 ("internal error ... ImportError: liblapack.so.3: failed to map segment from shared object"), or exit 4
    "stopped by a fault of the machine: Success" (llvmlite's OSError). Now exit 4, "out of memory", the limit
    named; nothing is claimed."""
    out = tmp_path / "out"
    r = fepen(*RIGID, "--out", out, limit_mib=limit)
    one_fault_line(r, "out of memory: ", f"(the address-space limit ulimit -v is {limit} MiB)")
    assert not (out / LOCK).exists() and not (out / RESERVE).exists()


@pytest.mark.parametrize("limit", [700, 1000])
def test_a_deformable_run_past_the_limit_is_refused_before_meshing(tmp_path, limit):
    """A deformable run under ulimit -v 700 or 1000 MiB. Before: at 700 MiB a segmentation fault in gmsh's
    OpenBLAS thread (exit 139, or MPI_ABORT 59 after PETSc's "Caught signal number 11 SEGV"), leaving run.json
    "running", the lock and the reserve; at 1000 MiB "internal error ... ImportError: ... failed to map segment"
    or a MemoryError in the record's own writing. Now refused before gmsh starts and before the directory is
    claimed: exit 4, one line naming ulimit -v and the limit the run needs."""
    out = tmp_path / "out"
    r = fepen(*DEFORMABLE, "--out", out, limit_mib=limit)
    line = one_fault_line(r, f"the address-space limit ulimit -v is {limit} MiB", "raise ulimit -v")
    at_least = float(line.split("to at least ")[1].split(" MiB")[0])
    assert limit < at_least < 2000
    assert not (out / "run.json").exists() and not (out / LOCK).exists()


#: a rigid run whose RigidRun.run first lowers the address-space limit to what the process maps plus a little,
#: then does WHAT: a memory fault after the run directory is claimed, in a whole fepen process
AFTER_CLAIM = """
import resource, sys
from fepen.runs import rigid

def run(self):
    with open("/proc/self/status") as f:
        vm = next(int(line.split()[1]) for line in f if line.startswith("VmSize:")) * 1024
    resource.setrlimit(resource.RLIMIT_AS, (vm + (48 << 20), resource.getrlimit(resource.RLIMIT_AS)[1]))
    WHAT

rigid.RigidRun.run = run
from fepen.cli import console
sys.argv[0] = "fepen"
console()
"""


@pytest.mark.parametrize("what, words", [
    ("import numpy; numpy.ones(1 << 31)", "out of memory: Unable to allocate 16.0 GiB"),
    ("import dolfinx", "out of memory: loading lib"),
    ("import gmsh", "out of memory: loading libgmsh"),
], ids=["MemoryError", "ImportError", "OSError"])
def test_a_memory_fault_after_the_claim_leaves_the_directory_recorded(tmp_path, what, words):
    """Memory running out after the run directory is claimed: a MemoryError, and libraries that cannot be
    mapped as they are imported under the lowered limit (dolfinx's: an ImportError; gmsh's, which ctypes
    loads: an OSError without errno). Before: the MemoryError was exit 4 "out of memory" without the limit;
    dolfinx's ImportError exit 1, "internal error (a bug in fepen ...)", run.json's outcome "error"; gmsh's
    exit 4 "stopped by a fault of the machine: Success". Now each is exit 4, one line "out of memory: ..."
    naming the limit; run.json's outcome "fault" (exit code 4), no lock, no reserve."""
    out = tmp_path / "out"
    r = fepen(*RIGID, "--out", out, script=AFTER_CLAIM.replace("WHAT", what), OPENBLAS_NUM_THREADS=1)
    one_fault_line(r, words, "(the address-space limit ulimit -v is ")
    left_clean(out)


def test_memory_exhausted_by_the_run_still_leaves_the_directory_recorded(tmp_path):
    """Memory exhausted by the run's own objects (64 KiB at a time until none is left), held by the traceback
    while the directory's record is written: run.json's outcome "fault", no lock, no reserve. Before, the record's
    writing failed on the same MemoryError (in files.versions(), importing fepen.dolfinx_api): run.json stayed
    "running", the lock and the reserve were left. Now the failed run's frames are cleared first, and the record
    is written without the versions if memory is still short."""
    out = tmp_path / "out"
    hog = "hog = []\n    while True:\n        hog.append(bytearray(1 << 16))"
    r = fepen(*RIGID, "--out", out, script=AFTER_CLAIM.replace("WHAT", hog), OPENBLAS_NUM_THREADS=1)
    one_fault_line(r, "out of memory: a memory allocation failed (the address-space limit ulimit -v is ")
    left_clean(out)


def test_version_keys_and_runs_under_a_generous_limit(tmp_path):
    """fepen --version, fepen keys, a rigid run (under ulimit -v 2 GiB) and a deformable run (4 GiB) work as
    without a limit."""
    r = fepen("--version", limit_mib=2048)
    assert r.returncode == 0 and r.stdout.startswith("fepen ") and not r.stderr.strip(), r.stderr[-2000:]
    r = fepen("keys", limit_mib=2048)
    assert r.returncode == 0 and "mesh.size" in r.stdout and not r.stderr.strip(), r.stderr[-2000:]
    r = fepen(*RIGID, "--out", tmp_path / "rigid", limit_mib=2048)
    assert r.returncode == 0 and not r.stderr.strip(), r.stderr[-2000:]
    left_clean(tmp_path / "rigid", "finished", 0)
    r = fepen(*DEFORMABLE, "--out", tmp_path / "deformable", limit_mib=4096, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    left_clean(tmp_path / "deformable", "finished", 0)
