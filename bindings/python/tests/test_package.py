"""Package surface: versions, option table, constants, typing files."""

import ast
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
    # and the Reconstructor's public methods
    cls = next(n for n in tree.body if isinstance(n, ast.ClassDef) and n.name == "Reconstructor")
    stub_methods = {n.name for n in cls.body if isinstance(n, ast.FunctionDef)}
    real = {m for m in dir(flatline.Reconstructor) if not m.startswith("_")}
    assert real <= stub_methods


def test_all_names_exist():
    for name in flatline.__all__:
        assert hasattr(flatline, name), name
