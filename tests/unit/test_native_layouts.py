"""The C interfaces are read from the kernels' headers (fepen.native, issue 60): the enum reader's rules (implicit
increments, expressions of earlier members, comments), the prototype reader's (the C types fepen uses, and a loud
failure on any other), every bound function's ctypes signature from its header, and every layout Python shares
with a kernel (the material vector, the tunnel's buffer, the target law's numbers, the batch's shot numbers and
results, the outcome codes) held to its header member by member, so that a header and its Python that disagree
fail here and when the kernel is loaded."""

import ctypes
import re

import numpy as np
import pytest

from fepen import native
from fepen.laws import materials, target, tunnel
from fepen.runs import batch, events
from fepen.solver import ckernel

HEADERS = sorted(native.PACKAGE.rglob("*.h"))


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


def test_the_prototype_reader_reads_the_types_fepen_uses(tmp_path):
    h = tmp_path / "k.h"
    h.write_text("#ifndef K_H\n#define K_H\n#include <stdint.h>\n/* int32_t hidden(double x); */\n"
                 "enum { A, B = A + 2 };\ntypedef struct { double x; } pair;\n"
                 "int32_t f(int32_t k, const double *restrict x, double q, // a comment\n"
                 "          void *fn, const int64_t *m, uint8_t *flags);\n"
                 "void g(void);\ndouble h(double, int n);\nint *p(int k);\n#endif\n")
    i32, vp, dbl = ctypes.c_int32, ctypes.c_void_p, ctypes.c_double
    assert native.c_prototypes(h) == {"f": ([i32, vp, dbl, vp, vp, vp], i32), "g": ([], None),
                                      "h": ([dbl, i32], dbl), "p": ([i32], vp)}
    assert native.c_enums(h) == {"A": 0, "B": 2}


@pytest.mark.parametrize("decl, function", [("float area(float r);", "area"),
                                            ("int32_t count(unsigned long n);", "count"),
                                            ("void each(int32_t k, void (*fn)(double));", "each"),
                                            ("static inline double twice(double x) { return 2 * x; }", "twice")])
def test_the_prototype_reader_refuses_what_it_does_not_know(tmp_path, decl, function):
    h = tmp_path / "bad.h"
    h.write_text(f"double fine(double x);\n{decl}\n")
    with pytest.raises(native.LayoutError, match=rf"{re.escape(str(h))}: {function}\b"):
        native.c_prototypes(h)


def test_every_bound_function_is_typed_by_its_header():
    """No ctypes list typed by hand: each kernel names its header (which its source includes, so that the compiler
    holds the prototypes to the definitions) and the functions it binds, by name; a loaded library's functions
    carry the header's signatures."""
    for name, k in native.KERNELS.items():
        header = native.PACKAGE / k.header
        assert f'#include "{header.name}"' in (native.PACKAGE / k.source).read_text(), (name, k.header)
        assert k.functions and all(isinstance(fn, str) for fn in k.functions), name
        declared = native.c_prototypes(header)
        assert set(native.signatures(name)) == set(k.functions) <= set(declared), name
        lib = native.kernel(name)
        if lib is None:  # an optional kernel that is off here
            continue
        for fn in k.functions:
            assert (list(getattr(lib, fn).argtypes), getattr(lib, fn).restype) == declared[fn], (name, fn)


def test_a_function_its_header_does_not_declare_fails_by_name(monkeypatch):
    k = native.KERNELS["events"]
    monkeypatch.setitem(native.KERNELS, "events", native.Kernel(k.source, k.header, k.flags, k.required,
                                                                ("penetration_outcome", "penetration_rule")))
    with pytest.raises(native.LayoutError, match=r"events_kernel\.h declares no function penetration_rule"):
        native.signatures("events")


def test_the_numba_law_is_typed_by_its_header():
    import numba

    for fn, ext in (("material_radial_return", materials._RETURN), ("material_yield_stress", materials._FLOW)):
        args, result = native.c_prototypes(materials._HEADER)[fn]
        assert ext.symbol == fn and len(ext.sig.args) == len(args)
        assert ext.sig.return_type == (numba.types.double if result is ctypes.c_double else None)


#: every layout Python shares with a kernel, by kernel: the prefixes of its header's enums
SHARED = {"target": {"P_", "SUM_"}, "rigid_batch": {"S_", "R_", "Y_", "STEP_"}, "events": {"OUTCOME_"},
          "cells": {"TOT_"}}


def test_every_shared_layout_is_declared_and_agrees():
    assert {name: {prefix for prefix, _ in entries} for name, entries in native._SHARED.items()} == SHARED
    for name in SHARED:
        native.check_layouts(name)
    assert len(batch.SHOT_NUMBERS) == native.c_enums(native.PACKAGE / "runs/rigid_batch.h")["S_COUNT"]
    assert batch.RESULTS[native.c_enums(native.PACKAGE / "runs/rigid_batch.h")["R_OUTCOME"]] == "outcome"
    p = native.c_enums(native.PACKAGE / "laws/target_kernel.h")
    assert [m for m, _ in target._LAW] == sorted((m for m in p if m.startswith("P_") and m != "P_COUNT"), key=p.get)


def _edited(tmp_path, header: str, old: str, new: str):
    """A copy of a package header with one edit."""
    text = (native.PACKAGE / header).read_text()
    assert old in text
    out = tmp_path / (native.Path(header).name)
    out.write_text(text.replace(old, new, 1))
    return out


@pytest.mark.parametrize("header, prefix, old, new, member", [
    ("runs/rigid_batch.h", "S_", "S_MASS, S_DT, S_HARD_END,", "S_MASS, S_HARD_END, S_DT,", "S_DT"),
    ("runs/rigid_batch.h", "S_", "S_RESERVED,", "S_RESERVED, S_SPARE,", "S_SHOULDER"),
    ("runs/rigid_batch.h", "R_", "R_ROWS,", "R_ROWS, R_SPARE,", "R_STATUS"),
    ("runs/rigid_batch.h", "R_", "R_COUNT };", "R_SPARE, R_COUNT };", "R_SPARE"),
    ("runs/rigid_batch.h", "R_", "R_MAX_NOSE", "R_MAX_NOSE_MM", "R_MAX_NOSE"),
    ("laws/target_kernel.h", "P_", "P_MU_DYNAMIC, P_MU_DECAY,", "P_MU_DECAY, P_MU_DYNAMIC,", "P_MU_DYNAMIC"),
    ("laws/target_kernel.h", "P_", "P_COUNT };", "P_EXTRA, P_COUNT };", "P_EXTRA"),
    ("laws/target_kernel.h", "SUM_", "SUM_LOADED = SUM_FORCE + 3", "SUM_LOADED = SUM_FORCE + 4", "SUM_LOADED"),
    ("solver/cell_kernel.h", "TOT_", "TOT_PLASTIC, TOT_HEAT,", "TOT_HEAT, TOT_PLASTIC,", "TOT_PLASTIC"),
    ("runs/rigid_batch.h", "Y_", "Y_VELOCITY = Y_QUAT + 4", "Y_VELOCITY = Y_QUAT + 3", "Y_VELOCITY"),
    ("runs/events_kernel.h", "OUTCOME_", "OUTCOME_RICOCHET, OUTCOME_EMBEDDED", "OUTCOME_EMBEDDED, OUTCOME_RICOCHET",
     "OUTCOME_RICOCHET"),
    ("runs/events_kernel.h", "OUTCOME_", "OUTCOME_EMBEDDED, OUTCOME_COUNT", "OUTCOME_EMBEDDED, OUTCOME_COUNT = 5",
     "OUTCOME_COUNT")])
def test_a_header_and_its_python_that_disagree_fail_naming_both(tmp_path, header, prefix, old, new, member):
    name = {"runs/rigid_batch.h": "rigid_batch", "laws/target_kernel.h": "target", "runs/events_kernel.h": "events",
            "solver/cell_kernel.h": "cells"}
    (members,) = [m for p, m in native._SHARED[name[header]] if p == prefix]
    native.check_layout(native.PACKAGE / header, prefix, members)  # as it is: agrees
    edited = _edited(tmp_path, header, old, new)
    with pytest.raises(native.LayoutError, match=rf"{re.escape(str(edited))}.*\b{member}\b"):
        native.check_layout(edited, prefix, members)


def test_a_disagreeing_layout_stops_the_kernel_s_load(monkeypatch):
    """The check runs when the kernel is loaded (and at once for a kernel loaded already): a Python copy of the
    outcome codes in another order stops events' load, naming the header and the member."""
    wrong = [("OUTCOME_NONE", 1), ("OUTCOME_RICOCHET", 1), ("OUTCOME_PERFORATED", 1), ("OUTCOME_EMBEDDED", 1)]
    monkeypatch.setitem(native._SHARED, "events", [("OUTCOME_", tuple(wrong))])
    monkeypatch.setattr(native, "_LOADED", {k: v for k, v in native._LOADED.items() if k != "events"})
    with pytest.raises(native.LayoutError, match=r"events_kernel\.h: enum member OUTCOME_RICOCHET is 2"):
        native.kernel("events")
    assert "events" not in native._LOADED
    native._LOADED["events"] = object()  # loaded: a layout declared now is checked now
    with pytest.raises(native.LayoutError, match=r"OUTCOME_RICOCHET"):
        native.shares("events", "OUTCOME_", wrong)


def test_a_member_a_module_reads_must_be_declared(tmp_path):
    h = _edited(tmp_path, "laws/tunnel_kernel.h", "T_ARC = 6", "T_ARCH = 6")
    with pytest.raises(native.LayoutError, match=rf"{re.escape(str(h))} declares no enum member T_ARC\b"):
        native.enum_values(h, "T_C", "T_ARC")
    assert native.enum_values(native.PACKAGE / "laws/tunnel_kernel.h", "T_C", "T_T", "T_ARC") == (
        tunnel.T_C, tunnel.T_T, tunnel.T_ARC) == (0, 3, 6)


def test_the_sums_and_passes_outputs_are_read_from_their_headers():
    cells = native.c_enums(native.PACKAGE / "solver/cell_kernel.h")
    assert (ckernel.KIN_J_MIN, ckernel.KIN_J_CELL, ckernel.KIN_DT_MIN, ckernel.KIN_DT_CELL, ckernel.KIN_COUNT) == (
        cells["KIN_J_MIN"], cells["KIN_J_CELL"], cells["KIN_DT_MIN"], cells["KIN_DT_CELL"], cells["KIN_COUNT"])
    sums = native.c_enums(native.PACKAGE / "laws/target_kernel.h")
    assert (target.SUM_FORCE, target.SUM_LOADED, target.SUM_AREA, target.SUM_COUNT) == (0, 3, 4, 5) == (
        sums["SUM_FORCE"], sums["SUM_LOADED"], sums["SUM_AREA"], sums["SUM_COUNT"])


def test_a_rigid_state_s_numbers_are_where_the_batch_reads_them():
    from fepen.laws.rigid_body import RigidState

    y = RigidState(*(np.arange(a, b, dtype=float) for a, b in ((0, 3), (3, 7), (7, 10), (10, 13)))).as_array()
    e = native.c_enums(native.PACKAGE / "runs/rigid_batch.h")
    assert len(y) == e["Y_COUNT"] and [y[e[m]] for m in ("Y_CENTRE", "Y_QUAT", "Y_VELOCITY", "Y_MOMENTUM")] == [
        0.0, 3.0, 7.0, 10.0]


def test_the_outcome_codes_are_the_kernel_s():
    """penetration's answers by the header's codes: perforated, then ricochet, then embedded."""
    v_down, axis = [0.0, -1.0, 0.0], [0.0, -1.0, 0.0]
    assert events.penetration(-2.0, -1.5, v_down, axis, 1.0, 1.0, 1.0, False, True)[0] == "perforated"
    assert events.penetration(0.5, 1.0, [0.0, 1.0, 0.0], axis, 1.0, 1.0, None, False, True)[0] == "ricochet"
    assert events.penetration(-1.0, 0.5, [0.0, 1.0, 0.0], axis, 1.0, 1.0, None, True, True)[0] == "embedded"
    assert events.penetration(-1.0, 0.5, v_down, axis, 1.0, 1.0, None, False, True) == (None, True)


def test_the_readme_names_every_header():
    readme = (native.PACKAGE.parent / "README.md").read_text()
    assert HEADERS and [h.name for h in HEADERS if not re.search(rf"\b{re.escape(h.name)}\b", readme)] == []
