# SPDX-License-Identifier: Apache-2.0
"""The reconstructor's behaviour through Python: accuracy, flags, streaming,
carry-over, lifetime."""

import numpy as np
import pytest

import flatline

from conftest import bits, measure, noisy_sheet, roi_reference, sine_sheet


def test_noise_free_sine_is_reconstructed_within_a_micrometre():
    # The reference sheet along travel: z = 12 sin(2 pi s / 1800), 9000 mm
    # at 3 mm, two lasers 100 mm apart. A cubic Hermite spline with 100 mm
    # knots represents this sine to ~(pi L / P)^4 / 384 * A ~ 0.3 um, so
    # 1e-3 mm is the accuracy goal (1 um) with margin.
    s, h, sl, z_true = sine_sheet(fibers=4)
    z = flatline.reconstruct(s, h, sl)
    assert z.shape == h.shape and z.dtype == np.float64
    assert np.abs(z - z_true).max() <= 1e-3


def test_options_change_the_result_as_the_c_defaults_say():
    s, h, sl, z_true = sine_sheet(fibers=1)
    default = flatline.reconstruct(s, h, sl)
    explicit = flatline.reconstruct(s, h, sl, laser_spacing=100.0, knot_spacing=0.0,
                                    height_sigma=2.5, slope_sigma=1e-3)
    np.testing.assert_array_equal(bits(default), bits(explicit))
    # Telling it the wrong laser spacing (200 mm) models the wrong operator:
    # the error grows to a visible fraction of the 12 mm amplitude.
    wrong = flatline.reconstruct(s, h, sl, laser_spacing=200.0)
    assert np.abs(wrong - z_true).max() > 0.1


def test_invalid_and_nan_samples_are_flagged_and_bridged():
    s, h, sl, z_true = sine_sheet(fibers=3)
    valid = np.ones(h.shape, bool)
    valid[1000:1010, 0] = False  # 30 mm hole: bridged, flagged invalid only
    h = h.copy(); sl = sl.copy()
    h[2000:2005, 1] = np.nan; sl[2000:2005, 1] = np.nan  # NaN counts as invalid
    valid[:, 2] = False  # a fiber with no data at all
    z, flags = flatline.reconstruct_with_flags(s, h, sl, valid)
    assert (flags[1000:1010, 0] == flatline.FLAG_INVALID_INPUT).all()
    assert (flags[2000:2005, 1] == flatline.FLAG_INVALID_INPUT).all()
    assert flags[:, :2].sum() == 15 * flatline.FLAG_INVALID_INPUT
    # The bridged values still follow the sheet (slopes around the hole pin it).
    assert np.abs(z[1000:1010, 0] - z_true[1000:1010, 0]).max() < 1e-2
    assert np.isnan(z[:, 2]).all() and (flags[:, 2] & flatline.FLAG_NO_DATA).all()
    assert not np.isnan(z[:, :2]).any()


def test_gap_longer_than_max_gap_is_flagged():
    s, h, sl, _ = sine_sheet(fibers=1)
    valid = np.ones(h.shape, bool)
    valid[1000:1100] = False  # 300 mm > max_gap 200 mm
    _, flags = flatline.reconstruct_with_flags(s, h, sl, valid)
    assert (flags[1000:1100, 0] & flatline.FLAG_GAP).all()
    _, flags = flatline.reconstruct_with_flags(s, h, sl, valid, max_gap=400.0)
    assert not (flags[:, 0] & flatline.FLAG_GAP).any()


def test_row_by_row_and_block_pushes_give_identical_bits():
    s, h, sl, valid = noisy_sheet(seed=1, rows=800, fibers=3)
    outputs = []
    for by_row in (False, True):
        with flatline.Reconstructor(3, lag_knots=8) as recon:
            if by_row:
                for r in range(len(s)):
                    recon.push(s[r], h[r], sl[r], valid[r])
            else:
                recon.push(s, h, sl, valid)
            recon.end_sheet()
            outputs.append(recon.pull())
    for a, b in zip(*outputs):
        np.testing.assert_array_equal(a, b) if a.dtype == np.uint8 else \
            np.testing.assert_array_equal(bits(a), bits(b))


def test_streaming_converges_to_the_batch_solution_with_enough_lag():
    s, h, sl, z_true = sine_sheet(fibers=2)
    batch = flatline.reconstruct(s, h, sl)
    with flatline.Reconstructor(2) as recon:  # default latency: a lag of 15 knots
        pulled = []
        for start in range(0, len(s), 500):
            recon.push(s[start:start + 500], h[start:start + 500], sl[start:start + 500])
            pulled.append(recon.pull())
        assert sum(len(p[0]) for p in pulled) > 0  # rows come out before the end
        recon.end_sheet()
        pulled.append(recon.pull())
        assert recon.ready == 0
    out_s = np.concatenate([p[0] for p in pulled])
    z = np.concatenate([p[1] for p in pulled])
    np.testing.assert_array_equal(out_s, s)  # every row, once, in order
    # Noise-free data: both are the spline through the same sine; they agree
    # to well under the 1 um accuracy of either.
    assert np.abs(z - batch).max() < 1e-4
    assert np.abs(z - z_true).max() <= 1e-3


def test_pull_max_rows_and_ready():
    s, h, sl, _ = sine_sheet(fibers=2, length=3000)
    with flatline.Reconstructor(2, lag_knots=2) as recon:
        recon.push(s, h, sl)
        ready = recon.ready
        assert ready > 100
        first = recon.pull(max_rows=10)
        assert first[0].shape == (10,) and first[1].shape == (10, 2) and first[2].shape == (10, 2)
        assert first[2].dtype == np.uint8
        assert recon.ready == ready - 10
        rest = recon.pull()
        assert len(rest[0]) == ready - 10 and recon.ready == 0
        empty = recon.pull()
        assert empty[0].shape == (0,) and empty[1].shape == (0, 2)
        with pytest.raises(ValueError, match="max_rows"):
            recon.pull(max_rows=-1)


def test_end_sheet_carries_the_boundary_and_the_next_sheet_joins_c1():
    s, h, sl, z_true = sine_sheet(fibers=2, length=9000)
    half = len(s) // 2
    with flatline.Reconstructor(2, lag_knots=8) as recon:
        recon.push(s[:half], h[:half], sl[:half])
        recon.end_sheet()
        first = recon.pull()
        knot_s, knot_h, knot_sl = recon.boundary()
        assert knot_h.shape == (2,) and knot_sl.shape == (2,)
        # The last knot of the sheet: the last row reaches s + 50 mm, so
        # that knot lies within one knot spacing past it.
        assert s[half - 1] < knot_s <= s[half - 1] + 50.0 + 100.0
        # Height and slope there are the sine's, to the spline's accuracy.
        # The end knot has data on one side only: its slope is allowed 5e-5
        # mm/mm (0.1 % of the 0.042 mm/mm peak slope; over a 100 mm knot
        # interval it is 5 um of height).
        z = lambda pos: 12 * np.sin(2 * np.pi * (pos + 5.0 * np.arange(2)) / 1800)
        dz = lambda pos: 12 * 2 * np.pi / 1800 * np.cos(2 * np.pi * (pos + 5.0 * np.arange(2)) / 1800)
        assert np.abs(knot_h - z(knot_s)).max() < 1e-3
        assert np.abs(knot_sl - dz(knot_s)).max() < 5e-5
        recon.push(s[half:], h[half:], sl[half:])
        recon.end_sheet()
        second = recon.pull()
    z_all = np.concatenate([first[1], second[1]])
    assert len(z_all) == len(s)
    assert np.abs(z_all - z_true).max() <= 1e-3


def test_reset_drops_rows_and_carry_over():
    s, h, sl, _ = sine_sheet(fibers=1, length=3000)
    with flatline.Reconstructor(1, lag_knots=2) as recon:
        recon.push(s, h, sl)
        recon.end_sheet()
        assert recon.ready == len(s)
        recon.reset()
        assert recon.ready == 0
        with pytest.raises(flatline.StateError):
            recon.boundary()
        with pytest.raises(flatline.StateError):
            recon.pull()
        recon.push(s, h, sl)  # a new strip may start at any position again


def test_fibers_option_and_repr():
    with flatline.Reconstructor(5, laser_spacing=80.0, lag_knots=3) as recon:
        assert recon.fibers == 5
        assert recon.option("knot_spacing") == 80.0  # resolved from 0
        assert recon.option("laser_spacing") == 80.0
        assert recon.option("lag_knots") == 3.0
        assert recon.option("row_capacity") == 8192.0
        assert repr(recon) == "<flatline.Reconstructor fibers=5 ready=0>"
    assert repr(recon) == "<flatline.Reconstructor closed>"


def test_constructor_argument_checks():
    with pytest.raises(ValueError, match="'fibers' must be >= 1"):
        flatline.Reconstructor(0)
    with pytest.raises(TypeError, match="'fibers' must be an int"):
        flatline.Reconstructor(2.5)
    assert flatline.Reconstructor(np.int64(2)).fibers == 2


def test_close_is_deterministic_and_idempotent():
    recon = flatline.Reconstructor(2)
    handle = recon._handle
    assert handle.thisown  # the SWIG object owns the C handle
    del handle
    recon.close()
    assert recon.closed
    recon.close()
    for call in (lambda: recon.ready, recon.pull, recon.end_sheet, recon.reset,
                 recon.boundary, lambda: recon.option("lag_knots"),
                 lambda: recon.push(0.0, [0.0, 0.0], [0.0, 0.0])):
        with pytest.raises(flatline.StateError, match="closed"):
            call()
    with pytest.raises(flatline.StateError):
        with recon:
            pass


def sensor_80mm():
    """The reference camera with its lasers 80 mm apart (offsets -40, +40
    mm), 41 fibers 50 mm apart. Profile rows of the simulator use only the
    offsets (the homographies scale peak noise, off here), so the reference
    homographies serve."""
    reference = roi_reference(fibers=41, pitch=50.0)
    calib = flatline.Calibration()
    calib.frame_size = reference.frame_size
    calib.intrinsics = reference.intrinsics
    for laser in (0, 1):
        calib.set_homography(laser, reference.homography(laser))
    calib.laser_offsets = (-40.0, 40.0)
    calib.encoder_scale = reference.encoder_scale
    calib.fiber_grid = reference.fiber_grid
    calib.finish()
    return calib


def test_reconstructor_from_a_calibration_takes_its_spacing_and_fibers():
    calib = sensor_80mm()
    assert calib.laser_spacing == 80.0
    with flatline.Reconstructor(calib, lag_knots=8) as recon:
        assert recon.fibers == 41
        assert recon.option("laser_spacing") == 80.0
        assert recon.option("knot_spacing") == 80.0  # follows the sensor
        assert recon.option("lag_knots") == 8.0
    # An option that agrees is fine; one that disagrees names both numbers.
    assert flatline.Reconstructor(calib, laser_spacing=80.0).option("laser_spacing") == 80.0
    with pytest.raises(flatline.InvalidArgumentError,
                       match="'laser_spacing' = 100 mm disagrees with the 80 mm"):
        flatline.Reconstructor(calib, laser_spacing=100.0)
    unfinished = flatline.Calibration()
    with pytest.raises(flatline.StateError, match="not finished"):
        flatline.Reconstructor(unfinished)
    with pytest.raises(TypeError, match="an int or a Calibration"):
        flatline.Reconstructor("sensor.json")


def test_an_80mm_sensor_is_reconstructed_right_only_with_its_spacing():
    """Simulated rows of the 80 mm sensor (a 5 mm wave at 400 mm on the
    edges, an 8 mm buckle at 1600 mm in the centre, no noise): the
    reconstructor made from the calibration matches the ground truth within
    what a cubic spline with knots h = 80 mm apart can follow of a 400 mm
    wave, h^4 / 384 * max|z^(4)| = 80^4 / 384 * 5 (2 pi / 400)^4 = 0.032 mm
    (measured: 0.016); one left at the 100 mm default misreads the 400 mm
    waves' slopes by sinc(pi 80/400) / sinc(pi 100/400) - 1 = 4 %, about
    0.2 mm (measured: 0.20)."""
    calib = sensor_80mm()
    with flatline.SimulatedLine(calib, sim_seed=3) as sim:
        sim.add_defect("centre_buckle", 8.0, 1600.0)
        sim.add_defect("wavy_edge_both", 5.0, 400.0)
        rows = sim.next_rows(1200)
    errors = {}
    for name, make in (("calibration", lambda: flatline.Reconstructor(calib)),
                       ("default", lambda: flatline.Reconstructor(calib.fiber_grid.count))):
        with make() as recon:
            recon.push(rows.s, rows.height, rows.slope, rows.valid)
            recon.end_sheet()
            s, z, flags = recon.pull()
        np.testing.assert_array_equal(s, rows.s)
        assert not flags.any()
        errors[name] = np.max(np.abs(z - rows.truth))
    assert errors["calibration"] <= 0.032, errors
    assert errors["default"] >= 0.1, errors


def test_peek_gives_the_pending_rows_provisionally_and_changes_nothing():
    s, h, sl, z_true = sine_sheet(fibers=3)
    with flatline.Reconstructor(3) as a, flatline.Reconstructor(3) as b:
        a.push(s[:1000], h[:1000], sl[:1000])
        b.push(s[:1000], h[:1000], sl[:1000])
        pulled_a, pulled_b = [a.pull()], [b.pull()]
        assert a.pending == 1000 - len(pulled_a[0][0])
        ps, pz, pf = a.peek()
        assert ps.shape == (a.pending,) and pz.shape == (a.pending, 3)
        assert pf.dtype == np.uint8 and not pf.any()
        np.testing.assert_array_equal(ps, s[len(pulled_a[0][0]):1000])
        # Noise-free: the provisional rows are already the spline (the
        # spline's own accuracy is 0.25 um; bound 1 um, as for final rows).
        assert np.abs(pz - z_true[len(pulled_a[0][0]):1000]).max() <= 1e-3
        assert len(a.peek(max_rows=2)[0]) == 2
        a.push(s[1000:], h[1000:], sl[1000:])
        b.push(s[1000:], h[1000:], sl[1000:])
        for recon, pulled in ((a, pulled_a), (b, pulled_b)):
            recon.end_sheet()
            pulled.append(recon.pull())
            assert recon.pending == 0 and len(recon.peek()[0]) == 0
        # Peeking changed nothing that pull gives, bit for bit.
        za = np.concatenate([p[1] for p in pulled_a])
        zb = np.concatenate([p[1] for p in pulled_b])
        np.testing.assert_array_equal(za, zb)
    with pytest.raises(flatline.StateError):
        flatline.Reconstructor(2).peek()
    with pytest.raises(ValueError, match="max_rows"):
        flatline.Reconstructor(2).peek(-1)


def test_latency_mm_sets_the_lag_and_conflicts_with_lag_knots():
    with flatline.Reconstructor(2, latency_mm=1000) as recon:
        # The longest lag L with L + L/8 + 2 knots of 100 mm and 50 mm within
        # 1000 mm: 7 knots, rows final within 950 mm.
        assert recon.option("lag_knots") == 7.0
        assert recon.option("latency_mm") == 950.0
    with pytest.raises(flatline.InvalidArgumentError, match="one setting"):
        flatline.Reconstructor(2, latency_mm=1000, lag_knots=8)
    with pytest.raises(flatline.InvalidArgumentError, match="shorter than the least"):
        flatline.Reconstructor(2, latency_mm=200)
