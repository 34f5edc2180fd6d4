"""Files that are never half-written: write to a temporary name beside the file, rename over it when
complete (an atomic rename on POSIX), and remove the temporary file when the writing fails."""

from __future__ import annotations

import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def replacing(path, suffix: str = "") -> Iterator[Path]:
    """A temporary path to write ``path`` through.

    Args:
        path: the file to (re)place.
        suffix: an ending the writer needs to see (".npz" for numpy, ".msh" for gmsh, ".png").

    Yields:
        The temporary path; renamed over ``path`` when the block ends normally, removed when it raises.
    """
    path = Path(path)
    tmp = path.with_name(f"{path.name}.tmp{os.getpid()}{suffix}")
    try:
        yield tmp
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def sha256_file(path) -> str:
    """The SHA-256 of a file's bytes (hex), read in blocks: the checksum checkpoints and mesh-cache entries
    carry."""
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()
