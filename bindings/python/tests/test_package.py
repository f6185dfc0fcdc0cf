# SPDX-License-Identifier: Apache-2.0
"""Package surface: versions, option table, constants, typing files."""

import ast
import dataclasses
import math
import os
import re

import numpy as np
import pytest

import flatline

PACKAGE_DIR = os.path.dirname(flatline.__file__)


def test_version_is_the_header_version_and_matches_the_library():
    assert re.fullmatch(r"\d+\.\d+\.\d+", flatline.__version__)
    # The library loaded is the one the extension was built against.
    assert flatline.version() == flatline.__version__


def test_version_number_agrees_with_version_string():
    major, minor, patch = map(int, flatline.version().split("."))
    assert flatline.capi.flt_version() == major * 10000 + minor * 100 + patch


def test_options_table_lists_every_reconstructor_option_with_c_defaults():
    table = flatline.options()
    expected_defaults = {
        "knot_spacing": 0.0, "laser_spacing": 100.0, "height_sigma": 2.5,
        "slope_sigma": 1e-3, "curvature_weight": 1e-3, "lag_knots": 64.0,
        "max_gap": 200.0, "row_capacity": 8192.0, "rigid_motion": 0.0,
        "shape_sigma": 0.1, "curvature_jump_weight": 10.0,
    }
    for name, default in expected_defaults.items():
        assert table[name].default == default
        assert table[name].name == name
    assert table["lag_knots"].is_integer and not table["height_sigma"].is_integer
    assert math.isinf(table["max_gap"].max_value)
    assert table["row_capacity"].min_value == 16.0


def test_option_info_round_trips_through_the_key():
    info = flatline.option_info("laser_spacing")
    assert info.key == flatline.capi.FLT_OPT_LASER_SPACING
    assert (info.min_value, info.default) == (1e-3, 100.0)
    with pytest.raises(TypeError, match="str"):
        flatline.option_info(101)


def test_reconstructor_options_are_the_resolved_defaults():
    opts = flatline.reconstructor_options()
    assert opts["knot_spacing"] == 100.0  # 0 resolves to laser_spacing
    assert opts["lag_knots"] == 64.0 and opts["row_capacity"] == 8192.0
    assert set(opts) >= {"knot_spacing", "laser_spacing", "height_sigma",
                         "slope_sigma", "curvature_weight", "lag_knots",
                         "max_gap", "row_capacity"}


def test_flag_constants_are_the_c_values():
    assert (flatline.FLAG_INVALID_INPUT, flatline.FLAG_GAP, flatline.FLAG_NO_DATA) == (1, 2, 4)


def test_docstrings_give_units_shapes_and_the_option_table():
    for doc in (flatline.reconstruct.__doc__, flatline.Reconstructor.push.__doc__):
        assert "mm" in doc and ("(n, K)" in doc or "(N, K)" in doc)
    assert "knot_spacing (float): default 0" in flatline.reconstruct.__doc__
    assert "row_capacity (int): default 8192" in flatline.Reconstructor.__doc__
    assert "{options}" not in flatline.Reconstructor.__doc__


def test_py_typed_and_stub_cover_the_public_api():
    assert os.path.isfile(os.path.join(PACKAGE_DIR, "py.typed"))
    stub = os.path.join(PACKAGE_DIR, "__init__.pyi")
    tree = ast.parse(open(stub).read())
    names = set()
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.ClassDef)):
            names.add(node.name)
        elif isinstance(node, ast.AnnAssign):
            names.add(node.target.id)
        elif isinstance(node, ast.Assign):
            names.update(t.id for t in node.targets)
        elif isinstance(node, ast.ImportFrom):
            names.update(a.asname or a.name for a in node.names)
    missing = set(flatline.__all__) - names
    assert not missing, f"stub lacks {sorted(missing)}"
    stub_classes = {n.name: n for n in tree.body if isinstance(n, ast.ClassDef)}

    def stub_members(name, kind):
        return {n.name if kind is ast.FunctionDef else n.target.id
                for n in stub_classes[name].body if isinstance(n, kind)}

    # Every public method and property of the classes over handles, and of
    # Intrinsics and PixelFormat...
    for name in ("Reconstructor", "Calibration", "SimulatedLine", "Extractor",
                 "Intrinsics", "FiberGrid", "Flatness", "Source"):
        real = {m for m in vars(getattr(flatline, name)) if not m.startswith("_")}
        real -= {f for f in getattr(getattr(flatline, name), "_fields", ())}
        real -= {"fx", "fy", "cx", "cy", "k1", "k2", "k3", "k4", "k5", "k6", "p1", "p2"}
        lacking = real - stub_members(name, ast.FunctionDef)
        assert not lacking, f"stub of {name} lacks {sorted(lacking)}"
    # ...every field of the result tuples and the Intrinsics...
    for name in ("FiberGrid", "IntrinsicsFit", "HomographyFit", "SimRows", "SimFrame",
                 "ExtractedRow", "OptionInfo", "Frame", "CameraInfo"):
        assert stub_members(name, ast.AnnAssign) == set(getattr(flatline, name)._fields), name
    for name in ("Intrinsics", "FiberResults", "ZoneResults", "ShapeResult", "WindowInfo",
                 "FlatnessResult"):
        assert stub_members(name, ast.AnnAssign) == {
            f.name for f in dataclasses.fields(getattr(flatline, name))}, name
    # ...and every member of the enums.
    for name in ("Target", "Defect", "PixelFormat", "Shape", "ShapeComponent", "SourceKind"):
        assert stub_members(name, ast.AnnAssign) == set(getattr(flatline, name).__members__), name


def test_component_option_tables_are_the_c_defaults():
    sim = flatline.simulator_options()
    assert sim["sim_seed"] == 1.0 and sim["sim_frame_spacing"] == 3.0
    assert sim["sim_bit_depth"] == 8.0 and sim["sim_line_sigma"] == 2.0
    assert all(name.startswith("sim_") for name in sim) and len(sim) == 20
    extract = flatline.extractor_options()
    assert extract["extract_sg_window"] == 11.0 and extract["extract_sg_order"] == 2.0
    assert extract["extract_laser0_rows"] == 0.0  # automatic band
    assert all(name.startswith("extract_") for name in extract) and len(extract) == 8
    source = flatline.source_options()
    assert source["source_encoder_step"] == 3.0 and source["u3v_transfers"] == 8.0
    assert all(name.startswith(("source_", "u3v_")) for name in source) and len(source) == 11
    assert "u3v_transfers (int): default 8" in flatline.Source.__doc__
    for doc in (flatline.SimulatedLine.__doc__, flatline.Extractor.__doc__,
                flatline.Source.__doc__, flatline.Flatness.__doc__):
        assert "{options}" not in doc
    assert "sim_heave_sigma (float): default 0" in flatline.SimulatedLine.__doc__
    assert "extract_sg_window (int): default 11" in flatline.Extractor.__doc__


def test_enums_are_the_c_values():
    assert [int(d) for d in flatline.Defect] == list(range(8))
    assert flatline.Defect.CROSSBOW == flatline.capi.FLT_SIM_CROSSBOW
    assert [int(p) for p in flatline.PixelFormat] == [8, 10, 12, 16]
    assert flatline.PixelFormat.MONO12.full_scale == 4095
    assert flatline.PixelFormat.MONO8.dtype == np.uint8
    assert flatline.PixelFormat.MONO10.dtype == np.uint16
    assert [int(t) for t in flatline.Target] == [0, 1, 2]
    assert flatline.LASERS == 2
    assert [int(s) for s in flatline.Shape] == list(range(8))
    assert int(flatline.ShapeComponent.CROSSBOW) == 32
    assert [int(k) for k in flatline.SourceKind] == [1, 2, 3]
    from flatline.testing import U3VFault, U3VSimParam
    assert U3VFault.LATE_ACK == 13 and U3VSimParam.OPEN == 25
    assert (flatline.FIBER_NO_DATA, flatline.FIBER_NO_WAVE, flatline.FIBER_PARTIAL) == (1, 2, 4)
    assert (flatline.WINDOW_SHORT, flatline.WINDOW_NO_VALID_FIBER, flatline.WINDOW_NO_BOW,
            flatline.WINDOW_NO_CROSSBOW, flatline.ZONE_NO_DATA) == (1, 2, 4, 8, 1)


def test_all_names_exist():
    for name in flatline.__all__:
        assert hasattr(flatline, name), name
