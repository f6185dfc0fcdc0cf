# SPDX-License-Identifier: Apache-2.0
"""Flatness: I-Units of analytic sines, results equal to the C API's bit for
bit, streaming windows, flags, errors and lifetime."""

import ctypes

import numpy as np
import pytest

import flatline

from conftest import bits, noisy_sheet, roi_reference

X9 = np.linspace(-800.0, 800.0, 9)  # mm, 200 mm pitch


def sine_fibers(amplitudes, periods, length=6000.0, step=3.0):
    """z = H/2 sin(2 pi s / P) per fiber (H peak-to-peak), rows every `step`
    mm over whole periods."""
    s = np.arange(0.0, length, step)
    h = np.asarray(amplitudes, float)
    p = np.asarray(periods, float)
    return s, 0.5 * h * np.sin(2 * np.pi * s[:, None] / p)


def test_sine_i_units_waves_and_steepness_match_the_analytic_values():
    # Fiber 0 is flat: the reference (shortest) fiber, so every other fiber's
    # I-Units are its own sine's 2.467 (H/P)^2 1e5 (pi^2/4 = 2.4674). The
    # small-H/P formula drops the next term (-3/16 (pi H/P)^2 relative,
    # <= 1.9e-4 here) and the chords over 3 mm rows add their own; measured
    # -0.05 to -0.07%: 1% is the accuracy goal with a wide margin.
    amplitudes = [0.0, 5.0, 10.0, 15.0, 8.0, 12.0]
    periods = [1000.0, 1000.0, 1000.0, 1500.0, 2000.0, 1200.0]
    s, z = sine_fibers(amplitudes, periods)
    x = np.linspace(-500.0, 500.0, 6)
    result = flatline.i_units(z, s, x)
    h, p = np.array(amplitudes[1:]), np.array(periods[1:])
    expected = np.pi ** 2 / 4 * (h / p) ** 2 * 1e5
    got = result.fibers.i_units[1:]
    assert np.all(np.abs(got / expected - 1) < 0.01), got / expected
    assert result.fibers.i_units[0] == 0.0
    # The largest wave: height and period within 1% (extrema refined by a
    # parabola through rows 3 mm apart: error ~ (2 pi 3 / P)^2 / 8 << 1%).
    assert np.all(np.abs(result.fibers.wave_height[1:] / h - 1) < 0.01)
    assert np.all(np.abs(result.fibers.wave_period[1:] / p - 1) < 0.01)
    np.testing.assert_allclose(result.fibers.steepness_percent[1:],
                               100 * result.fibers.wave_height[1:] / result.fibers.wave_period[1:],
                               rtol=1e-12)
    # The flat fiber has no wave: NaN and flagged, never NaN unflagged.
    assert np.isnan(result.fibers.wave_height[0])
    assert result.fibers.flags[0] == flatline.FIBER_NO_WAVE
    assert np.all(result.fibers.flags[1:] == 0)
    # Arc length of the flat fiber is the window's travel, s[-1] - s[0].
    assert result.fibers.arc_length[0] == pytest.approx(s[-1] - s[0], abs=1e-9)
    assert result.window == flatline.WindowInfo(0.0, s[-1], len(s), 0, 1)


def test_centre_buckle_is_classified_with_its_name_and_components():
    # Only the centre fiber of nine is long (24.67 I-Units >> flat_flat_limit):
    # all the long material is in |u| < 0.3, so CENTRE_BUCKLE with
    # confidence a * e = 1 * 1.
    s, z = sine_fibers([0.0] * 4 + [10.0] + [0.0] * 4, [1000.0] * 9)
    result = flatline.i_units(z, s, X9)
    assert result.shape.shape is flatline.Shape.CENTRE_BUCKLE
    assert result.shape.name == "centre buckle" == str(flatline.Shape.CENTRE_BUCKLE)
    assert result.shape.confidence == 1.0
    assert result.shape.components == flatline.ShapeComponent.CENTRE
    # No coil set, no crossbow: the flat fibers are exactly flat.
    assert abs(result.shape.bow_mm) < 1e-12 and abs(result.shape.crossbow_mm) < 1e-9
    # Zones: the fiber counts cover every fiber once; zone I-Units are the
    # mean of their fibers, NaN (and flagged) where a zone holds none.
    zones = result.zones
    assert zones.fiber_count.sum() == 9
    assert np.array_equal(np.isnan(zones.i_units), zones.fiber_count == 0)
    assert np.array_equal(zones.flags == flatline.ZONE_NO_DATA, zones.fiber_count == 0)
    centre_zone = np.flatnonzero((zones.left_x <= 0) & (0 < zones.left_x + np.diff(zones.left_x)[0]))
    assert zones.i_units[centre_zone[0]] == result.fibers.i_units[4]
    np.testing.assert_allclose(zones.centre_x - zones.left_x, np.diff(zones.left_x)[0] / 2)


def test_every_shape_has_the_library_name():
    for shape in flatline.Shape:
        assert shape.label == flatline.capi.flt_shape_string(int(shape))
    assert flatline.Shape.WAVY_EDGE_BOTH.label == "wavy edges"
    assert flatline.capi.flt_shape_string(99) == "unknown"


# -- bit for bit against the C API ------------------------------------------------


def c_flatness(clib, x, s, z, flags, **options):
    """flt_flatness_create / evaluate / the result getters through ctypes."""
    lib, dp, up = clib.lib, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_uint8)
    P, sz = ctypes.c_void_p, ctypes.c_size_t
    lib.flt_flatness_create.argtypes = [sz, dp, P, ctypes.POINTER(P)]
    lib.flt_flatness_destroy.argtypes = [P]
    lib.flt_flatness_zones.argtypes = [P, ctypes.POINTER(sz)]
    lib.flt_flatness_evaluate.argtypes = [P, sz, sz, dp, dp, up]
    lib.flt_flatness_fiber_results.argtypes = [P, sz, dp, dp, dp, dp, dp, up]
    lib.flt_flatness_zone_results.argtypes = [P, sz, dp, up]
    lib.flt_flatness_shape.argtypes = [P, ctypes.POINTER(ctypes.c_int), dp,
                                       ctypes.POINTER(ctypes.c_uint), dp, dp]
    x, s, z = (np.ascontiguousarray(a, np.float64) for a in (x, s, z))
    flags = None if flags is None else np.ascontiguousarray(flags, np.uint8)
    bag = clib.options(**options) if options else None
    handle = P()
    clib._check(lib.flt_flatness_create(len(x), clib._ptr(x, ctypes.c_double), bag,
                                        ctypes.byref(handle)))
    if bag is not None:
        lib.flt_options_destroy(bag)
    try:
        k = len(x)
        clib._check(lib.flt_flatness_evaluate(handle, len(s), k, clib._ptr(s, ctypes.c_double),
                                               clib._ptr(z, ctypes.c_double),
                                               clib._ptr(flags, ctypes.c_uint8)))
        fiber = [np.empty(k) for _ in range(5)] + [np.empty(k, np.uint8)]
        clib._check(lib.flt_flatness_fiber_results(
            handle, k, *[clib._ptr(a, ctypes.c_double) for a in fiber[:5]],
            clib._ptr(fiber[5], ctypes.c_uint8)))
        zones = sz()
        clib._check(lib.flt_flatness_zones(handle, ctypes.byref(zones)))
        zone = [np.empty(zones.value), np.empty(zones.value, np.uint8)]
        clib._check(lib.flt_flatness_zone_results(handle, zones.value,
                                                  clib._ptr(zone[0], ctypes.c_double),
                                                  clib._ptr(zone[1], ctypes.c_uint8)))
        shape, comp = ctypes.c_int(), ctypes.c_uint()
        conf, bow, cross = ctypes.c_double(), ctypes.c_double(), ctypes.c_double()
        clib._check(lib.flt_flatness_shape(handle, ctypes.byref(shape), ctypes.byref(conf),
                                           ctypes.byref(comp), ctypes.byref(bow),
                                           ctypes.byref(cross)))
    finally:
        lib.flt_flatness_destroy(handle)
    return fiber, zone, (shape.value, conf.value, comp.value, bow.value, cross.value)


def test_results_equal_the_c_api_bit_for_bit(clib):
    # Reconstructed noisy rows with invalid samples and their flags: every
    # output of every fiber and zone, and the shape, as the C API gives them.
    s, height, slope, valid = noisy_sheet(17, rows=1500, fibers=12)
    valid[200:400, 3] = False  # 600 mm > max_gap: FLAG_GAP rows, a partial fiber
    valid[:, 5] = False  # never measured: FLAG_NO_DATA, a NaN fiber
    z, flags = flatline.reconstruct_with_flags(s, height, slope, valid, max_gap=300.0)
    x = np.linspace(-900.0, 900.0, 12)
    options = dict(flat_zone_width=150.0, flat_wave_hysteresis=0.5)
    result = flatline.Flatness(x, **options).evaluate(s, z, flags)
    fiber, zone, shape = c_flatness(clib, x, s, z, flags, **options)
    ours = result.fibers
    for mine, theirs in zip((ours.arc_length, ours.i_units, ours.wave_height,
                             ours.wave_period, ours.steepness_percent), fiber[:5]):
        assert np.array_equal(bits(mine), bits(theirs))
    assert np.array_equal(ours.flags, fiber[5])
    assert ours.flags[3] & flatline.FIBER_PARTIAL  # the gap was seen
    assert ours.flags[5] & flatline.FIBER_NO_DATA and np.isnan(ours.i_units[5])
    assert np.array_equal(bits(result.zones.i_units), bits(zone[0]))
    assert np.array_equal(result.zones.flags, zone[1])
    assert (int(result.shape.shape), result.shape.confidence, int(result.shape.components)) \
        == shape[:3]
    assert bits(np.array([result.shape.bow_mm, result.shape.crossbow_mm])).tolist() == \
        bits(np.array(shape[3:])).tolist()


# -- streaming ------------------------------------------------------------------------


def test_streaming_windows_follow_the_grid_and_equal_evaluate_on_their_rows():
    # Rows every 3 mm from 0 to 5997; windows of 3000 mm every 1000 mm end
    # at 3000, 4000, 5000 mm: three complete windows; finish() evaluates the
    # rows of the last window's start (3000 mm) onwards.
    s, z = sine_fibers([0.0, 4.0, 8.0], [1000.0, 900.0, 1100.0])
    x = np.array([-100.0, 0.0, 100.0])
    with flatline.Flatness(x, flat_window_length=3000.0, flat_update_interval=1000.0) as flat:
        windows = list(flat.windows(s, z))
        assert [(w.window.s_first, w.window.s_last, w.window.rows, w.window.index)
                for w in windows] == [(0.0, 2997.0, 1000, 1), (1002.0, 3999.0, 1000, 2),
                                      (2001.0, 4998.0, 1000, 3)]
        last = flat.finish()
        assert (last.window.s_first, last.window.s_last, last.window.index) == (3000.0, 5997.0, 4)
        assert flat.finish() is None  # nothing pending any more
        # Each streamed window is exactly evaluate() on its rows.
        second = windows[1]
        rows = (s >= 1000.0) & (s < 4000.0)
        with flatline.Flatness(x) as whole:
            direct = whole.evaluate(s[rows], z[rows])
        assert np.array_equal(bits(direct.fibers.i_units), bits(second.fibers.i_units))
        # push stops at the first completed window: rows 0..999 are taken,
        # the row at s = 3000 completes it.
        flat.reset()
        consumed, evaluated = flat.push(s, z)
        assert (consumed, evaluated) == (1000, True)
        assert flat.result().window.index == 5
        consumed, evaluated = flat.push(s[1000:1100], z[1000:1100])
        assert (consumed, evaluated) == (100, False)


def test_flags_mark_fibers_without_data_nan_and_flagged():
    s, z = sine_fibers([0.0, 6.0, 6.0], [1000.0] * 3)
    flags = np.zeros(z.shape, np.uint8)
    flags[:, 2] = flatline.FLAG_NO_DATA
    z[:, 2] = np.nan
    result = flatline.i_units(z, s, [0.0, 50.0, 100.0], flags=flags)
    assert result.fibers.flags[2] & flatline.FIBER_NO_DATA
    assert np.isnan(result.fibers.i_units[2]) and np.isnan(result.fibers.arc_length[2])
    assert np.isfinite(result.fibers.i_units[:2]).all()
    # bool flags are refused (a validity mask is not FLAG_* bits).
    with pytest.raises(TypeError, match="flags"):
        flatline.i_units(z, s, flags=flags.astype(bool))


def test_calibration_grid_and_default_x():
    calib = roi_reference(fibers=21, pitch=50.0)
    with flatline.Flatness(calib) as flat:
        assert flat.fibers == 21
        assert np.array_equal(flat.fiber_x, calib.fiber_x)
        assert flat.zone_fiber_count.sum() == 21
        assert len(flat.zone_left_x) == flat.zones == len(flat.zone_centre_x)
        assert "fibers=21" in repr(flat)
    # Without fiber_x, i_units places fibers 1 mm apart: the per-fiber
    # I-Units do not depend on x.
    s, z = sine_fibers([0.0, 6.0], [1000.0, 1000.0])
    a = flatline.i_units(z, s).fibers.i_units
    b = flatline.i_units(z, s, [0.0, 300.0]).fibers.i_units
    assert np.array_equal(a, b)


def test_options_table_and_docstring():
    opts = flatline.flatness_options()
    assert set(opts) == {"flat_window_length", "flat_update_interval", "flat_zone_width",
                         "flat_reference", "flat_min_length", "flat_min_coverage",
                         "flat_wave_hysteresis", "flat_flat_limit", "flat_bow_limit",
                         "flat_crossbow_limit", "flat_row_capacity", "flat_zone_count",
                         "flat_drive_side", "flat_zones_on"}
    assert "{options}" not in flatline.Flatness.__doc__
    assert "flat_zone_width (float)" in flatline.Flatness.__doc__


def test_bad_input_raises_clear_errors_and_leaves_the_handle_usable():
    s, z = sine_fibers([0.0, 6.0, 3.0], [1000.0] * 3)
    x = [0.0, 10.0, 20.0]
    flat = flatline.Flatness(x)
    with pytest.raises(flatline.StateError):
        flat.result()  # no window yet
    with pytest.raises(flatline.InvalidArgumentError, match="rows"):
        flat.evaluate(s[:1], z[:1])
    with pytest.raises(flatline.InvalidArgumentError):
        flat.evaluate(s[::-1].copy(), z)  # s decreasing
    with pytest.raises(ValueError, match="3 fibers"):
        flat.evaluate(s, z[:, :2])
    with pytest.raises(ValueError, match="'s'"):
        flat.evaluate(s[:-1], z)
    with pytest.raises(ValueError, match="'flags'"):
        flat.evaluate(s, z, np.zeros((2, 3), np.uint8))
    with pytest.raises(TypeError, match="'z'"):
        flat.evaluate(s, z.astype(complex))
    good = flat.evaluate(s, z)  # still usable
    assert good.window.index == 1 and good.fibers.i_units[1] > 0
    with pytest.raises(flatline.InvalidArgumentError, match="fiber_x"):
        flatline.Flatness([0.0, 0.0, 1.0])
    with pytest.raises(flatline.InvalidArgumentError):
        flatline.Flatness(x, flat_window_length=1000.0, flat_update_interval=2000.0)
    with pytest.raises(TypeError, match="another component"):
        flatline.Flatness(x, knot_spacing=50.0)
    with pytest.raises(TypeError, match="unexpected keyword"):
        flatline.Flatness(x, flat_nonsense=1.0)
    # A window longer than flat_row_capacity rows: BufferFullError, with the
    # rows taken before counted.
    info = flatline.option_info("flat_row_capacity")
    cap = int(info.min_value)
    small = flatline.Flatness(x, flat_row_capacity=cap, flat_window_length=0.0)
    with pytest.raises(flatline.BufferFullError):
        small.push(s[:cap + 10], z[:cap + 10])
    flat.close()
    flat.close()
    with pytest.raises(flatline.StateError, match="closed"):
        flat.evaluate(s, z)
    assert repr(flat) == "<flatline.Flatness closed>"


def test_streaming_equals_the_c_push_loop_bit_for_bit(clib):
    # The same rows pushed through ctypes flt_flatness_push in the same
    # blocks: every window's I-Units and zone profile agree bit for bit.
    lib, P, sz = clib.lib, ctypes.c_void_p, ctypes.c_size_t
    dp, up = ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_uint8)
    lib.flt_flatness_push.argtypes = [P, sz, sz, dp, dp, up, ctypes.POINTER(sz),
                                      ctypes.POINTER(ctypes.c_int)]
    lib.flt_flatness_create.argtypes = [sz, dp, P, ctypes.POINTER(P)]
    lib.flt_flatness_destroy.argtypes = [P]
    lib.flt_flatness_fiber_results.argtypes = [P, sz, dp, dp, dp, dp, dp, up]
    s, height, slope, valid = noisy_sheet(23, rows=2500, fibers=8)
    z, flags = flatline.reconstruct_with_flags(s, height, slope, valid)
    x = np.linspace(-700.0, 700.0, 8)
    options = dict(flat_window_length=2000.0, flat_update_interval=500.0)
    ours = [w.fibers.i_units for w in flatline.Flatness(x, **options).windows(s, z, flags)]
    bag = clib.options(**options)
    handle = P()
    clib._check(lib.flt_flatness_create(8, clib._ptr(x, ctypes.c_double), bag,
                                        ctypes.byref(handle)))
    lib.flt_options_destroy(bag)
    theirs, start = [], 0
    try:
        while start < len(s):
            consumed, evaluated = sz(), ctypes.c_int()
            clib._check(lib.flt_flatness_push(
                handle, len(s) - start, 8, clib._ptr(s[start:], ctypes.c_double),
                clib._ptr(z[start:], ctypes.c_double), clib._ptr(flags[start:], ctypes.c_uint8),
                ctypes.byref(consumed), ctypes.byref(evaluated)))
            start += consumed.value
            if evaluated.value:
                iu = np.empty(8)
                clib._check(lib.flt_flatness_fiber_results(
                    handle, 8, None, clib._ptr(iu, ctypes.c_double), None, None, None, None))
                theirs.append(iu)
    finally:
        lib.flt_flatness_destroy(handle)
    # s runs from 3.2 to 7508 mm: windows end at s0 + 2000 + 500 j <= 7508,
    # j = 0..11.
    assert len(ours) == len(theirs) == 12
    for mine, c in zip(ours, theirs):
        assert np.array_equal(bits(mine), bits(c))


def test_two_threads_with_their_own_flatness_equal_serial_runs():
    import threading

    s, height, slope, valid = noisy_sheet(29, rows=3000, fibers=40)
    z, flags = flatline.reconstruct_with_flags(s, height, slope, valid)
    x = np.linspace(-1000.0, 1000.0, 40)

    def run():
        flat = flatline.Flatness(x, flat_window_length=1500.0, flat_update_interval=300.0)
        return np.array([w.fibers.i_units for w in flat.windows(s, z, flags)])

    serial = run()
    results = [None, None]

    def worker(i):
        results[i] = run()

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for r in results:
        assert np.array_equal(bits(r), bits(serial))
