"""fepen's one CSV writer (issue 60): every table a run or a study writes (history.csv, probes.csv,
accelerations.csv, strains.csv, hazard.csv, charge_sections.csv, nose_profile.csv, sweep.csv, the studies'
tables) goes through ``text`` or ``write`` here, with one number format and one way of replacing the file.

The number format: a real number is written with the table's significant digits (``%.<digits>g``), or, with
``digits=None``, as the shortest text that reads back to the same double (Python's ``repr``); an integer as
itself; a truth value as ``true``/``false`` (as in TOML); an absent value (None) as an empty cell; text as it is,
quoted by the csv module when it holds a comma or a quote. Each row is formatted once (``Rows``): a table that
grows by rows (a run's history, written again at every output) formats only its new rows, and the file is
replaced whole and atomically, so that it always holds its last complete version and a resumed run or study
writes it again from the rows it has.
"""

from __future__ import annotations

import csv
import io
import numbers
from pathlib import Path

from mpi4py import MPI

from fepen.io import files

__all__ = ["DIGITS", "cell", "Rows", "text", "write"]

#: the significant digits of a run's tables (history.csv, accelerations.csv, strains.csv, ...): the nearest
#: 1e-9 of each number, far below any physical resolution and above the round-off a comparison sees
DIGITS = 9


def cell(v, digits: int | None = DIGITS) -> str:
    """One cell's text.

    Args:
        v: the value (a number, numpy's included, a truth value, text or None).
        digits: significant digits of a real number; None: the shortest text that reads back exactly.

    Returns:
        The cell, before the csv module's quoting.
    """
    if v is None:
        return ""
    if isinstance(v, str):
        return v
    if isinstance(v, bool) or type(v).__name__ == "bool_":
        return "true" if v else "false"
    if isinstance(v, numbers.Integral):
        return str(int(v))
    if isinstance(v, numbers.Real):
        return repr(float(v)) if digits is None else f"{float(v):.{digits}g}"
    return str(v)


def _cells(row, columns, digits) -> list[str]:
    values = [row.get(c) for c in columns] if isinstance(row, dict) else row
    return [cell(v, digits) for v in values]


class Rows:
    """A growing table's rows, each formatted once. ``of(rows)`` keeps the text of the rows it formatted while the
    list starts with the same row objects; any other change (a row replaced or removed) formats them all again.

    Args:
        columns: the table's columns (dict rows are read by them). digits: as ``cell``. newline: the line end.
    """

    def __init__(self, columns=(), digits: int | None = DIGITS, newline: str = "\n"):
        self.columns, self.digits, self.newline = list(columns), digits, newline
        self.rows: list = []  #: the row objects formatted so far, in order
        self.chunks: list[str] = []  #: their text, a chunk per call

    def of(self, rows) -> str:
        """The text (no header) of ``rows``."""
        n = len(self.rows)
        if n > len(rows) or any(a is not b for a, b in zip(self.rows, rows)):
            self.rows, self.chunks, n = [], [], 0
        if len(rows) > n:
            buf = io.StringIO()
            w = csv.writer(buf, lineterminator=self.newline)
            for r in rows[n:]:
                w.writerow(_cells(r, self.columns, self.digits))
            self.chunks.append(buf.getvalue())
            self.rows.extend(rows[n:])
        return "".join(self.chunks)


def text(columns, rows, digits: int | None = DIGITS, newline: str = "\n", formatted: Rows | None = None) -> str:
    """A table's text: its header line, then its rows.

    Args:
        columns: the header. rows: sequences in the header's order, or dicts read by the header (a missing key is
            an empty cell). digits, newline: as ``Rows``. formatted: the table's ``Rows`` (its rows formatted
            once), or None.

    Returns:
        The CSV text.
    """
    buf = io.StringIO()
    csv.writer(buf, lineterminator=newline).writerow(list(columns))
    return buf.getvalue() + (formatted or Rows(columns, digits, newline)).of(rows)


def write(path, columns, rows, digits: int | None = DIGITS, comm: MPI.Comm = MPI.COMM_SELF, newline: str = "\n",
          formatted: Rows | None = None) -> None:
    """Write a table on rank 0 of ``comm``, replacing the file whole and atomically (fepen.io.files.write_text:
    a file fepen did not write in a claimed folder is refused).

    Args:
        path: the file. columns, rows, digits, newline, formatted: as ``text``. comm: who writes (rank 0).
    """
    if comm.rank == 0:
        files.write_text(Path(path), text(columns, rows, digits, newline, formatted), comm)
