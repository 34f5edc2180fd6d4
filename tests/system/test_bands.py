"""Table 1 as distributions (issue 59, item 4: fepen validate --samples): a prior of no width gives every member
the deterministic shot, so each band closes on ``fepen validate``'s figure; the bands are the same, bit for bit,
from their seed on one rank and on two; the command writes bands.csv with its columns."""

import csv

import pytest
from mpi4py import MPI

from fepen.stats import striking
from fepen.studies import bands, study, validate


def run_bands(out, samples, prior=striking.PRIOR, comm=MPI.COMM_SELF, seed=5):
    st = bands.Bands()
    return study.run(st, st.plan(None, (), samples, seed, prior), out, comm, say=lambda *a: None)


def test_a_prior_of_no_width_closes_every_band_on_the_deterministic_shot(tmp_path):
    zero = striking.StrikingPrior(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.02)
    res = run_bands(tmp_path / "b", 2, zero)
    det = {r["shot"]: r for r in validate.validate(None, ["effects.fidelity=rigid", "run.figures=false"],
                                                    tmp_path / "v")}
    names = {"Hx_mm": "Hx_mm", "Hy_mm": "Hy_mm", "Tx_mm": "Tx_mm", "Ty_mm": "Ty_mm",
             "final_axis_angle_deg": "axis_deg", "nose_offset_mm": "nose_offset_mm"}
    for r in res["rows"]:
        if r["quantity"] in names:
            want = det[r["shot"]][names[r["quantity"]]]
            assert r["p10"] == r["p50"] == r["p90"] == pytest.approx(want, rel=1e-12, abs=1e-12), r
    for shot, (nose, tail) in bands.median_errors(res["rows"]).items():  # the medians' errors are the line's
        assert (nose, tail) == pytest.approx((det[shot]["nose_error"], det[shot]["tail_error"]), rel=1e-9)
    with open(tmp_path / "b" / "bands.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert tuple(rows[0]) == bands.FIELDS and len(rows) == 8 * len(bands.QUANTITIES)


@pytest.mark.mpi
def test_the_bands_are_the_same_from_their_seed_on_one_and_two_ranks(tmp_path_factory):
    root = MPI.COMM_WORLD.bcast(str(tmp_path_factory.mktemp("bands")) if MPI.COMM_WORLD.rank == 0 else None)
    from pathlib import Path

    world = run_bands(Path(root) / "world", 3, comm=MPI.COMM_WORLD)
    if MPI.COMM_WORLD.rank == 0:
        alone = run_bands(Path(root) / "alone", 3)
        assert world["rows"] == alone["rows"]
        assert any(r["p90"] > r["p10"] for r in alone["rows"])  # the members differ


def test_a_subset_of_shots_draws_the_same_members_as_the_whole_table():
    """--shots C8,C2: each member's draw depends on (seed, shot, member) alone, so the subset's members are the
    whole table's; a name not in Table 1 is refused before anything runs."""
    from fepen.errors import InputError

    st = bands.Bands()
    whole, part = st.plan(None, (), 3, 7), st.plan(None, (), 3, 7, shots=["C8", "C2"])
    assert list(part.members) == ["C8", "C2"]
    for name in part.members:
        assert [m.as_dict() for m in part.members[name]] == [m.as_dict() for m in whole.members[name]]
    with pytest.raises(InputError, match="--shots"):
        st.plan(None, (), 3, 7, shots=["C9"])
    plastic = st.plan(None, ("effects.fidelity=plastic",), 2, 7, shots=["C2"])
    assert st.fidelity(plastic) == "plastic" and plastic.members["C2"][0].run.fields is False
