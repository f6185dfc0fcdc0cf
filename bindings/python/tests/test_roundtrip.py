"""Python results equal the C API's, bit for bit, on the same input. The
reference side calls the very libflatline the extension loaded through
ctypes, so any difference would be the binding's (a conversion, a copy with a
different layout, a mask or an option lost on the way)."""

import numpy as np
import pytest

import flatline

from conftest import bits, noisy_sheet


@pytest.mark.parametrize("seed", [11, 12])
@pytest.mark.parametrize("options", [{}, {"knot_spacing": 50.0, "height_sigma": 1.0,
                                          "max_gap": 20.0}])
def test_reconstruct_equals_c_bit_for_bit(clib, seed, options):
    s, h, sl, valid = noisy_sheet(seed)
    z_c, flags_c = clib.reconstruct(s, h, sl, valid, **options)
    z_py, flags_py = flatline.reconstruct_with_flags(s, h, sl, valid, **options)
    np.testing.assert_array_equal(bits(z_py), bits(z_c))
    np.testing.assert_array_equal(flags_py, flags_c)
    assert flags_c.any()  # the masks really were passed (2 % invalid)
    # and without a mask
    z_c, _ = clib.reconstruct(s, h, sl, None, **options)
    np.testing.assert_array_equal(bits(flatline.reconstruct(s, h, sl, **options)), bits(z_c))


def test_streaming_equals_c_bit_for_bit(clib):
    s, h, sl, valid = noisy_sheet(21, rows=2500, fibers=5)
    cuts = [0, 1, 300, 301, 1000, 2500]
    blocks = [(s[a:b], h[a:b], sl[a:b], valid[a:b]) for a, b in zip(cuts, cuts[1:])]
    s_c, z_c, f_c = clib.stream(blocks, 5, lag_knots=6)
    with flatline.Reconstructor(5, lag_knots=6) as recon:
        out = []
        for bs, bh, bsl, bv in blocks:
            if len(bs) == 1:  # exercise the one-row form too
                recon.push(bs[0], bh[0], bsl[0], bv[0])
            else:
                recon.push(bs, bh, bsl, bv)
            out.append(recon.pull())
        recon.end_sheet()
        out.append(recon.pull())
    s_py, z_py, f_py = (np.concatenate(parts) for parts in zip(*out))
    assert len(s_py) == len(s)
    np.testing.assert_array_equal(bits(s_py), bits(s_c))
    np.testing.assert_array_equal(bits(z_py), bits(z_c))
    np.testing.assert_array_equal(f_py, f_c)
