"""What a study writes into its folder, declared by the study and written by the skeleton (issue 60): its
document (NAME.json), its tables (every CSV through fepen.io.table, the one writer), its texts (NAME.md and the
like) and its pictures (each drawn on a Figure of its own by fepen.post, saved by fepen.post.figures). A study
says what it adds (``Study.tables``, ``Study.texts``, ``Study.pictures``); ``write`` is the skeleton's alone.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Table", "Picture", "Inputs", "write", "parquet_unavailable"]


@dataclass(frozen=True)
class Table:
    """A CSV table a study writes.

    Attributes:
        file: its name in the study's folder. columns: its header. rows: sequences in the header's order or dicts
            read by it. digits: significant digits of its real numbers (None: each the shortest text that reads
            back exactly; fepen.io.table.cell). comments: lines written first, each after "# " (provenance).
        copies: further paths the same table is written to (a table shipped with fepen, on the user's asking).
        parquet: the same table as NAME.parquet too, when pyarrow imports (else one line says why not).
    """

    file: str
    columns: Sequence
    rows: Sequence
    digits: int | None = 6
    comments: str = ""
    copies: tuple = ()
    parquet: bool = False


@dataclass(frozen=True)
class Picture:
    """A figure a study writes: drawn on a Figure of ``size`` inches by ``draw(fig)`` (which returns False when
    there is nothing to draw: no file), saved at ``dpi`` (None: fepen.post.figures' default)."""

    file: str
    size: tuple
    draw: Callable
    dpi: int | None = None


@dataclass(frozen=True)
class Inputs:
    """A step of a study's rounds: files the next rounds read (e.g. the table of drawn inputs a sweep runs),
    written by rank 0 into the study's folder before they run; ``folder = yield Inputs(...)`` gives every rank the
    folder.

    Attributes:
        tables: the tables (Table). documents: {file: JSON content} written beside them.
    """

    tables: tuple = ()
    documents: dict | None = None

    def write(self, out: Path, say=None) -> None:
        """Its documents and tables into the study's folder ``out`` (rank 0)."""
        from mpi4py import MPI

        from fepen.io import files

        write(out, None, "", self.tables, say=say)
        for file, document in (self.documents or {}).items():
            files.write_json(Path(out) / file, document, MPI.COMM_SELF)


def _table(out: Path, t: Table, say) -> None:
    from mpi4py import MPI

    from fepen.io import files, table

    text = "".join(f"# {line}\n" for line in t.comments.splitlines()) + table.text(t.columns, t.rows, t.digits)
    for path in (out / t.file, *map(Path, t.copies)):
        files.write_text(path, text, MPI.COMM_SELF)
    if t.parquet:
        _parquet(out / Path(t.file).with_suffix(".parquet").name, t, say)


def parquet_unavailable() -> str | None:
    """Why a table's .parquet cannot be written here (one line), or None when pyarrow imports."""
    try:
        import pyarrow  # noqa: F401
        import pyarrow.parquet  # noqa: F401
    except ModuleNotFoundError:
        return "pyarrow is not installed (pip install 'fepen[parquet]': a pyarrow that works with numpy 1.24)"
    except Exception as err:  # noqa: BLE001 - an ImportError of a build for numpy 2, or anything it raises
        text = " ".join(str(err).split()) or type(err).__name__
        return f"pyarrow failed to import ({text}); pip install 'pyarrow>=14,<26' (the extra 'parquet')"
    return None


def _parquet(path: Path, t: Table, say) -> None:
    from fepen.atomic import replacing

    why = parquet_unavailable()
    if why is not None:
        if say is not None:
            say(f"{path.name} not written: {why}")
        return
    import pyarrow as pa
    import pyarrow.parquet as pq

    rows = [r if isinstance(r, dict) else dict(zip(t.columns, r)) for r in t.rows]
    with replacing(path, ".parquet") as tmp:
        pq.write_table(pa.table({c: [r.get(c) for r in rows] for c in t.columns}), str(tmp))


def write(out: Path, document: dict | None, name: str, tables: Sequence[Table] = (), texts: dict | None = None,
          pictures: Sequence[Picture] = (), say=None) -> None:
    """A study's files (rank 0), in this order: NAME.json, the tables, the texts, the pictures.

    Args:
        out: the study's folder. document: NAME.json's content (None: no NAME.json). name: the files' stem.
        tables, texts ({file: text}), pictures: what the study declares. say: the console (a table's one line).
    """
    from mpi4py import MPI

    from fepen.io import files

    out = Path(out)
    if document is not None:
        files.write_json(out / f"{name}.json", document, MPI.COMM_SELF)
    for t in tables:
        _table(out, t, say)
    for file, text in (texts or {}).items():
        files.write_text(out / file, text, MPI.COMM_SELF)
    if pictures:
        from fepen.post.figures import new_figure, save_figure

        for p in pictures:
            fig = new_figure(p.size)
            if p.draw(fig) is not False:
                save_figure(fig, out / p.file, **({} if p.dpi is None else {"dpi": p.dpi}))
