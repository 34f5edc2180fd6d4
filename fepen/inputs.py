"""A user's input files, read without ever blocking or reading without bound: regular files only (a pipe, a
device, a socket or a folder is refused when opened, so that a FIFO named as a scene, a table, a profile or a CAD
body cannot hang a run), of at most a given size. Every reader of a user's file goes through here: the scene and
sweep files (fepen.scene), a sweep's table (fepen.studies.spec), a drawn profile and a CAD body (fepen.geometry).
"""

from __future__ import annotations

import os
import stat
from pathlib import Path
from typing import BinaryIO

from fepen.errors import InputError

__all__ = ["NotRegularFile", "open_input", "unreadable", "read_capped"]


def _name(path, limit: int = 200) -> str:
    """A path as the user wrote it, on one line (cut past ``limit`` characters)."""
    text = str(path)
    return text if text.isprintable() and len(text) <= limit else repr(text[:limit]) + ("..." if len(text) > limit
                                                                                          else "")


class NotRegularFile(OSError):
    """A user's input file that is not a regular file: a pipe, a device, a folder or a socket (open_input)."""


def _kind(mode: int) -> str:
    """What a file that is not a regular one is, in words."""
    for test, word in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a pipe"), (stat.S_ISCHR, "a device"),
                       (stat.S_ISBLK, "a device"), (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return word
    return "a special file"


def open_input(path) -> BinaryIO:
    """Open a user's input file for reading, refusing anything but a regular file without blocking: opened with
    O_NONBLOCK (a pipe without a writer opens at once instead of waiting for one for ever), then what was opened
    is asked (fstat), so a file swapped for a pipe between a check and the open is caught too.

    Args:
        path: the file (str or Path).

    Returns:
        The open binary file (a context manager; ``os.fstat(f.fileno()).st_size`` its size).

    Raises:
        NotRegularFile (an OSError) for a pipe, a device, a folder or a socket; OSError as open() raises it;
        ValueError for a name holding a NUL. :func:`unreadable` turns each into the one-line InputError.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOCTTY", 0) | getattr(os, "O_CLOEXEC", 0)
    fd = os.open(path, flags)
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise NotRegularFile(_kind(mode))
        return os.fdopen(fd, "rb")  # (O_NONBLOCK changes nothing in the reads of a regular file)
    except BaseException:
        os.close(fd)
        raise


def unreadable(err: Exception, path, key: str, what: str, missing: str | None = None) -> InputError:
    """The error of a user's input file :func:`open_input` could not open, naming ``key``.

    Args:
        err: what open_input raised (NotRegularFile, another OSError, or ValueError).
        path: the file. key: the key that names it. what: what the file is ("a scene file", "the profile").
        missing: the message when there is no such file (None: "cannot read PATH: No such file or directory").

    Returns:
        The InputError (to raise).
    """
    name = _name(path)
    if isinstance(err, NotRegularFile):
        return InputError(key, f"{name} is {err}, not a regular file: {what} is read from a regular file")
    if isinstance(err, FileNotFoundError) and missing is not None:
        return InputError(key, missing)
    return InputError(key, f"cannot read {name}: {getattr(err, 'strerror', None) or err}")


def read_capped(path: Path, limit: int, key: str, what: str, missing: str | None = None) -> bytes:
    """The bytes of a user's text file, refused (InputError naming ``key``) when it is not a regular file (a
    pipe, a device or a folder, checked without blocking: :func:`open_input`) or larger than ``limit``: never
    more than ``limit`` + 1 bytes are read.

    Args:
        path: the file. limit: the most bytes it may hold. key: the key that names it.
        what: what the file is, as the messages say it ("a scene file").
        missing: the message when there is no such file (:func:`unreadable`).

    Returns:
        The file's bytes.
    """
    try:
        with open_input(path) as fh:
            size = os.fstat(fh.fileno()).st_size
            data = b"" if size > limit else fh.read(limit + 1)
    except (OSError, ValueError) as err:
        raise unreadable(err, path, key, what, missing) from None
    if size > limit or len(data) > limit:
        raise InputError(key, f"{_name(path)} is larger than {limit >> 10} KiB, the most {what} "
                              "may be")
    return data


