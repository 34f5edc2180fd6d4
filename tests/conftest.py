"""Shared test helpers. Tests marked ``mpi`` compare 1 and 2 ranks: make test runs them under ``mpirun -n 2``
only, and the serial lanes (``-m "not mpi"``) leave them out (see the Makefile).

The longest tests start first (pytest_collection_modifyitems): pytest-xdist hands tests out in collection
order, so a 2-minute test collected last would keep one worker busy after the other has finished."""

from pathlib import Path

import pytest

from fepen.studies import processes

ROOT = Path(__file__).resolve().parents[1]


def run_fepen(*args, cwd=None, ranks: int = 1, timeout: float = 600):
    """Run ``python -m fepen ARGS`` in a subprocess (on ``ranks`` MPI ranks); return CompletedProcess."""
    return processes.run(args, ranks, cwd=cwd, timeout=timeout)


def run_python(script, *args, ranks: int = 1, timeout: float = 600):
    """Run a Python script (a demo) in a subprocess, on ``ranks`` MPI ranks; return CompletedProcess."""
    return processes.run([script, *args], ranks, fepen=False, timeout=timeout)


class Runs(dict):
    """Runs made when first asked for, by key (``make(key)``), then kept: the 2-rank run is made only in the
    system lane's two_ranks phase, the serial one only where a serial test asks for it."""

    def __init__(self, make):
        super().__init__()
        self.make = make

    def __missing__(self, key):
        self[key] = value = self.make(key)
        return value


@pytest.fixture
def fepen_cli():
    return run_fepen


def check_bad_input_line(code: int, err: str, key: str, words: str) -> None:
    """Bad input's contract: exit code 2 and one line on stderr, "fepen: bad input: KEY: ..." whose message
    matches the regular expression ``words``."""
    import re

    lines = err.splitlines()
    assert code == 2 and len(lines) == 1, (code, err)
    prefix = f"fepen: bad input: {key}: "
    assert lines[0].startswith(prefix), lines[0]
    assert re.search(words, lines[0][len(prefix):]), lines[0]


@pytest.fixture
def bad_input_line():
    """check_bad_input_line, for the tests of every command's bad input."""
    return check_bad_input_line


#: the longest files and tests of a fresh clone (cold mesh cache, 2 workers; seconds, rounded), longest first.
#: A module's tests stay together, so that its module-scoped runs are made once; a listed test moves to the
#: front of its module only where the module has no module-scoped fixture.
SLOW_MODULES = {
    "tests/system/test_mesh.py": 400, "tests/system/test_resume.py": 200, "tests/system/test_rigid.py": 190,
    "tests/system/test_demos.py": 170, "tests/system/test_faults.py": 160, "tests/system/test_api_runs.py": 135,
    "tests/system/test_interface.py": 130, "tests/system/test_hard_cases.py": 100,
    "tests/system/test_paraview.py": 90, "tests/system/test_charge.py": 60,
    "tests/system/test_calibration_minimum.py": 45, "tests/unit/solver/test_explicit.py": 120,
    "tests/unit/post/test_figures.py": 50, "tests/unit/test_bootstrap.py": 20,
}
SLOW_TESTS = {
    "tests/system/test_mesh.py::test_default_mass_at_every_size[1.2]": 150,
    "tests/system/test_mesh.py::test_mesh_json_quality[1.2]": 149,  # reads the mesh the one above made
    "tests/system/test_mesh.py::test_charge_is_its_own_volume": 70,
    "tests/system/test_mesh.py::test_split_wall_gives_the_charge_its_own_surface[self]": 50,
    "tests/system/test_resume.py::test_killed_run_resumes_to_the_same_results[2-charged-worn]": 85,
    "tests/system/test_demos.py::test_hard_cases_demo": 60,
    "tests/system/test_demos.py::test_charge_demo_tied_against_frictional": 36,
    "tests/system/test_interface.py::test_uniformly_decelerated_charge_loads_the_shell_with_its_inertia[2]": 110,
}


#: the system tests that start processes on 2 ranks, marked ``two_ranks`` (pytest_collection_modifyitems): whole
#: modules whose module-scoped fixtures hold 2-rank runs, and tests by name; a test parametrized ``ranks=2`` is
#: marked too. The system lane runs them after the others, one at a time, so that each 2-rank run has both
#: cores: beside the other xdist worker's test, three processes on two cores, a 2-rank run waits on every
#: collective for its descheduled rank (the API tour on 2 ranks: 8.8 s alone, 65 s beside another test).
TWO_RANKS_MODULES = {"tests/system/test_charge_safety.py", "tests/system/test_paraview.py",
                     "tests/system/test_scaling_model.py"}  # its 4-rank run too
TWO_RANKS_TESTS = {
    "tests/system/test_demos.py::test_mpi_shot_demo", "tests/system/test_demos.py::test_hard_cases_demo",
    "tests/system/test_demos.py::test_charge_demo_tied_against_frictional",
    "tests/system/test_sweep.py::test_two_ranks_give_the_same_table",
    "tests/system/test_sweep.py::test_deformable_shots_on_groups_of_one_and_two_ranks",
    "tests/system/test_data_safety.py::test_rerun_into_a_finished_deformable_run_leaves_no_file_of_the_old_run",
}


def _two_ranks(item) -> bool:
    if item.nodeid.split("::", 1)[0] in TWO_RANKS_MODULES or item.nodeid.split("[", 1)[0] in TWO_RANKS_TESTS:
        return True
    callspec = getattr(item, "callspec", None)
    return callspec is not None and callspec.params.get("ranks") == 2


def pytest_collection_modifyitems(session, config, items):
    """Longest first: modules by SLOW_MODULES, tests within a module by SLOW_TESTS (a stable sort: the rest
    keep their order). The order is the same on every xdist worker, as xdist requires. The system tests that
    start 2-rank processes are marked ``two_ranks`` (TWO_RANKS_MODULES, TWO_RANKS_TESTS)."""
    for item in items:
        if item.nodeid.startswith("tests/system/") and _two_ranks(item):
            item.add_marker(pytest.mark.two_ranks)

    def cost(item):
        module = item.nodeid.split("::", 1)[0]
        return -SLOW_MODULES.get(module, 0), module, -SLOW_TESTS.get(item.nodeid, 0)

    items.sort(key=cost)
    if getattr(config.option, "loadgroup", False):
        _group_for_xdist(items)


def _group_for_xdist(items) -> None:
    """--dist loadgroup sends the tests of one ``xdist_group`` to one worker by the group's name after an "@" at
    the end of their node ids. pytest-xdist 3.8 writes it to ``item._nodeid``, which pytest 9.2 no longer reads
    (a node's id is ``item._id``): every grouped test went to any worker, and a module's module-scoped runs were
    made once per worker (test_sweep's and test_uncertainty_study's, 13 and 19 s each time). The suffix is
    written here where pytest reads it, once (an id that has it already is left alone)."""
    for item in items:
        names = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                        for m in item.iter_markers("xdist_group")})
        nodeid = item.nodeid
        if not names or nodeid.rfind("@") > nodeid.rfind("]"):
            continue
        grouped = f"{nodeid}@{'_'.join(names)}"
        if hasattr(item, "_id"):  # pytest 9
            from _pytest.nodeid import coerce_node_id

            item._id = coerce_node_id(grouped)
        else:
            item._nodeid = grouped
