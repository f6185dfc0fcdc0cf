# SPDX-License-Identifier: Apache-2.0
"""The simulated sensor through Python: the sheet and its ground truth,
profile rows, rendered frames, determinism, errors, lifetime."""

import gc
import weakref

import numpy as np
import pytest

import flatline

from conftest import bits, roi_reference

NOISY = dict(sim_heave_sigma=2.5, sim_tilt_sigma=1e-3, sim_eccentricity_amplitude=0.5,
             sim_peak_sigma=1 / 16)


@pytest.fixture(scope="module")
def small_calib():
    return roi_reference(fibers=101, pitch=20.0)  # x = -1000 .. 1000 mm


def reference_sheet(sim):
    """The reference article's sheet: centre buckles and wavy edges, sinusoidal
    along travel with period 1800 mm, 12 mm amplitude."""
    sim.add_defect("centre_buckle", 12.0, 1800.0)
    sim.add_defect(flatline.Defect.WAVY_EDGE_BOTH, 12.0, 1800.0)


def test_default_simulator_is_the_reference_sensor():
    with flatline.SimulatedLine() as sim:
        assert sim.fibers == 1001 and sim.frame_size == (2048, 2048)
        assert sim.pixel_format is flatline.PixelFormat.MONO8
        assert sim.calibration.finished and sim.calibration.laser_spacing == 100.0
        assert sim.fiber_x[0] == -1000.0 and sim.fiber_x[-1] == 1000.0
        assert "fibers=1001 frame=2048x2048 MONO8" in repr(sim)


def test_defect_shapes_follow_the_header(small_calib):
    # W = 2000 mm (sim_strip_width): the formulas of flatline/sim.h.
    with flatline.SimulatedLine(small_calib) as sim:
        s = np.array([450.0])  # a quarter period of 1800 mm: sin = 1
        assert sim.surface(0.0, 450.0) == 0.0  # starts flat
        sim.add_defect("centre_buckle", 12.0, 1800.0)
        assert sim.surface(0.0, 450.0) == pytest.approx(12.0, abs=1e-12)
        assert sim.surface(1000.0, 450.0) == pytest.approx(0.0, abs=1e-12)  # cos^2(pi/2)
        assert sim.surface(500.0, 450.0) == pytest.approx(6.0, abs=1e-12)  # cos^2(pi/4)
        sim.clear_sheet()
        sim.add_defect(flatline.Defect.WAVY_EDGE_LEFT, 4.0)  # period 0: constant
        z = sim.surface([-1000.0, -500.0, 0.0, 500.0], [7.0, 7.0, 7.0, 7.0])
        np.testing.assert_allclose(z, [4.0, 4.0 / 16, 0.0, 0.0], rtol=0, atol=1e-12)
        sim.add_defect(flatline.Defect.BOW, 1.5, 0.0)  # defects add up
        assert sim.surface(0.0, s) == pytest.approx([1.5], abs=1e-12)
        sim.clear_sheet()
        assert np.all(sim.surface(np.linspace(-1000, 1000, 5), 100.0) == 0.0)


def test_surface_broadcasts_x_and_s(small_calib):
    with flatline.SimulatedLine(small_calib) as sim:
        reference_sheet(sim)
        x = np.linspace(-1000, 1000, 7)
        s = np.arange(0.0, 3000.0, 500.0)
        grid = sim.surface(x[None, :], s[:, None])
        assert grid.shape == (6, 7)
        for i, si in enumerate(s):
            np.testing.assert_array_equal(bits(grid[i]), bits(sim.surface(x, np.full(7, si))))
        with pytest.raises(ValueError, match="do not broadcast"):
            sim.surface(np.zeros(3), np.zeros(4))


def test_height_map_is_interpolated_bilinearly(small_calib):
    # heights[r, c] at s = 100 + 50 r, x = -200 + 100 c; bilinear in between,
    # clamped to the edge values outside.
    heights = np.array([[0.0, 1.0, 2.0], [10.0, 11.0, 12.0]])
    with flatline.SimulatedLine(small_calib) as sim:
        sim.set_height_map(heights, 100.0, 50.0, -200.0, 100.0)
        z = sim.surface([-200.0, 0.0, -150.0, -150.0, 500.0, -900.0],
                        [100.0, 150.0, 125.0, 100.0, 1e4, -1e4])
        np.testing.assert_allclose(z, [0.0, 12.0, 5.5, 0.5, 12.0, 0.0], rtol=0, atol=1e-12)
        with pytest.raises(flatline.InvalidArgumentError, match=r"'heights\[4\]' = nan"):
            sim.set_height_map(np.where(np.arange(6).reshape(2, 3) == 4, np.nan, heights),
                               100.0, 50.0, -200.0, 100.0)
        with pytest.raises(flatline.InvalidArgumentError, match="'rows' = 1, 'cols' = 3"):
            sim.set_height_map(heights[:1], 100.0, 50.0, -200.0, 100.0)
        with pytest.raises(flatline.InvalidArgumentError, match="'ds_mm' = 0"):
            sim.set_height_map(heights, 100.0, 0.0, -200.0, 100.0)
        with pytest.raises(ValueError, match="'heights' must have 2 dimensions"):
            sim.set_height_map(heights.ravel(), 100.0, 50.0, -200.0, 100.0)
        # The failed calls left the map in place.
        assert sim.surface(0.0, 150.0) == pytest.approx(12.0, abs=1e-12)


def test_rows_are_the_two_laser_operators_of_the_ground_truth(small_calib):
    # Noise free: height = (z(s - 50) + z(s + 50)) / 2, slope = (z(s + 50) -
    # z(s - 50)) / 100 (laser 0 at offset -50 reads s + 50, ahead), truth =
    # z(s), s = encoder - mean offset = encoder. Only rounding differs
    # (1e-12 mm on 20 mm of sheet).
    with flatline.SimulatedLine(small_calib, sim_start=1000.0) as sim:
        reference_sheet(sim)
        rows = sim.next_rows(200)
        assert isinstance(rows, flatline.SimRows)
        k = sim.fibers
        assert rows.encoder_mm.shape == rows.s.shape == (200,)
        assert rows.height.shape == rows.slope.shape == rows.truth.shape == (200, k)
        assert rows.valid.dtype == np.bool_ and rows.valid.all()
        np.testing.assert_array_equal(rows.encoder_mm, 1000.0 + 3.0 * np.arange(200))
        np.testing.assert_array_equal(rows.s, rows.encoder_mm)  # offsets -50, +50
        x = sim.fiber_x[None, :]
        ahead = sim.surface(x, rows.s[:, None] + 50.0)
        behind = sim.surface(x, rows.s[:, None] - 50.0)
        np.testing.assert_allclose(rows.height, (ahead + behind) / 2, rtol=0, atol=1e-12)
        np.testing.assert_allclose(rows.slope, (ahead - behind) / 100.0, rtol=0, atol=1e-14)
        np.testing.assert_array_equal(bits(rows.truth), bits(sim.surface(x, rows.s[:, None])))


def test_noise_free_rows_reconstruct_to_the_ground_truth_within_a_micrometre(small_calib):
    # The reference sheet, 9000 mm at 3 mm: the Hermite spline with 100 mm
    # knots represents these sines to ~0.3 um (see test_recon), so the
    # reconstruction from the simulator's rows must meet its truth to 1e-3 mm.
    with flatline.SimulatedLine(small_calib) as sim:
        reference_sheet(sim)
        rows = sim.next_rows(3000)
    z = flatline.reconstruct(rows.s, rows.height, rows.slope, rows.valid,
                             laser_spacing=small_calib.laser_spacing)
    error = np.abs(z - rows.truth).max()
    print(f"noise-free simulator -> reconstruct: max error {error * 1e3:.3f} um")
    assert error <= 1e-3
    assert np.abs(rows.truth).max() > 10  # a real sheet, not a flat one


def test_same_seed_same_bits_other_seed_other_bits_and_rewind(small_calib):
    def run(seed, blocks):
        with flatline.SimulatedLine(small_calib, sim_seed=seed, **NOISY) as sim:
            reference_sheet(sim)
            parts = [sim.next_rows(n) for n in blocks]
        return [np.concatenate(p) for p in zip(*parts)]

    first = run(5, [400])
    again = run(5, [1, 150, 249])  # block sizes do not matter either
    other = run(6, [400])
    for a, b in zip(first, again):
        np.testing.assert_array_equal(bits(a) if a.dtype != np.bool_ else a,
                                      bits(b) if b.dtype != np.bool_ else b)
    # Noise is really on: heave of 2.5 mm moves heights, not the truth.
    assert np.abs(first[2] - other[2]).max() > 1.0
    np.testing.assert_array_equal(bits(first[5]), bits(other[5]))
    with flatline.SimulatedLine(small_calib, sim_seed=5, **NOISY) as sim:
        reference_sheet(sim)
        sim.next_rows(123)
        sim.rewind()
        np.testing.assert_array_equal(bits(sim.next_rows(400).height), bits(first[2]))


def test_frames_render_both_lines_at_the_reported_rows(small_calib):
    # Line sigma 2 px, peak 0.6 of full scale on a 0.03 background: in every
    # column where a line is in the frame, the brightest pixel near it lies
    # within 1 px of the exact centre the simulator reports.
    with flatline.SimulatedLine(small_calib, sim_seed=2) as sim:
        reference_sheet(sim)
        frame = sim.next_frame()
        assert isinstance(frame, flatline.SimFrame)
        image = frame.image
        assert image.shape == (256, 2048) and image.dtype == np.uint8
        assert image.flags.c_contiguous
        assert frame.encoder_mm == 0.0 and frame.s == 0.0
        assert frame.truth.shape == (sim.fibers,)
        np.testing.assert_array_equal(bits(frame.truth), bits(sim.surface(sim.fiber_x, 0.0)))
        assert frame.peak_rows.shape == (2, 2048)
        columns = np.arange(2048)
        for laser in (0, 1):
            centre = frame.peak_rows[laser]
            seen = np.isfinite(centre)
            assert seen.mean() > 0.99
            lo = np.clip(np.round(centre[seen]).astype(int) - 4, 0, 255)
            window = np.stack([image[np.clip(lo + d, 0, 255), columns[seen]] for d in range(9)])
            brightest = lo + window.argmax(axis=0)
            assert np.median(np.abs(brightest - centre[seen])) <= 0.5
            assert np.percentile(np.abs(brightest - centre[seen]), 99) <= 1.5
        # Laser 1 (offset +50) sits higher in the image than laser 0.
        assert np.nanmean(frame.peak_rows[1]) < np.nanmean(frame.peak_rows[0])
        background = np.median(image)
        assert abs(background - 0.03 * 255) <= 3
        # The next frame is one frame spacing later.
        assert sim.next_frame().encoder_mm == 3.0


def test_frames_and_rows_share_the_frame_counter(small_calib):
    with flatline.SimulatedLine(small_calib, sim_frame_spacing=4.0, sim_start=10.0) as sim:
        assert sim.next_rows(2).encoder_mm.tolist() == [10.0, 14.0]
        assert sim.next_frame().encoder_mm == 18.0
        assert sim.next_rows(1).encoder_mm.tolist() == [22.0]


def test_frames_are_deterministic_and_can_render_into_a_given_buffer(small_calib):
    with flatline.SimulatedLine(small_calib, sim_seed=9, sim_reflections=2) as a, \
            flatline.SimulatedLine(small_calib, sim_seed=9, sim_reflections=2) as b:
        for sim in (a, b):
            reference_sheet(sim)
        first = a.next_frame()
        buffer = np.zeros((256, 2048), np.uint8)
        second = b.next_frame(out=buffer)
        assert second.image is buffer  # rendered in place, no allocation
        np.testing.assert_array_equal(first.image, buffer)
        np.testing.assert_array_equal(bits(first.peak_rows), bits(second.peak_rows))
        a.rewind()
        np.testing.assert_array_equal(a.next_frame().image, first.image)
        with pytest.raises(TypeError, match="'out' has dtype uint16"):
            a.next_frame(out=np.zeros((256, 2048), np.uint16))
        with pytest.raises(ValueError, match=r"'out' has shape \(2048, 256\)"):
            a.next_frame(out=np.zeros((2048, 256), np.uint8))
        with pytest.raises(ValueError, match="C-contiguous"):
            a.next_frame(out=np.zeros((2048, 256), np.uint8).T)
        with pytest.raises(TypeError, match="numpy array"):
            a.next_frame(out=bytearray(256 * 2048))
        # The raw layer checks the buffer too.
        with pytest.raises(flatline.InvalidArgumentError, match="8-bit pixels, which need a uint8 frame_out"):
            a._live().next_frame_u16(np.zeros((256, 2048), np.uint16), np.zeros(101),
                                     np.zeros((2, 2048)))


def test_sixteen_bit_frames(small_calib):
    # 12 bits: uint16 pixels up to 4095, the same line brightness in units of
    # full scale (peak 0.6 -> ~2457 minus speckle and noise).
    with flatline.SimulatedLine(small_calib, sim_bit_depth=12, sim_seed=4) as sim:
        assert sim.pixel_format is flatline.PixelFormat.MONO12
        frame = sim.next_frame()
        assert frame.image.dtype == np.uint16 and frame.image.max() <= 4095
        assert 0.45 * 4095 < np.percentile(frame.image.max(axis=0), 50) < 0.75 * 4095


def test_errors_are_mapped_and_leave_the_simulator_usable(small_calib):
    with flatline.SimulatedLine(small_calib) as sim:
        with pytest.raises(ValueError, match="'kind' = 'buckle' is not one of"):
            sim.add_defect("buckle", 1.0, 100.0)
        with pytest.raises(flatline.InvalidArgumentError, match="'kind' = 99 is unknown") as info:
            sim.add_defect(99, 1.0, 100.0)
        assert info.value.status == -1
        with pytest.raises(flatline.InvalidArgumentError, match="'amplitude_mm' = nan"):
            sim.add_defect("bow", float("nan"))
        with pytest.raises(flatline.InvalidArgumentError, match="'period_mm' = -1"):
            sim.add_defect("bow", 1.0, -1.0)
        for _ in range(64):
            sim.add_defect("bow", 0.01)
        with pytest.raises(flatline.BufferFullError, match="already has 64 defects") as info:
            sim.add_defect("bow", 0.01)
        assert info.value.status == -4
        assert sim.surface(0.0, 0.0) == pytest.approx(0.64, abs=1e-12)
        with pytest.raises(flatline.InvalidArgumentError, match="'rows' is 0"):
            sim.next_rows(0)
        with pytest.raises(ValueError, match="'n' must be >= 0"):
            sim.next_rows(-1)
        with pytest.raises(TypeError, match="'n' must be an int"):
            sim.next_rows(2.0)
        assert sim.next_rows(1).encoder_mm[0] == 0.0  # nothing was consumed
    with pytest.raises(flatline.StateError, match="closed"):
        sim.next_rows(1)


def test_options_and_calibration_are_checked():
    with pytest.raises(flatline.InvalidArgumentError, match="'sim_bit_depth' = 9"):
        flatline.SimulatedLine(sim_bit_depth=9)
    with pytest.raises(flatline.InvalidArgumentError, match="sim_frame_spacing"):
        flatline.SimulatedLine(sim_frame_spacing=-3.0)
    with pytest.raises(TypeError, match="'knot_spacing' \\(an option of another component"):
        flatline.SimulatedLine(knot_spacing=50.0)
    with pytest.raises(TypeError, match="'sim_sed'"):
        flatline.SimulatedLine(sim_sed=1)
    with pytest.raises(TypeError, match="must be a Calibration"):
        flatline.SimulatedLine("reference")
    unfinished = flatline.Calibration()
    with pytest.raises(flatline.StateError, match="'calib' is not finished"):
        flatline.SimulatedLine(unfinished)
    closed = flatline.Calibration.reference()
    closed.close()
    with pytest.raises(flatline.StateError, match="closed"):
        flatline.SimulatedLine(closed)


def test_the_simulator_keeps_its_calibration_alive():
    calib = roi_reference()
    ref = weakref.ref(calib)
    sim = flatline.SimulatedLine(calib)
    del calib
    gc.collect()
    assert ref() is not None and sim.calibration is ref()
    assert sim.next_rows(3).s.tolist() == [0.0, 3.0, 6.0]
    del sim
    gc.collect()
    assert ref() is None
