# SPDX-License-Identifier: Apache-2.0
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


# --- calibration, simulator, extractor -----------------------------------------

from conftest import roi_reference  # noqa: E402


@pytest.mark.parametrize("laser", [0, 1])
def test_mapping_equals_c_bit_for_bit(clib, laser):
    calib = flatline.Calibration.reference()
    text = calib.dumps()
    rng = np.random.default_rng(100 + laser)
    image = rng.uniform([0, 900], [2047, 1100], (5000, 2))
    image[::97] = np.nan  # invalid peaks stay invalid on both sides
    plane = rng.uniform([-1000, -50], [1000, 50], (5000, 2))
    np.testing.assert_array_equal(bits(calib.image_to_plane(laser, image)),
                                  bits(clib.map_points(text, "image_to_plane", laser, image)))
    np.testing.assert_array_equal(bits(calib.plane_to_image(laser, plane)),
                                  bits(clib.map_points(text, "plane_to_image", laser, plane)))
    np.testing.assert_array_equal(bits(calib.undistort(image)),
                                  bits(clib.map_points(text, "undistort", 0, image)))


def test_simulator_rows_equal_c_bit_for_bit(clib):
    calib = roi_reference(fibers=101, pitch=20.0)
    options = dict(sim_seed=17, sim_heave_sigma=2.5, sim_peak_sigma=1 / 16,
                   sim_shear_amplitude=50.0)
    defects = [(flatline.Defect.CENTRE_BUCKLE, 12.0, 1800.0),
               (flatline.Defect.QUARTER_BUCKLE, 3.0, 700.0)]
    want = clib.sim_rows(calib.dumps(), defects, [300, 200], **options)
    with flatline.SimulatedLine(calib, **options) as sim:
        for kind, amplitude, period in defects:
            sim.add_defect(kind, amplitude, period)
        parts = [sim.next_rows(n) for n in (300, 200)]
    got = [np.concatenate(p) for p in zip(*parts)]
    for name, g, w in zip(flatline.SimRows._fields, got, want):
        if g.dtype == np.bool_:
            np.testing.assert_array_equal(g.view(np.uint8), w, err_msg=name)
        else:
            np.testing.assert_array_equal(bits(g), bits(w), err_msg=name)


def test_extractor_rows_equal_c_bit_for_bit(clib):
    calib = roi_reference(fibers=101, pitch=20.0)
    with flatline.SimulatedLine(calib, sim_seed=4, sim_reflections=1) as sim:
        sim.add_defect("centre_buckle", 12.0, 1800.0)
        frames = [sim.next_frame() for _ in range(5)]
    encoders = [f.encoder_mm for f in frames]
    h_c, g_c, v_c, s_c = clib.extract(calib.dumps(), [f.image for f in frames], encoders,
                                      extract_sg_window=9)
    with flatline.Extractor(calib, extract_sg_window=9) as extractor:
        rows = [extractor.process(f.image, f.encoder_mm) for f in frames]
    np.testing.assert_array_equal(bits(np.array([r.height for r in rows])), bits(h_c))
    np.testing.assert_array_equal(bits(np.array([r.slope for r in rows])), bits(g_c))
    np.testing.assert_array_equal(np.array([r.valid for r in rows]).view(np.uint8), v_c)
    np.testing.assert_array_equal(np.array([r.s for r in rows]), s_c)
    assert v_c.mean() > 0.9  # real rows, not all-invalid ones
