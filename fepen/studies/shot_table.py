"""A table of shots: a CSV file whose header names scene keys, one shot a row, values in TOML syntax (a sweep's
``[table] file``, fepen.studies.spec). Read whole and checked before any shot runs: a regular file of at most
TABLE_MAX bytes, UTF-8 (a byte-order mark allowed), each column a scene key named once, each cell at most
CELL_MAX characters; every refusal one line naming table.file, the line and the column."""

from __future__ import annotations

import csv
import io
from pathlib import Path

from fepen import scene as fscene
from fepen.errors import InputError
from fepen.scene.keys import display_name

__all__ = ["read_table", "check_key", "TABLE_MAX", "CELL_MAX"]

#: the largest table of shots read (bytes)
TABLE_MAX = 64 << 20
#: the largest cell of a table of shots (characters): one scene value (a number, a word, a path, a short list);
#: Python's csv module's own default field limit, past which it stopped with an error of its own
CELL_MAX = 128 << 10


def check_key(section: str, name: str) -> None:
    """A scene key named in a sweep's ``section`` (a grid, a sample's vary, a table's header): InputError else."""
    if name not in fscene.SCHEMA:
        err = fscene.unknown_key(name)
        raise InputError(f"{section}.{display_name(name)}", f"not a scene key ({err.message})")


def _csv_rows(path: Path, text: str) -> list[tuple[int, list]]:
    """(line, cells) of each row of a CSV text but blank and # comment rows: every cell read whole (csv's own
    field limit raised to the table's size for the read, then restored), so that a long cell is named by
    read_table with its column; a CSV csv cannot read is InputError (table.file)."""
    reader = csv.reader(io.StringIO(text))
    limit = csv.field_size_limit(max(csv.field_size_limit(), TABLE_MAX))
    rows = []
    try:
        for r in reader:
            if r and not r[0].lstrip().startswith("#"):
                rows.append((reader.line_num, r))
    except csv.Error as err:
        raise InputError("table.file", f"{path} line {reader.line_num}: not CSV fepen reads: {err}") from None
    finally:
        csv.field_size_limit(limit)
    return rows


def read_table(path: Path, max_shots: int) -> tuple[list, list]:
    """Keys and shots of a CSV table (header: scene keys, each once; values in TOML syntax, bare words strings;
    cells of at most CELL_MAX characters; UTF-8, a byte-order mark allowed).

    Args:
        path: the CSV file (a regular file of at most TABLE_MAX bytes). max_shots: the most rows it may hold.

    Returns:
        (the keys, one {key: value} per row). InputError naming table.file (its line and column) else.
    """
    try:
        text = fscene.read_capped(path, TABLE_MAX, "table.file", "a table of shots").decode("utf-8-sig")
    except UnicodeDecodeError:
        raise InputError("table.file", f"{path} is not UTF-8 text") from None
    rows = _csv_rows(path, text)
    if len(rows) < 2:
        raise InputError("table.file", f"{path} needs a header of scene keys and at least one row")
    if len(rows) - 1 > max_shots:
        raise InputError("table.file", f"{path} holds {len(rows) - 1} shots; a sweep holds at most {max_shots}")
    header_line, header = rows[0]
    keys = [k.strip() for k in header]

    def column(j: int) -> str:
        return f"column {j + 1}" + (f" ({display_name(keys[j])})" if j < len(keys) and keys[j] else "")

    for n, r in rows:
        for j, v in enumerate(r):
            if len(v) > CELL_MAX:
                raise InputError("table.file", f"{path} line {n}, {column(j)}: a cell of {len(v)} characters; a "
                                               f"cell holds one scene value, at most {CELL_MAX}")
    for j, k in enumerate(keys):
        if not k:
            raise InputError("table.file", f"{path} line {header_line}, column {j + 1}: an empty header cell; each "
                                           "column names a scene key")
        if k in keys[:j]:
            raise InputError("table.file", f"{path} line {header_line}, {column(j)}: given twice (also column "
                                           f"{keys.index(k) + 1}); each key is one column")
        check_key("table.file", k)
    shots = []
    for n, r in rows[1:]:
        if len(r) != len(keys):
            raise InputError("table.file", f"{path} line {n}: {len(r)} values for {len(keys)} keys")
        shot = {}
        for j, (k, v) in enumerate(zip(keys, r)):
            try:
                shot[k] = fscene.parse_set(f"{k}={v.strip()}")[1]
            except InputError as err:
                raise InputError("table.file", f"{path} line {n}, {column(j)}: {err.message}") from None
        shots.append(shot)
    return keys, shots
