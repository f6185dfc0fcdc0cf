# SPDX-License-Identifier: Apache-2.0
"""numpy conversion: what is accepted, what is refused (with the argument's
name), and that nothing crashes, including direct calls of the raw layer."""

import numpy as np
import pytest

import flatline
from flatline import _arrays, capi

from conftest import bits, sine_sheet


@pytest.fixture(scope="module")
def sheet():
    s, h, sl, _ = sine_sheet(fibers=3, length=1200)
    return s, h, sl


@pytest.fixture(scope="module")
def reference(sheet):
    return flatline.reconstruct(*sheet)


def test_c_contiguous_float64_is_not_copied():
    a = np.zeros((5, 3))
    assert _arrays.as_float64("f", "height", a, 2) is a
    mask = np.ones((5, 3), bool)
    assert np.shares_memory(_arrays.as_mask("f", "valid", mask, 2), mask)


@pytest.mark.parametrize("convert", [
    np.asfortranarray,
    lambda a: np.repeat(a, 2, axis=-1)[..., ::2],  # non-contiguous view
    lambda a: a.astype(">f8"),  # big-endian
    lambda a: a.tolist(),
], ids=["fortran", "strided", "big-endian", "list"])
def test_any_array_like_with_the_same_values_gives_the_same_bits(sheet, reference, convert):
    s, h, sl = sheet
    z = flatline.reconstruct(convert(s), convert(h), convert(sl))
    np.testing.assert_array_equal(bits(z), bits(reference))


def test_integer_and_float32_inputs_are_converted_exactly():
    s = np.arange(0, 600, 3)  # int64: exact in float64
    h = np.zeros((len(s), 2), np.int32)
    sl = np.zeros((len(s), 2), np.float32)
    z = flatline.reconstruct(s, h, sl)
    assert z.dtype == np.float64 and z.shape == (len(s), 2)
    # A flat zero sheet reconstructs to zero to rounding (heights are exact).
    assert np.abs(z).max() < 1e-12


@pytest.mark.parametrize("name, bad", [
    ("s", lambda s, h, sl: (s.astype(complex), h, sl)),
    ("height", lambda s, h, sl: (s, h.astype(complex), sl)),
    ("slope", lambda s, h, sl: (s, h, sl.astype(str))),
    ("height", lambda s, h, sl: (s, h.astype(object), sl)),
    ("height", lambda s, h, sl: (s, h.astype(np.longdouble), sl)),  # would lose bits
    ("s", lambda s, h, sl: (s.astype("datetime64[ms]"), h, sl)),
])
def test_unsafe_dtypes_are_type_errors_naming_the_argument(sheet, name, bad):
    args = bad(*sheet)
    with pytest.raises(TypeError, match=f"argument '{name}'"):
        flatline.reconstruct(*args)


def test_wrong_ndim_and_shapes_are_value_errors_naming_the_argument(sheet):
    s, h, sl = sheet
    with pytest.raises(ValueError, match="'height' must have 2 dimensions"):
        flatline.reconstruct(s, h[:, 0], sl)
    with pytest.raises(ValueError, match="'s' must have 1 dimension"):
        flatline.reconstruct(s[:, None], h, sl)
    with pytest.raises(ValueError, match=r"'s' has shape \(399,\)"):
        flatline.reconstruct(s[:-1], h, sl)
    with pytest.raises(ValueError, match="'slope' has shape"):
        flatline.reconstruct(s, h, sl[:, :2])
    with pytest.raises(ValueError, match="'valid' has shape"):
        flatline.reconstruct(s, h, sl, valid=np.ones((len(s), 2), bool))
    with pytest.raises(TypeError, match="'valid' must be a bool"):
        flatline.reconstruct(s, h, sl, valid=np.ones(h.shape))
    with pytest.raises(TypeError, match="'height' must be array-like, not None"):
        flatline.reconstruct(s, None, sl)
    with pytest.raises(TypeError, match="'height' is not array-like"):
        flatline.reconstruct(s, [[1.0, 2.0], [3.0]], sl)
    with pytest.raises(TypeError, match="masked array"):
        flatline.reconstruct(s, np.ma.masked_invalid(h), sl)


def test_empty_input_is_an_invalid_argument():
    with pytest.raises(flatline.InvalidArgumentError, match="'rows' is 0"):
        flatline.reconstruct(np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)))


def test_integer_mask_is_compared_with_zero(sheet):
    s, h, sl = sheet
    mask = np.ones(h.shape, np.int64) * 7
    mask[::5, 1] = 0
    z1, f1 = flatline.reconstruct_with_flags(s, h, sl, valid=mask)
    z2, f2 = flatline.reconstruct_with_flags(s, h, sl, valid=mask != 0)
    np.testing.assert_array_equal(bits(z1), bits(z2))
    np.testing.assert_array_equal(f1, f2)
    assert (f1[::5, 1] & flatline.FLAG_INVALID_INPUT).all()


def test_reconstructor_checks_fibers_and_row_shapes():
    s, h, sl, _ = sine_sheet(fibers=3, length=300)
    with flatline.Reconstructor(3) as recon:
        with pytest.raises(ValueError, match=r"'height' has shape \(100, 2\), but a Reconstructor of 3 fibers"):
            recon.push(s, h[:, :2], sl[:, :2])
        with pytest.raises(ValueError, match="'s' must be a scalar"):
            recon.push(s[:2], h[0], sl[0])
        with pytest.raises(ValueError, match="'slope' has shape"):
            recon.push(s[0], h[0], sl[0, :2])
        with pytest.raises(TypeError, match="'height'"):
            recon.push(s[0], h[0].astype(complex), sl[0])
        assert recon.ready == 0


# --- the raw SWIG layer: numpy.i and the helpers must refuse, not crash ------


def test_raw_layer_refuses_wrong_dtypes_and_inconsistent_shapes():
    recon = capi.flt_recon_create(2, None)
    s = np.arange(4.0)
    h = np.zeros((4, 2))
    with pytest.raises(TypeError):
        recon.push_block(s.astype(complex), h, h, _arrays.NO_MASK, 0)
    with pytest.raises((TypeError, ValueError)):  # numpy.i: "could not convert"
        recon.push_block(s, "not an array", h, _arrays.NO_MASK, 0)
    with pytest.raises(flatline.InvalidArgumentError, match="height.shape\\[0\\] is 3 but should be 4"):
        recon.push_block(s, h[:3], h[:3], _arrays.NO_MASK, 0)
    with pytest.raises(flatline.InvalidArgumentError, match="valid.shape\\[0\\]"):
        recon.push_block(s, h, h, _arrays.NO_MASK, 1)
    with pytest.raises(flatline.InvalidArgumentError, match="'fibers' = 3 but the reconstructor has 2"):
        recon.push_block(s, np.zeros((4, 3)), np.zeros((4, 3)), _arrays.NO_MASK, 0)
    with pytest.raises(TypeError):  # pull targets must be exactly float64/uint8
        recon.pull_into(np.zeros(4, np.float32), np.zeros((4, 2)), np.zeros((4, 2), np.uint8))
    with pytest.raises(flatline.InvalidArgumentError, match="z_out.shape\\[0\\]"):
        recon.pull_into(np.zeros(4), np.zeros((3, 2)), np.zeros((4, 2), np.uint8))
    with pytest.raises(TypeError):
        capi.flt_py_reconstruct(None, s, h, h, _arrays.NO_MASK, 0, np.zeros((4, 2)), np.zeros((4, 2)))
    with pytest.raises(flatline.InvalidArgumentError, match="z_out.size"):
        capi.flt_py_reconstruct(None, s, h, h, _arrays.NO_MASK, 0, np.zeros((4, 3)),
                                np.zeros((4, 2), np.uint8))
