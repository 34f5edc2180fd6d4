"""The study skeleton: every study fepen runs (``fepen sweep``, ``fepen validate``, ``fepen validate-depth``,
``fepen study NAME``, the calibrations) is a Study, run by one function (``run``) on one executor
(fepen.studies.engine.execute) into a folder owned by manifest (fepen.io.rundir.study_directory), and found in one
registry (``REGISTRY``) that feeds the command line (fepen.cli.study) and the API (``fepen.study``).

A study is four separable things (ASE's eos: produce, analyse, draw, command):

    plan(**options) -> plan          read and check everything: InputError before anything is written
    digest(plan) -> str | None       what makes its folder resumable (None: it runs again each time)
    rounds(plan)                     a generator of Rounds of shots (each ``yield`` receives the round's records),
                                     or of Subs: whole studies run in a folder of its own; what it returns
                                     (what its rounds found) reaches result as info.found
    result(plan, records, info)      pure: the records (and info.found) in, the study's result out (rank 0)
    document, tables, texts, pictures  what it writes (rank 0): by default NAME.json, NAME.md (report) and
                                     NAME.png (figure, drawn on a Figure fepen.post gives it); the skeleton's
                                     write() writes them (fepen.studies.products: every table through
                                     fepen.io.table)
    lines(result) -> list[str]       what the console says

A new study is one file: a subclass with a name, its options and these methods, and ``@register``.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path

from fepen.io import layout
from fepen.studies import rounds
from fepen.studies.products import Inputs
from fepen.studies.rounds import Round, RunInfo, Sub

__all__ = ["Round", "Sub", "Inputs", "Study", "RunInfo", "run", "register", "get", "public", "set_option", "numbers",
           "STUDIES", "REGISTRY", "study_names"]

#: every study by name, in the order the command line lists them: (its module, its class). A module is imported
#: only when its study is asked for (fepen.cli.study builds its parser from them; fepen.study runs one).
STUDIES = {
    "sweep": ("fepen.studies.sweep", "SweepStudy"),
    "validate": ("fepen.studies.validate", "Validate"),
    "validate-bands": ("fepen.studies.bands", "Bands"),
    "validate-depth": ("fepen.studies.depth", "ValidateDepth"),
    "accuracy-cost": ("fepen.studies.accuracy_cost", "AccuracyCost"),
    "ballistic-limit": ("fepen.studies.limits", "BallisticLimit"),
    "ricochet": ("fepen.studies.limits", "Ricochet"),
    "uncertainty": ("fepen.studies.uncertainty", "Uncertainty"),
    "charge-safety": ("fepen.studies.charge_safety", "ChargeSafetyStudy"),
    "calibration": ("fepen.studies.calibration", "Calibration"),
    "wear-calibration": ("fepen.studies.wear_calibration", "WearCalibration"),
    "prediction-errors": ("fepen.studies.prediction_errors", "PredictionErrors"),
}
#: the studies registered so far (``register``), by name
REGISTRY: dict[str, type] = {}


def register(cls: type) -> type:
    """A class decorator: the study joins REGISTRY under its ``name``, which STUDIES must list (a study of a
    test may add itself to STUDIES first)."""
    if STUDIES.get(cls.name, (None, None))[1] != cls.__name__:
        raise ValueError(f"study {cls.name!r} ({cls.__name__}) is not in fepen.studies.study.STUDIES")
    REGISTRY[cls.name] = cls
    layout.declare(cls.name, cls.names)  # what its folder may hold: the one declaration --fresh removes by
    return cls


def get(name: str) -> type:
    """The Study class of a name (its module imported on first use).

    Raises:
        InputError: naming the study, when there is none of that name.
    """
    if name not in STUDIES:
        from fepen.errors import InputError

        raise InputError("study", f"no study {name!r}; the studies: {', '.join(STUDIES)}")
    if name not in REGISTRY:
        import importlib

        importlib.import_module(STUDIES[name][0])
    return REGISTRY[name]


def _names_of(kind: str) -> tuple:
    """A study's declared names by its kind (fepen.io.layout asks for a study it has not met in this process)."""
    return get(kind).names


layout.study_names = _names_of


def study_names(command: str | None = None) -> list[str]:
    """The studies' names: all, or those a command runs ("study": ``fepen study NAME``)."""
    return [n for n in STUDIES if command is None or get(n).command == command]


def set_option(parser, help: str) -> None:
    """--set KEY=VALUE, repeatable, into ``args.sets`` (a study's own options, as the command line has them)."""
    parser.add_argument("--set", dest="sets", action="append", default=[], metavar="KEY=VALUE", help=help)


def numbers(option: str, text: str) -> list[float]:
    """The positive finite numbers of a comma-separated option value; InputError naming ``option`` else."""
    import math

    from fepen.errors import InputError

    try:
        values = [float(x) for x in text.split(",")]
    except ValueError:
        values = []
    if not values or not all(math.isfinite(v) and v > 0 for v in values):
        raise InputError(option, f"comma-separated positive numbers, got {text!r}")
    return values


class Study:
    """The protocol every study fills in (module docstring); the defaults write NAME.json, NAME.md, NAME.png.

    Class attributes:
        name: the registry's name (``fepen study NAME``, ``fepen.study(NAME)``).
        help: its line in ``fepen study --help``.
        command: "study" (a sub-command of ``fepen study``), or the top-level command that runs it
            ("sweep", "validate", "validate-depth"), or "" (the API and ``python -m`` only: the calibrations).
        names: what it writes into its folder (a file fepen did not write there under one of them is refused
            before any shot runs).
        out: its default folder.
    """

    name: str = ""
    help: str = ""
    command: str = "study"
    names: tuple = ()
    out: str = "results/study"

    # ---- the command line ---------------------------------------------------------------------------------
    @classmethod
    def add_arguments(cls, parser) -> None:
        """Its options (the common ones, --out, --fresh, --ranks-per-shot, are added by fepen.cli.study)."""

    @classmethod
    def options(cls, args) -> dict:
        """plan()'s keyword arguments from parsed command-line arguments."""
        return {}

    # ---- the study ----------------------------------------------------------------------------------------
    def plan(self, **options):
        """Read and check everything the study needs; InputError before anything is written."""
        raise NotImplementedError

    def digest(self, plan) -> str | None:
        """What makes the folder resumable: a folder of the same study with another digest is refused (by
        default the plan's fields, its scenes resolved: fepen.studies.record.canonical_digest)."""
        from fepen.studies.record import canonical_digest

        return canonical_digest(plan)

    def prepare(self, plan, out: Path, comm) -> None:
        """Before the first round (every rank; the folder claimed): e.g. the tables of what is drawn."""

    def rounds(self, plan) -> Iterator[Round]:
        """The rounds of shots; ``records = yield Round(...)`` gives each round's records ({index: record})."""
        raise NotImplementedError

    def result(self, plan, records: list[dict], info) -> dict:
        """The study's result from every round's records (rank 0; info: RunInfo)."""
        raise NotImplementedError

    def report(self, result: dict) -> str | None:
        """NAME.md, or None."""
        return None

    def figure(self, result: dict, fig) -> bool:
        """Draw NAME.png on ``fig`` (a matplotlib Figure of fepen.post.figures.new_figure); False: no picture."""
        return False

    def figure_size(self, result: dict) -> tuple[float, float]:
        return (8.0, 5.0)

    # ---- what it writes: declared here, written by the skeleton (fepen.studies.products) --------------------
    def document(self, plan, result: dict, info) -> dict | None:
        """NAME.json's content (default: the public result), or None: no NAME.json."""
        return public(result)

    def tables(self, plan, result: dict, info) -> list:
        """Its CSV tables (fepen.studies.products.Table), written by fepen.io.table."""
        return []

    def texts(self, plan, result: dict, info) -> dict:
        """Its texts, {file: text} (default NAME.md: ``report``)."""
        text = self.report(result)
        return {} if text is None else {f"{self.json_name}.md": text}

    def pictures(self, plan, result: dict, info) -> list:
        """Its figures (fepen.studies.products.Picture; default NAME.png: ``figure``)."""
        from fepen.studies.products import Picture

        return [Picture(f"{self.json_name}.png", self.figure_size(result), lambda fig: self.figure(result, fig))]

    def write(self, plan, result: dict, out: Path, info) -> None:
        """Its files (rank 0; info: RunInfo): what ``document``, ``tables``, ``texts`` and ``pictures`` declare,
        written by the skeleton alone (a study never overrides this)."""
        from fepen.studies import products

        products.write(out, self.document(plan, result, info), self.json_name, self.tables(plan, result, info),
                       self.texts(plan, result, info), self.pictures(plan, result, info), info.say)

    @property
    def json_name(self) -> str:
        """The stem of its files (the name with _ for -)."""
        return self.name.replace("-", "_")

    def lines(self, result: dict) -> list[str]:
        """What the console says at the end."""
        return []


def run(study: Study, plan, out, comm=None, ranks_per_shot: int = 1, fresh: bool = False, say=print,
        progress: bool = True) -> dict:
    """Run a study into its folder: claim it (fepen.io.rundir.study_directory, with the digest), prepare, every
    round on the executor (fepen.studies.engine.execute: MPI groups taking shots from a queue, rigid shots in
    batches, records kept so that a killed study resumes), the result, the files, the console's lines.

    Args:
        study: the Study. plan: its plan (study.plan(...)). out: the folder. comm: the communicator (None:
            COMM_WORLD). ranks_per_shot: ranks of each shot's group. fresh: remove what the study wrote in OUT
            first and run every shot again. say: prints lines (rank 0). progress: the shots' bar (rank 0).

    Returns:
        The result without its private entries (every rank; public), with "wall_s" and "ran" added when the
        study's own result has none.
    """
    from mpi4py import MPI

    from fepen.io import files, rundir
    from fepen.studies import engine, record

    comm = MPI.COMM_WORLD if comm is None else comm
    engine.check_ranks_per_shot(ranks_per_shot, comm.size)
    info = RunInfo(time.perf_counter(), comm.size, ranks_per_shot, say)
    inputs = record.inputs_of(study, plan)
    with rundir.study_directory(out, comm, fresh, study.name, study.names, digest=inputs["sha256"], inputs=inputs):
        out = info.out = files.prepare(Path(out), comm)
        study.prepare(plan, out, comm)
        from fepen.runs.interrupts import Interrupts

        with Interrupts(comm) as info.stop:  # a signal stops the study at its next shot boundary
            rounds.drive(study, plan, out, comm, info, progress, run)
        result, failure = None, None
        if comm.rank == 0:
            failure = record.failed(info.records)
            if failure is None:
                result = study.result(plan, info.records, info)
                study.write(plan, result, out, info)
                say(*study.lines(result))
                result = {"wall_s": info.wall_s, "ran": info.ran, **public(result)}
            else:
                _write_what_failed(study, plan, out, info)
        result, failure = comm.bcast((result, failure), root=0) if comm.size > 1 else (result, failure)
        if failure is not None:
            raise failure
        return result


def _write_what_failed(study: Study, plan, out: Path, info: RunInfo) -> None:
    """The tables of a study none of whose shots finished, as far as its result can be made (each point's
    outcome is in them); a result that cannot be made of failed shots writes nothing more (rank 0)."""
    import logging

    try:
        result = study.result(plan, info.records, info)
        study.write(plan, result, out, info)
    except Exception as err:  # noqa: BLE001 - the shots' failure is the one to report
        logging.getLogger("fepen").debug(f"no table of the failed shots: {type(err).__name__}: {err}")


def public(result: dict) -> dict:
    """A result without its private entries (names starting "_": rank 0's records and tables)."""
    return {k: v for k, v in result.items() if not k.startswith("_")}
