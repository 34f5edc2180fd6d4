"""A sweep that varies the concrete's strength keeps the base scene's strength basis: the default concrete's
40 MPa is a cube strength (theory.md §8.1), and the values drawn about it must be cube strengths too, or the
whole Monte Carlo sample is read on cylinders and runs shallow."""

from fepen.laws import target as tg
from fepen.studies import sweep


def _spec(**base):
    return {"base": {"effects": {"fidelity": "rigid"}, **base},
            "monte_carlo": {"samples": 5, "seed": 1,
                            "vary": {"target.compressive_strength": {"distribution": "normal", "std_percent": 10.0}}}}


def test_the_default_concretes_cube_basis_is_kept():
    s = sweep.read(_spec())
    for i, shot in enumerate(s.shots):
        sc = s.scene(i)
        assert sc.target.strength_basis == "cube"
        assert sc.target.compressive_strength == shot["target.compressive_strength"]
    mean = sum(x["target.compressive_strength"] for x in s.shots) / len(s.shots)
    assert abs(mean / 40e6 - 1.0) < 0.15  # drawn about the base's 40 MPa
    assert tg.cylinder_strength(40e6, "cube") < 0.81 * 40e6  # what reading them on cylinders would have lost


def test_a_basis_given_in_the_base_is_the_one_used():
    s = sweep.read(_spec(target={"strength_basis": "cylinder"}))
    assert all(s.scene(i).target.strength_basis == "cylinder" for i in range(len(s.shots)))
