# SPDX-License-Identifier: Apache-2.0
"""Package surface: versions, option table, constants, typing files."""

import dataclasses
import enum
import importlib
import inspect
import math
import os
import re
import typing

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
        "slope_sigma": 1e-3, "curvature_weight": 1e-3, "lag_knots": -1.0,
        "max_gap": 200.0, "row_capacity": 8192.0, "rigid_motion": 0.0,
        "shape_sigma": 0.1, "curvature_jump_weight": 10.0, "latency_mm": 2000.0,
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
    # lag_knots -1 resolves to the lag latency_mm allows: 15 knots at 100 mm
    # (15 + 2 + 1 knots and half the laser spacing, 1850 mm, within 2000).
    assert opts["lag_knots"] == 15.0 and opts["row_capacity"] == 8192.0
    assert opts["latency_mm"] == 1850.0
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


def _public_callables():
    """(where, function) for every public function of the package and every
    public method, property accessor, classmethod and staticmethod of its
    public classes (enums and exceptions have nothing of their own)."""
    for name in flatline.__all__:
        obj = getattr(flatline, name)
        if inspect.isclass(obj):
            if issubclass(obj, (enum.Enum, BaseException)):
                continue
            for member, value in vars(obj).items():
                if member.startswith("_") and member not in ("__init__", "__enter__", "__exit__",
                                                              "__iter__", "__next__", "__len__",
                                                              "__getitem__", "__call__"):
                    continue
                if isinstance(value, property):
                    for accessor in (value.fget, value.fset):
                        if accessor is not None:
                            yield f"{name}.{member}", accessor
                elif isinstance(value, (staticmethod, classmethod)):
                    yield f"{name}.{member}", value.__func__
                elif inspect.isfunction(value):
                    yield f"{name}.{member}", value
        elif inspect.isfunction(obj):
            yield name, obj


def test_py_typed_and_inline_annotations_cover_the_public_api():
    # Type checkers read the package's own annotations (PEP 561: py.typed);
    # a hand-written __init__.pyi would shadow them and drift from the code.
    assert os.path.isfile(os.path.join(PACKAGE_DIR, "py.typed"))
    assert not os.path.exists(os.path.join(PACKAGE_DIR, "__init__.pyi"))
    assert all(hasattr(flatline, name) for name in flatline.__all__)
    testing = importlib.import_module("flatline.testing")
    testing_types = {name: getattr(testing, name) for name in testing.__all__}
    checked = 0
    for where, function in _public_callables():
        signature = inspect.signature(function)
        for parameter in list(signature.parameters.values())[1 if "." in where else 0:]:
            if parameter.name in ("self", "cls"):
                continue
            assert parameter.annotation is not inspect.Parameter.empty, \
                f"{where}: parameter '{parameter.name}' has no annotation"
        if function.__name__ != "__init__":
            assert signature.return_annotation is not inspect.Signature.empty, \
                f"{where}: no return annotation"
        # The annotations name real types (forward references resolve; the
        # testing tier's types, named only for type checkers where a bus is
        # taken, resolve in flatline.testing).
        typing.get_type_hints(function, localns=testing_types)
        checked += 1
    assert checked > 150  # the whole surface was walked, not an empty list
    # Every field of the result tuples is typed.
    for name in flatline.__all__:
        obj = getattr(flatline, name)
        if inspect.isclass(obj) and issubclass(obj, tuple) and hasattr(obj, "_fields"):
            assert set(typing.get_type_hints(obj)) == set(obj._fields), name
        elif dataclasses.is_dataclass(obj):
            assert all(f.type is not None for f in dataclasses.fields(obj)), name


def test_component_option_tables_are_the_c_defaults():
    sim = flatline.simulator_options()
    assert sim["sim_seed"] == 1.0 and sim["sim_frame_spacing"] == 3.0
    assert sim["sim_bit_depth"] == 8.0 and sim["sim_line_sigma"] == 2.0
    assert all(name.startswith("sim_") for name in sim) and len(sim) == 40
    extract = flatline.extractor_options()
    assert extract["extract_sg_window"] == 11.0 and extract["extract_sg_order"] == 2.0
    assert extract["extract_laser0_rows"] == 0.0  # automatic band
    assert all(name.startswith("extract_") for name in extract) and len(extract) == 11
    source = flatline.source_options()
    assert source["source_encoder_step"] == 3.0 and source["u3v_transfers"] == 8.0
    assert source["gige_resend_attempts"] == 3.0 and source["gige_packet_size"] == 0.0
    assert all(name.startswith(("source_", "u3v_", "gige_")) for name in source)
    assert len(source) == 11 + 9
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
    assert [int(s) for s in flatline.Shape] == list(range(9))
    assert int(flatline.ShapeComponent.CROSSBOW) == 32
    assert [int(k) for k in flatline.SourceKind] == [1, 2, 3, 4, 5]
    assert flatline.SourceKind.RECORDING == flatline.capi.FLT_SOURCE_RECORDING
    from flatline.testing import U3VFault, U3VSimParam
    assert U3VFault.LATE_ACK == 13 and U3VSimParam.OPEN == 25
    assert (flatline.FIBER_NO_DATA, flatline.FIBER_NO_WAVE, flatline.FIBER_PARTIAL) == (1, 2, 4)
    assert (flatline.WINDOW_SHORT, flatline.WINDOW_NO_VALID_FIBER, flatline.WINDOW_NO_BOW,
            flatline.WINDOW_NO_CROSSBOW, flatline.ZONE_NO_DATA) == (1, 2, 4, 8, 1)


def test_all_names_exist():
    for name in flatline.__all__:
        assert hasattr(flatline, name), name
