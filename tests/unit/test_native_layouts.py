"""The layouts Python shares with a C kernel are read from the kernel's source (fepen.native.c_enums, issue 60):
the reader's rules (implicit increments, expressions of earlier members, comments), and the layouts the laws
take from it (the material vector: materials_kernel.c; the tunnel's buffer: tunnel_kernel.c)."""

import pytest

from fepen import native
from fepen.laws import materials, tunnel


def test_the_reader_follows_c_s_enum_rules(tmp_path):
    src = tmp_path / "k.c"
    src.write_text("/* enum { NOT, THIS }; */\nenum { A, B /* 1 */, C = B + 3, D, // E,\n E = C * 2 - 1 };\n"
                   "typedef enum named { X = 7, Y } named_t;\nint f(void) { return 0; }\n")
    assert native.c_enums(src) == {"A": 0, "B": 1, "C": 4, "D": 5, "E": 7, "X": 7, "Y": 8}
    src.write_text("enum { A = sizeof(double) };\n")
    with pytest.raises(ValueError, match="not an integer expression"):
        native.c_enums(src)


def test_the_laws_layouts_are_their_kernels():
    m = native.c_enums(native.Path(materials.__file__).with_name("materials_kernel.h"))
    assert (materials.N_PARAMS, materials.H_, materials.THERMAL_ON, materials.BILINEAR) == (17, 16, 15, 2)
    assert m["N_PARAMS"] == materials.N_PARAMS and m["JOHNSON_COOK"] == materials.JOHNSON_COOK
    t = native.c_enums(native.Path(tunnel.__file__).with_name("tunnel_kernel.h"))
    assert (tunnel.HEADER, tunnel.STATION, tunnel.T_TS, tunnel.T_FACE) == (16, 8, 11, 14) == (
        t["T_HEADER"], t["T_STATION"], t["T_TS"], t["T_FACE"])
