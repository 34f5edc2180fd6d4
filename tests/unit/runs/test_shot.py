"""The resolved Shot: what it refuses before any mesh."""

import pytest

from fepen import scene
from fepen.errors import InputError
from fepen.runs import shot


@pytest.mark.parametrize("effect", ["effects.erosion=true", "effects.wear=true"])
def test_nodal_load_points_refuse_the_effects_that_rework_the_facets(effect):
    """Erosion exposes facets and the deformable wear recedes them by their own forces: with nodal load points
    both are refused naming target.load_points; the rigid fidelity (its rings) and the facets take them."""
    with pytest.raises(InputError) as err:
        shot.resolve(scene.load(None, ['target.load_points="nodes"', effect]), toml=False)
    assert err.value.key == "target.load_points" and "'facets'" in err.value.message
    assert shot.resolve(scene.load(None, ['target.load_points="facets"', effect]), toml=False).load_points == "facets"
    rigid = ['target.load_points="nodes"', "effects.fidelity=rigid"]
    if effect == "effects.wear=true":
        assert shot.resolve(scene.load(None, [*rigid, effect]), toml=False).load_points == "nodes"
