"""A CAD body is its own type (CadBody), and the mesh cache keys it, and every Shape, in the record layout of
the one Shape type that once held both: the same body keeps its key (but for the meshing code's hash)."""

import json
from dataclasses import replace

from fepen.geometry import mesh_cache
from fepen.geometry.cad import CadBody
from fepen.geometry.shape import Shape

#: Shape's fields when it held CAD bodies too, in the cache record
LEGACY_FIELDS = {"diameter", "length", "nose", "crh", "cavity_diameter", "cavity_length", "step_diameter",
                 "step_length", "base_thickness", "nose_length_given", "meplat_diameter", "boattail_length",
                 "boattail_diameter", "cavity_table", "outer_points", "inner_points", "cad_file", "cad_scale",
                 "cad_digest", "tip_point", "tail_point"}


def test_a_cad_body_tracks_its_ends():
    body = CadBody(0.0236, 0.144, "/x/body.step", 0.001, "abc")
    assert body.radius == 0.0118 and body.tip == (0.0, 0.0, 0.0) and body.tail == (0.0, 0.144, 0.0)
    meshed = replace(body, tip_point=[0, 1e-9, 0], tail_point=[1e-6, 0.144, 0])
    assert meshed.tip == (0.0, 1e-9, 0.0) and meshed.tail == (1e-6, 0.144, 0.0)


def test_the_cache_record_of_a_cad_body_is_the_former_shapes():
    body = CadBody(0.0236, 0.144, "/x/body.step", 0.001, "abc", (0.0, 0.0, 0.0), (0.0, 0.144, 0.0))
    rec = json.loads(json.dumps(mesh_cache.record(body)))
    assert set(rec) == LEGACY_FIELDS
    assert rec["nose"] == "cad" and rec["crh"] == 3.0 and rec["cavity_diameter"] == 0.0 and rec["cavity_table"] == []
    assert (rec["cad_file"], rec["cad_scale"], rec["cad_digest"]) == ("/x/body.step", 0.001, "abc")
    assert mesh_cache.from_record(rec) == body


def test_the_cache_record_of_a_shape_holds_the_cad_fields_at_their_defaults():
    shape = Shape(0.0236, 0.144, "cone", cavity_diameter=0.012, cavity_length=0.06, nose_length_given=0.03,
                  cavity_table=((0.01, 0.006),))
    rec = json.loads(json.dumps(mesh_cache.record(shape)))
    assert set(rec) == LEGACY_FIELDS
    assert (rec["cad_file"], rec["cad_scale"], rec["cad_digest"], rec["tip_point"], rec["tail_point"]) == (
        "", 1.0, "", [], [])
    assert mesh_cache.from_record(rec) == shape
