# SPDX-License-Identifier: Apache-2.0
"""The frame-to-profile extractor through Python, against the simulated
sensor's ground truth: rows, peaks, frames without copies, 16-bit frames,
the streaming pipeline, errors."""

import numpy as np
import pytest

import flatline

from conftest import bits, roi_reference


@pytest.fixture(scope="module")
def calib():
    return roi_reference(fibers=101, pitch=20.0)  # x = -1000 .. 1000 mm, rows 892..1147


def sheet(sim):
    sim.add_defect("centre_buckle", 12.0, 1800.0)
    sim.add_defect("wavy_edge_both", 8.0, 900.0)


def two_laser_height(sim, s):
    """What the extractor's height means: the mean of the sheet under the two
    lasers, at s + 50 (laser 0, offset -50) and s - 50 (laser 1)."""
    x = sim.fiber_x
    return (sim.surface(x, s + 50.0) + sim.surface(x, s - 50.0)) / 2


def test_rows_measure_the_sheet_within_a_tenth_of_a_millimetre(calib):
    # Noise-free motion, default rendering (speckle 0.05, shot noise): the C
    # test's bound, 2 sigma of the height error <= 0.1 mm, >= 99.5 % valid.
    with flatline.SimulatedLine(calib, sim_start=200.0) as sim, \
            flatline.Extractor(calib) as extractor:
        sheet(sim)
        errors = []
        for _ in range(10):
            frame = sim.next_frame()
            row = extractor.process(frame.image, frame.encoder_mm)
            assert isinstance(row, flatline.ExtractedRow)
            assert row.s == frame.s  # e - (offset_0 + offset_1) / 2
            assert row.height.shape == row.slope.shape == row.valid.shape == (101,)
            assert row.valid.dtype == np.bool_
            assert np.isnan(row.height[~row.valid]).all()
            errors.append(row.height - two_laser_height(sim, frame.s))
    errors = np.array(errors)
    valid = np.isfinite(errors)
    sigma = errors[valid].std()
    print(f"extractor heights: 2 sigma {2 * sigma:.4f} mm, bias {errors[valid].mean():+.4f} mm, "
          f"{100 * valid.mean():.2f} % valid")
    assert valid.mean() >= 0.995
    assert 2 * sigma <= 0.1 and abs(errors[valid].mean()) <= 0.05


def test_peaks_are_within_a_sixteenth_of_a_pixel_and_nan_where_none(calib):
    with flatline.SimulatedLine(calib, sim_seed=3) as sim, \
            flatline.Extractor(calib) as extractor:
        sheet(sim)
        with pytest.raises(flatline.StateError, match="no frame has been processed"):
            extractor.peaks()
        frame = sim.next_frame()
        rows = extractor.peaks(frame.image)  # processes the frame
        assert rows.shape == (2, 2048) and rows.dtype == np.float64
        np.testing.assert_array_equal(bits(extractor.peaks()), bits(rows))  # the last frame's
        both = np.isfinite(rows) & np.isfinite(frame.peak_rows)
        assert both.mean() > 0.99
        rms = np.sqrt(np.mean((rows[both] - frame.peak_rows[both]) ** 2))
        print(f"extractor peaks: RMS error {rms:.4f} px (1/{1 / rms:.0f})")
        assert rms <= 1 / 16
        # A black frame has no line: every peak is NaN, every fiber invalid
        # (the bands were found in the first frame).
        dark = np.zeros((256, 2048), np.uint8)
        assert np.isnan(extractor.peaks(dark)).all()
        row = extractor.process(dark, 0.0)
        assert not row.valid.any() and np.isnan(row.height).all()
        profiles = extractor.laser_profiles()
        assert profiles.shape == (2, 101) and np.isnan(profiles).all()


def test_bands_are_found_in_the_first_frame(calib):
    with flatline.SimulatedLine(calib) as sim, flatline.Extractor(calib) as extractor:
        with pytest.raises(flatline.StateError, match="automatic"):
            extractor.band(0)
        # A first frame without two lines cannot place the bands: a
        # NumericError, and the next frame tries again.
        with pytest.raises(flatline.NumericError, match="does not show two laser lines") as info:
            extractor.process(np.zeros((256, 2048), np.uint8), 0.0)
        assert info.value.status == -10
        frame = sim.next_frame()
        extractor.process(frame.image, frame.encoder_mm)
        for laser in (0, 1):
            first, rows = extractor.band(laser)
            centre = np.nanmedian(frame.peak_rows[laser])
            assert first <= centre < first + rows
    with flatline.Extractor(calib, extract_laser0_first_row=120, extract_laser0_rows=60,
                            extract_laser1_first_row=70, extract_laser1_rows=50) as fixed:
        assert fixed.band(0) == (120, 60) and fixed.band(1) == (70, 50)


def test_bands_are_found_from_one_line(calib):
    # One laser on (a commissioning engineer aligning it): its line's laser
    # is the one whose plane puts it near the pass line, the other band
    # goes where the calibration puts the other line. The bands land within
    # 3 rows of those found from both lines (the other line's row is
    # predicted, not seen), and the next two-line frame reads the same
    # heights within 0.02 mm (only the column maps' fitting interval moves).
    with flatline.SimulatedLine(calib) as sim:
        frame = sim.next_frame()
    with flatline.Extractor(calib) as both:
        reference = both.process(frame.image, frame.encoder_mm)
        bands = [both.band(laser) for laser in (0, 1)]
    for lit in (0, 1):
        dark = 1 - lit
        one = frame.image.copy()
        first, rows = bands[dark]
        one[first:first + rows, :] = frame.image[0, :]  # background and noise only
        with flatline.Extractor(calib) as extractor:
            row = extractor.process(one, frame.encoder_mm)
            assert not row.valid.any()  # the dark laser sees no strip
            for laser in (0, 1):
                got, want = extractor.band(laser), bands[laser]
                assert abs(got[0] - want[0]) <= 3
                assert abs(got[0] + got[1] - want[0] - want[1]) <= 3
            again = extractor.process(frame.image, frame.encoder_mm)
            assert np.array_equal(again.valid, reference.valid) and reference.valid.sum() >= 99
            assert np.max(np.abs(again.height - reference.height)[reference.valid]) <= 0.02
    # A line either laser could cast (z = +53 mm for one, -46 mm for the
    # other): refused, with both heights, and the next frame tries again.
    ambiguous = np.full((256, 2048), 10, np.uint8)
    ambiguous[122:131, :] = (10 + 150 * np.exp(-0.5 * (np.arange(-4, 5) / 1.5) ** 2)
                             ).round().astype(np.uint8)[:, None]
    with flatline.Extractor(calib) as extractor:
        with pytest.raises(flatline.NumericError, match="either laser's"):
            extractor.process(ambiguous, 0.0)
        extractor.process(frame.image, frame.encoder_mm)
        assert extractor.band(0)[1] > 0


def test_frames_without_a_copy_and_layouts_that_need_one(calib):
    with flatline.SimulatedLine(calib, sim_seed=5) as sim, \
            flatline.Extractor(calib) as extractor:
        sheet(sim)
        frame = sim.next_frame()
        image = frame.image
        want = extractor.process(image, frame.encoder_mm)
        # C-contiguous: the very array goes to C.
        passed, bits_per_pixel = extractor._frame("process", image)
        assert passed is image and bits_per_pixel == 8
        # A row-strided view of a wider buffer (an ROI, a padded camera line)
        # goes to C without a copy too, with its stride.
        padded = np.zeros((256, 2048 + 64), np.uint8)
        padded[:, 16:2064] = image
        view = padded[:, 16:2064]
        passed, _ = extractor._frame("process", view)
        assert passed is view and not view.flags.c_contiguous
        got = extractor.process(view, frame.encoder_mm)
        np.testing.assert_array_equal(bits(got.height), bits(want.height))
        # Fortran order and swapped bytes are copied once, same result.
        for variant in (np.asfortranarray(image),):
            got = extractor.process(variant, frame.encoder_mm)
            np.testing.assert_array_equal(bits(got.slope), bits(want.slope))


def test_sixteen_bit_frames_need_their_pixel_format(calib):
    # Mono12 frames: with pixel_format="mono12" the thresholds are fractions
    # of 4095 and the heights match the 8-bit run's quality; read as Mono16
    # (full scale 65535) the lines are below extract_min_peak and nothing is
    # valid.
    with flatline.SimulatedLine(calib, sim_bit_depth=12, sim_start=200.0) as sim:
        sheet(sim)
        frame = sim.next_frame()
        expected = two_laser_height(sim, frame.s)
    assert frame.image.dtype == np.uint16
    with flatline.Extractor(calib, pixel_format="mono12") as extractor:
        assert extractor.pixel_format is flatline.PixelFormat.MONO12
        row = extractor.process(frame.image, frame.encoder_mm)
        errors = row.height - expected
        assert row.valid.mean() >= 0.99 and np.nanstd(errors) <= 0.05
        with pytest.raises(TypeError, match="pixel format MONO12 needs uint16"):
            extractor.process(frame.image.astype(np.uint8), frame.encoder_mm)
        swapped = frame.image.astype(">u2")  # copied to native order, same values
        np.testing.assert_array_equal(
            bits(extractor.process(swapped, frame.encoder_mm).height), bits(row.height))
    with flatline.Extractor(calib) as as_mono16:
        assert not as_mono16.process(frame.image, frame.encoder_mm).valid.any()


def test_frames_of_wrong_type_or_shape_are_refused_naming_frame(calib):
    bands = dict(extract_laser0_first_row=120, extract_laser0_rows=60,
                 extract_laser1_first_row=70, extract_laser1_rows=50)
    with flatline.Extractor(calib, **bands) as extractor:
        good = np.zeros((256, 2048), np.uint8)
        for bad, error, needle in [
            (good.astype(np.float64), TypeError, "dtype float64"),
            (good.astype(np.int32), TypeError, "dtype int32"),
            (good.astype(np.int8), TypeError, "dtype int8"),
            (good.tolist(), TypeError, "must be a numpy array"),
            (good[:, :1024], ValueError, r"shape \(256, 1024\)"),
            (good[None], ValueError, r"shape \(1, 256, 2048\)"),
            (good.T, ValueError, r"shape \(2048, 256\)"),
            (np.zeros((256, 2048, 3), np.uint8), ValueError, r"3 channels; pass one channel"),
        ]:
            with pytest.raises(error, match=f"argument 'frame'.*{needle}|{needle}"):
                extractor.process(bad, 0.0)
        with pytest.raises(flatline.InvalidArgumentError, match="'encoder_mm' = nan"):
            extractor.process(good, float("nan"))
        with pytest.raises(TypeError, match="'encoder_mm' must be a real number"):
            extractor.process(good, "0")
        # The raw layer: the helper refuses what the C API cannot read...
        handle = extractor._live()
        h, g, v = np.empty(101), np.empty(101), np.empty(101, np.uint8)
        with pytest.raises(TypeError, match="native uint8 array"):
            handle.process_frame(good.astype(np.uint16), 8, 0.0, h, g, v)
        with pytest.raises(ValueError, match="contiguous rows"):
            handle.process_frame(np.asfortranarray(good), 8, 0.0, h, g, v)
        with pytest.raises(TypeError, match="must be a numpy array"):
            handle.process_frame(b"x" * 10, 8, 0.0, h, g, v)
        # ...and the library names a bad format or size.
        with pytest.raises(flatline.InvalidArgumentError, match="'format' = 9"):
            handle.process_frame(good, 9, 0.0, h, g, v)
        with pytest.raises(flatline.InvalidArgumentError, match="2048 x 255"):
            handle.process_frame(good[:255], 8, 0.0, h, g, v)
        with pytest.raises(flatline.InvalidArgumentError, match="'fibers' = 100"):
            handle.process_frame(good, 8, 0.0, h[:100], g[:100], v[:100])
        # Still usable after all that.
        assert extractor.process(good, 1.0).s == 1.0
        assert not extractor.process(good, 1.0).valid.any()  # a black frame


def test_options_and_calibration_are_checked(calib):
    with pytest.raises(flatline.InvalidArgumentError,
                       match="'extract_sg_window' = 5 must be at least 'extract_sg_order' \\+ 2"):
        flatline.Extractor(calib, extract_sg_window=5, extract_sg_order=4)
    with pytest.raises(flatline.InvalidArgumentError, match="'extract_sg_order' = 8 is outside"):
        flatline.Extractor(calib, extract_sg_order=8)
    with pytest.raises(flatline.InvalidArgumentError, match="must be odd"):
        flatline.Extractor(calib, extract_sg_window=8)
    with pytest.raises(flatline.InvalidArgumentError, match="exceeds the frame height 256"):
        flatline.Extractor(calib, extract_laser0_first_row=200, extract_laser0_rows=100,
                           extract_laser1_first_row=0, extract_laser1_rows=100)
    with pytest.raises(TypeError, match="another component"):
        flatline.Extractor(calib, sim_seed=3)
    with pytest.raises(flatline.StateError, match="'calib' is not finished"):
        flatline.Extractor(flatline.Calibration())
    with pytest.raises(TypeError, match="must be a Calibration"):
        flatline.Extractor(None)
    with pytest.raises(ValueError, match="'pixel_format' = 9"):
        flatline.Extractor(calib, pixel_format=9)
    with pytest.raises(ValueError, match="'pixel_format' = 'mono9'"):
        flatline.Extractor(calib, pixel_format="mono9")
    extractor = flatline.Extractor(calib)
    assert extractor.calibration is calib and extractor.fibers == 101
    assert extractor.frame_size == (2048, 256)
    assert "fibers=101 frame=2048x256" in repr(extractor)
    extractor.close()
    with pytest.raises(flatline.StateError, match="closed"):
        extractor.process(np.zeros((256, 2048), np.uint8), 0.0)


def test_frames_to_rows_to_reconstructor_follow_the_sheet(calib):
    # The whole pipeline on a 1.8 m stretch of the reference sheet (one
    # centre-buckle period, 300 frames at 6 mm): the streamed reconstruction
    # stays within 0.5 mm of the truth (the C test's end-to-end bound).
    with flatline.SimulatedLine(calib, sim_frame_spacing=6.0, sim_start=200.0) as sim, \
            flatline.Extractor(calib) as extractor, \
            flatline.Reconstructor(calib.fiber_grid.count, lag_knots=8,
                                   laser_spacing=calib.laser_spacing) as recon:
        sim.add_defect("centre_buckle", 12.0, 1800.0)
        out, truth = [], {}
        for _ in range(300):
            frame = sim.next_frame()
            row = extractor.process(frame.image, frame.encoder_mm)
            truth[row.s] = frame.truth
            recon.push(row.s, row.height, row.slope, row.valid)
            out.append(recon.pull())
        recon.end_sheet()
        out.append(recon.pull())
    s, z, _ = (np.concatenate(p) for p in zip(*out))
    assert len(s) == 300
    error = np.abs(z - np.array([truth[v] for v in s]))
    print(f"frames -> extractor -> reconstructor: max error {error.max():.3f} mm")
    assert error.max() <= 0.5
