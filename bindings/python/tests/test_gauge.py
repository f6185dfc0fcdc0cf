# SPDX-License-Identifier: Apache-2.0
"""The gauge from Python: sheets out of rows and frames, cuts early and late,
counters, the iterators, a source on the gauge's thread, bad input."""

import logging
import math
import threading
import time

import numpy as np
import pytest

import flatline

K = 51  # fibers across 1500 mm
PITCH = 1500.0 / (K - 1)


def reference_sheet(rows, step=3.0):
    """The reference's sheet (12 mm centre buckle with wavy edges, 1800 mm
    waves) measured noise-free by two lasers 100 mm apart, rows every step
    mm from s = 0: (s, height, slope, truth)."""
    s = np.arange(rows) * step
    x = -750.0 + PITCH * np.arange(K)

    def z(ss):
        return 12.0 * np.sin(2 * np.pi * ss[:, None] / 1800.0) * np.cos(2 * np.pi * x / 1500.0)

    behind, ahead = z(s - 50.0), z(s + 50.0)
    return s, 0.5 * (behind + ahead), (ahead - behind) / 100.0, z(s)


@pytest.fixture(scope="module")
def calib():
    return flatline.Calibration.reference(first_row=900, rows=240, first_x_mm=-750.0,
                                          pitch_mm=PITCH, fibers=K)


def run_rows(calib, s, h, g, cuts=(), workers=2, **options):
    gauge = flatline.Gauge(calib, gauge_workers=workers, gauge_overflow=1,
                           gauge_keep_maps=1, gauge_sheet_slots=32,
                           gauge_frame_spacing=2.0, **options)
    for c in cuts:
        gauge.cut(c)
    for r in range(len(s)):
        gauge.push_row(s[r], h[r], g[r])
    gauge.flush()
    sheets = list(gauge)
    counters = gauge.counters()
    gauge.close()
    return sheets, counters


def test_rows_to_sheets_with_cuts(calib):
    s, h, g, truth = reference_sheet(3000)  # 9 m
    sheets, counters = run_rows(calib, s, h, g, cuts=(3000.0, 6000.0))
    assert [sh.id for sh in sheets] == [1, 2, 3]
    assert [sh.coil for sh in sheets] == [1, 1, 1]
    assert (sheets[0].s_start, sheets[0].s_end) == (0.0, 3000.0)
    assert (sheets[1].s_start, sheets[1].s_end) == (3000.0, 6000.0)
    assert sheets[0].flags == flatline.SheetFlag.HEAD
    assert flatline.SheetFlag.FLUSHED in sheets[2].flags
    assert sum(sh.rows for sh in sheets) == 3000 == counters["frames"]
    # A sheet ends exactly at its cut: its rows lie before it.
    assert sheets[0].s[-1] < 3000.0 <= sheets[1].s[0]
    # Noise-free rows: the reconstruction is within 1 um of the truth
    # (the reconstructor's own figure on this sheet is 0.25 um).
    z = np.concatenate([sh.z for sh in sheets])
    assert np.max(np.abs(z - truth)) < 1e-3
    # The centre buckle and wavy edges: every sheet is a mix of the two,
    # the strip spans the fiber grid plus one pitch.
    for sh in sheets:
        assert sh.shape in (flatline.Shape.MIX, flatline.Shape.CENTRE_BUCKLE,
                            flatline.Shape.WAVY_EDGE_BOTH)
        assert sh.strip_width == pytest.approx(1500.0 + PITCH, abs=1e-9)
        assert sh.fibers.i_units.shape == (K,) and sh.zones.i_units.ndim == 1
        assert sh.values["rows"] == sh.rows
        assert sh.dropped == 0 and sh.invalid == 0
    # A 12 mm wave of 1800 mm: the largest wave is 24 mm peak to peak at
    # the centre or the edges (within 2% for the rows' sampling).
    assert sheets[1].wave_height == pytest.approx(24.0, rel=0.02)
    assert sheets[1].wave_period == pytest.approx(1800.0, rel=0.02)


def test_workers_give_the_same_sheets(calib):
    s, h, g, _ = reference_sheet(1500)
    runs = [run_rows(calib, s, h, g, cuts=(1500.0, 3000.0), workers=w)[0] for w in (0, 1, 2)]
    for other in runs[1:]:
        assert len(other) == len(runs[0])
        for a, b in zip(runs[0], other):
            assert a.values == b.values or all(
                (a.values[k] == b.values[k]) or (math.isnan(a.values[k]) and
                                                 math.isnan(b.values[k]))
                for k in a.values)
            assert np.array_equal(a.z, b.z)
            assert np.array_equal(a.fibers.i_units, b.fibers.i_units, equal_nan=True)


def test_late_cut_gives_the_early_cut_sheets(calib):
    s, h, g, _ = reference_sheet(5400)  # 16.2 m
    early, _ = run_rows(calib, s, h, g, cuts=(3000.0,), gauge_max_sheet_length=14000.0)
    gauge = flatline.Gauge(calib, gauge_overflow=1, gauge_keep_maps=1,
                           gauge_frame_spacing=2.0, gauge_max_sheet_length=14000.0)
    for r in range(4000):  # to s = 12 m: the reconstructor finished s = 3 m long ago
        gauge.push_row(s[r], h[r], g[r])
    gauge.cut(3000.0)
    for r in range(4000, len(s)):
        gauge.push_row(s[r], h[r], g[r])
    gauge.flush()
    late = list(gauge)
    assert len(late) == len(early) == 2
    for a, b in zip(early, late):
        assert np.array_equal(a.z, b.z) and a.rows == b.rows and a.s_end == b.s_end
    assert late[0].lookahead_mm > early[0].lookahead_mm


def test_latency_in_seconds_is_the_lookahead_at_the_rows_pace(calib):
    # Rows 3 mm apart pushed every ~1 ms: a sheet's latency in seconds is
    # its look-ahead at that pace. The bound is the push times of the rows
    # beside the cut and of the newest row taken, by the host's clock
    # (time.time, the clock the gauge stamps rows with), widened by 20 ms
    # for Windows' clock tick.
    s, h, g, _ = reference_sheet(1400)  # 4.2 m
    gauge = flatline.Gauge(calib, gauge_overflow=1, gauge_frame_spacing=2.0, latency_mm=1000.0)
    gauge.cut(1500.0)
    before, after = [], []
    for r in range(len(s)):
        time.sleep(0.001)
        before.append(time.time())
        gauge.push_row(s[r], h[r], g[r])
        after.append(time.time())
    gauge.flush()
    sheets = list(gauge)
    assert len(sheets) == 2
    first, last = sheets
    i = int(np.searchsorted(s, first.s_end))  # the first row at or after the cut
    j = int(np.searchsorted(s, first.s_end + first.lookahead_mm - 1e-6))  # the newest row taken
    assert s[j] == pytest.approx(first.s_end + first.lookahead_mm, abs=1e-9)
    assert first.lookahead_mm >= 900.0
    assert after[j] - before[i - 1] + 0.02 >= first.latency_s >= before[j] - after[i] - 0.02
    assert before[i - 1] - 0.02 <= first.cut_time <= after[i] + 0.02
    assert first.finished_time >= first.cut_time + first.latency_s - 0.02
    # The last sheet ended with the strip: it waited for nothing.
    assert last.lookahead_mm == 0.0 and last.latency_s == 0.0


def test_provisional_sheets_come_early_and_count_nowhere(calib):
    # With gauge_provisional_mm 300 each cut's sheet comes first as an early
    # answer 300 mm past its cut, then final with the same id; the finals
    # are the sheets of a gauge without early answers, and only they are
    # counted (counters, coil statistics).
    s, h, g, _ = reference_sheet(4000)  # 12 m
    rules = flatline.ToleranceRules.loads(VERDICT_RULES)
    runs = []
    for provisional in (0.0, 300.0):
        gauge = flatline.Gauge(calib, gauge_workers=2, gauge_overflow=1, gauge_keep_maps=1,
                               gauge_sheet_slots=32, gauge_frame_spacing=2.0,
                               gauge_provisional_mm=provisional)
        gauge.set_rules(rules, thickness_mm=4.0, width_mm="measured")
        gauge.cut(3000.0)
        gauge.cut(6000.0)
        # The rows before the second early answer is due (row 2100 is at
        # 6300 mm), then the sheets before it (the first early answer and
        # its final; the final alone without early answers): the evaluator
        # is free when the next early answer falls due, on any machine.
        # Pushed at once, a loaded machine can still be evaluating the first
        # early answer when the second cut's final comes: that cut then has
        # none.
        for r in range(2100):
            gauge.push_row(s[r], h[r], g[r])
        sheets = []
        while len(sheets) < (2 if provisional > 0 else 1):
            sheet = gauge.next_sheet(timeout=60.0)
            assert sheet is not None, "no sheet in a minute"
            sheets.append(sheet)
        for r in range(2100, len(s)):
            gauge.push_row(s[r], h[r], g[r])
        gauge.flush()
        runs.append((sheets + list(gauge), gauge.counters(), gauge.coil_stats(last=True)))
        gauge.close()
    (plain, plain_counters, plain_stats), (early, counters, stats) = runs
    assert [sh.provisional for sh in early] == [True, False, True, False, False]
    assert [sh.id for sh in early] == [1, 1, 2, 2, 3]
    finals = [sh for sh in early if not sh.provisional]
    assert len(finals) == len(plain) == 3
    for a, b in zip(finals, plain):  # every value and map (times apart), bit for bit
        assert a.values.keys() == b.values.keys()
        assert all(a.values[k] == b.values[k] or (math.isnan(a.values[k]) and
                                                  math.isnan(b.values[k])) for k in a.values)
        assert np.array_equal(a.z, b.z) and np.array_equal(a.s, b.s)
        assert [r.worst for r in a.verdict] == [r.worst for r in b.verdict]
    for p, f in ((early[0], early[1]), (early[2], early[3])):
        assert flatline.SheetFlag.PROVISIONAL in p.flags
        assert (p.s_start, p.s_end, p.rows) == (f.s_start, f.s_end, f.rows)
        assert 300.0 <= p.lookahead_mm < 303.0 < 1500.0 < f.lookahead_mm
        # Noise-free rows: the estimate is within 1 um of the final.
        assert np.max(np.abs(p.z - f.z)) < 1e-3
        assert [r.state for r in p.verdict] == [r.state for r in f.verdict]
    assert counters["sheets"] == plain_counters["sheets"] == 3
    assert counters["provisional"] == 2 and plain_counters["provisional"] == 0
    assert (stats.sheets, stats.failed) == (plain_stats.sheets, plain_stats.failed) == (3, 3)


def test_line_stop_and_reversal_are_skipped_and_counted(calib):
    s, h, g, _ = reference_sheet(1000)
    gauge = flatline.Gauge(calib, gauge_overflow=1, gauge_frame_spacing=2.0)
    for r in range(500):
        gauge.push_row(s[r], h[r], g[r])
    for _ in range(5):  # the line stops
        gauge.push_row(s[499], h[499] + 9.0, g[499])
    for r in range(490, 1000):  # backs up 30 mm, then on again
        gauge.push_row(s[r], h[r], g[r])
    gauge.flush()
    (sheet,) = list(gauge)
    c = gauge.counters()
    # Rows 490..498 lie behind the furthest position (reversal); row 499 is
    # at it again (a stop, like the five before).
    assert c["skipped_stop"] == 6 and c["skipped_reversal"] == 9
    assert sheet.skipped == 15 and sheet.rows == 1000


def test_frames_and_the_sheet_iterator(calib):
    with flatline.SimulatedLine(calib, sim_frame_spacing=10.0) as sim:
        sim.add_defect("centre_buckle", 4.0, 800.0)
        with flatline.Gauge(calib, gauge_frame_spacing=8.0, gauge_overflow=1,
                            lag_knots=4) as gauge:
            gauge.cut(1000.0)
            got = []
            for _ in range(200):  # 2 m
                frame = sim.next_frame()
                gauge.push_frame(frame.image, frame.encoder_mm)
                got.extend(gauge)
            gauge.flush()
            got.extend(gauge.sheets(timeout=0.1))
            assert [sh.id for sh in got] == [1, 2]
            assert got[0].s_end == 1000.0 and got[0].rows == 100
            assert gauge.counters()["extracted"] == 200
            assert gauge.option("laser_spacing") == 100.0


def test_acquisition_from_a_source(calib):
    with flatline.SimulatedLine(calib, sim_frame_spacing=10.0) as sim:
        sim.add_defect("centre_buckle", 4.0, 800.0)
        source = flatline.Source.simulator(sim)
        with flatline.Gauge(calib, gauge_frame_spacing=8.0, gauge_overflow=1,
                            lag_knots=4) as gauge:
            gauge.attach(source)
            gauge.cut(1000.0)
            gauge.start()
            with pytest.raises(flatline.StateError, match="acquiring"):
                gauge.flush()  # frames come from the source: stop first
            sheet = gauge.next_sheet(timeout=60.0)  # comes while acquiring
            gauge.stop()
            assert sheet is not None and sheet.s_end == 1000.0
            assert gauge.counters()["acquiring"] == 0
            gauge.flush()
            rest = gauge.next_sheet()
            assert rest is not None and rest.s_start == 1000.0
            gauge.attach(None)


def test_sheets_can_be_taken_on_another_thread(calib):
    s, h, g, _ = reference_sheet(2000)
    gauge = flatline.Gauge(calib, gauge_overflow=1, gauge_frame_spacing=2.0, lag_knots=4)
    for c in (1000.0, 2000.0, 3000.0, 4000.0, 5000.0):
        gauge.cut(c)
    taken = []
    reader = threading.Thread(target=lambda: taken.extend(gauge.sheets(timeout=5.0)))
    reader.start()
    for r in range(len(s)):
        gauge.push_row(s[r], h[r], g[r])
    gauge.flush()
    reader.join()
    assert [sh.id for sh in taken] == [1, 2, 3, 4, 5, 6]


def test_bad_input_raises_with_the_library_message(calib):
    with pytest.raises(flatline.InvalidArgumentError, match="sim_seed"):
        flatline.Gauge(calib, sim_seed=3)
    with pytest.raises(TypeError):
        flatline.Gauge(calib, no_such_option=1)
    with pytest.raises(flatline.InvalidArgumentError, match="laser_spacing"):
        flatline.Gauge(calib, laser_spacing=80.0)
    gauge = flatline.Gauge(calib)
    with pytest.raises(ValueError, match="shape"):
        gauge.push_frame(np.zeros((10, 10), np.uint8), 0.0)
    with pytest.raises(ValueError, match="3 channels; pass one channel"):
        gauge.push_frame(np.zeros((240, 2048, 3), np.uint8), 0.0)
    with pytest.raises(TypeError, match="dtype"):
        gauge.push_frame(np.zeros((240, 2048), np.float32), 0.0)
    with pytest.raises(flatline.InvalidArgumentError, match="encoder_mm"):
        gauge.push_frame(np.zeros((240, 2048), np.uint8), math.nan)
    with pytest.raises(flatline.InvalidArgumentError, match="fibers"):
        gauge.push_row(0.0, np.zeros(K + 1), np.zeros(K + 1))
    with pytest.raises(flatline.InvalidArgumentError, match="shape"):
        gauge.push_row(0.0, np.zeros(K), np.zeros(K - 1))
    gauge.cut(100.0)
    with pytest.raises(flatline.InvalidArgumentError, match="previous cut"):
        gauge.cut(50.0)
    with pytest.raises(flatline.StateError, match="no source"):
        gauge.start()
    with pytest.raises(ValueError):
        gauge.next_sheet(timeout=-1)
    gauge.close()
    with pytest.raises(flatline.StateError):
        gauge.cut(200.0)


def test_gauge_options_table():
    table = flatline.gauge_options()
    assert table["gauge_workers"] == 2.0 and table["gauge_frame_spacing"] == 1.0
    assert all(name.startswith("gauge_") for name in table) and len(table) == 14
    assert "gauge_workers (int): default 2" in flatline.Gauge.__doc__


def test_narrow_strip_edges_and_off_strip_fibers(calib):
    # A strip 1000 mm wide, 100 mm off centre, on the 1500 mm fiber grid.
    with flatline.SimulatedLine(calib, sim_frame_spacing=10.0, sim_strip_width=1000.0,
                                sim_strip_offset=100.0, sim_surround=2) as sim:
        sim.add_defect("centre_buckle", 4.0, 800.0)
        with flatline.Gauge(calib, gauge_frame_spacing=8.0, gauge_overflow=1,
                            gauge_keep_maps=1, lag_knots=4) as gauge:
            for _ in range(200):  # 2 m
                frame = sim.next_frame()
                gauge.push_frame(frame.image, frame.encoder_mm)
            gauge.flush()
            (sheet,) = list(gauge)
    assert sheet.window_flags & flatline.WINDOW_ON_STRIP
    # The extractor's edges, to a fraction of a camera column (about 1 mm),
    # smoothed along the sheet: within 2 mm.
    assert abs(sheet.strip_width - 1000.0) < 2.0
    assert abs(sheet.strip_centre - 100.0) < 2.0
    assert sheet.strip_width_range[0] <= sheet.strip_width <= sheet.strip_width_range[1]
    assert sheet.strip_centre_range[0] <= sheet.strip_centre <= sheet.strip_centre_range[1]
    x = -750.0 + PITCH * np.arange(K)
    beside = (x < -445.0) | (x > 645.0)  # a pitch and a half (45 mm) beside the edges
    assert np.all(sheet.z_flags[:, beside] == flatline.FLAG_OFF_STRIP)
    assert np.all(np.isnan(sheet.z[:, beside]))
    inside = (x > -355.0) & (x < 555.0)
    assert not np.any(sheet.z_flags[:, inside] & flatline.FLAG_OFF_STRIP)
    # Result fibers on the strip lie within its half width; those beyond
    # its edges are flagged off it.
    on = (sheet.fibers.flags & flatline.FIBER_NO_DATA) == 0
    assert np.any(on)
    assert np.all(np.abs(sheet.fiber_strip_x[on]) <= 500.0)
    beyond = np.abs(sheet.fiber_strip_x) > 500.0
    assert np.all(sheet.fibers.flags[beyond] & flatline.FIBER_OFF_STRIP)
    on_strip = (sheet.zones.flags & flatline.ZONE_OFF_STRIP) == 0
    assert np.any(on_strip)
    assert np.all(np.abs(sheet.zones.strip_x[on_strip]) < 500.0)
    assert np.all(np.isnan(sheet.zones.strip_x[~on_strip]))


VERDICT_RULES = """{
  "format": "flatline-tolerances", "version": 1, "name": "python gauge test",
  "rules": [
    { "name": "1/2 m tight", "measure": "straightedge_along", "length_mm": 500,
      "bands": [ { "thickness_mm": [1, 10], "width_mm": [0, 3000], "limit": 1.9 } ] },
    { "name": "1/2 m loose", "measure": "straightedge_along", "length_mm": 500,
      "bands": [ { "thickness_mm": [1, 10], "width_mm": [0, 3000], "limit": 2.1 } ] }
  ]
}"""


def test_sheets_carry_their_verdict_and_the_coil_its_statistics(calib):
    # The strip waves along travel as 2 sin(2 pi s / 1000) mm over its whole
    # width: under a 500 mm straightedge the deviation is A (1 - cos(pi L /
    # P)) = 2 mm (flatline/verdict.h), so the 1.9 mm rule fails and the
    # 2.1 mm one passes.
    s = np.arange(3000) * 3.0
    x = np.zeros(K)

    def z(ss):
        return 2.0 * np.sin(2 * np.pi * ss[:, None] / 1000.0) + x

    behind, ahead = z(s - 50.0), z(s + 50.0)
    h, g = 0.5 * (behind + ahead), (ahead - behind) / 100.0
    rules = flatline.ToleranceRules.loads(VERDICT_RULES)
    gauge = flatline.Gauge(calib, gauge_workers=2, gauge_overflow=1, gauge_frame_spacing=2.0)
    assert gauge.rules is None and gauge.coil_stats() is None
    gauge.set_rules(rules, thickness_mm=4.0, width_mm="measured")
    assert gauge.rules is rules
    for c in (3000.0, 6000.0):
        gauge.cut(c)
    for r in range(len(s)):
        gauge.push_row(s[r], h[r], g[r])
    gauge.flush()
    sheets = list(gauge)
    assert len(sheets) == 3
    for sheet in sheets:
        tight, loose = sheet.verdict
        assert tight.rule.name == "1/2 m tight" and loose.rule.name == "1/2 m loose"
        assert tight.state == flatline.VerdictState.FAIL
        assert loose.state == flatline.VerdictState.PASS
        assert sheet.failed_rules == 1
        # Rows every 3 mm: the contacts lie up to 3 mm closer than 500 mm
        # and the trough up to 1.5 mm from a row, at most A pi h / P = 0.019
        # mm less; the noise-free gauge is within micrometres of the sheet.
        assert 2.0 - 0.02 <= tight.worst <= 2.0 + 0.001
        assert tight.worst == loose.worst
        assert tight.margin == pytest.approx(1.9 - tight.worst, abs=1e-12)
        assert sheet.s_first <= tight.s_mm <= sheet.s_last
    stats = gauge.coil_stats(last=True)
    assert stats is not None and stats.finished
    assert (stats.coil, stats.sheets, stats.passed, stats.failed) == (1, 3, 0, 3)
    tight_stats = stats.rules[0]
    assert (tight_stats.passed, tight_stats.failed) == (0, 3)
    assert tight_stats.worst_max == max(sh.verdict[0].worst for sh in sheets)
    # worst / limit = 2 / 1.9 lies in (1.0, 1.1]: bin 10.
    assert tight_stats.histogram[10] == 3 and tight_stats.histogram.sum() == 3
    assert stats.rules[1].histogram[9] == 3  # 2 / 2.1 in (0.9, 1.0]
    assert stats.rules[1].passed == 3
    now = gauge.coil_stats()
    assert now is not None and (now.coil, now.sheets) == (0, 0)
    # Without rules a sheet has no verdict.
    gauge.set_rules(None)
    for r in range(len(s)):
        gauge.push_row(s[r] + 20000.0, h[r], g[r])
    gauge.flush()
    assert all(sheet.verdict is None for sheet in gauge)
    with pytest.raises(flatline.InvalidArgumentError, match="thickness_mm"):
        gauge.set_rules(rules, thickness_mm=-1.0, width_mm="measured")
    gauge.close()


# ---- nothing lost unless the caller chose it ------------------------------------


def _frame_pool(calib, n=60):
    """n rendered frames of the simulated line (a buckle), to push cyclically."""
    with flatline.SimulatedLine(calib, sim_frame_spacing=3.0) as sim:
        sim.add_defect("centre_buckle", 6.0, 1800.0)
        return [sim.next_frame().image for _ in range(n)]


def _push_frames_fast(gauge, pool, count, step=3.0, cut_every=1000.0):
    for c in np.arange(cut_every, count * step, cut_every):
        gauge.cut(float(c))
    for i in range(count):
        gauge.push_frame(pool[i % len(pool)], i * step)
    gauge.flush()
    return list(gauge)


def _same_sheets(a, b):
    assert len(a) == len(b)
    for x, y in zip(a, b):
        assert x.values.keys() == y.values.keys()
        for key in x.values:
            vx, vy = x.values[key], y.values[key]
            assert (vx == vy) or (math.isnan(vx) and math.isnan(vy)), key
        assert np.array_equal(x.zones.i_units, y.zones.i_units, equal_nan=True)


def test_frames_pushed_as_fast_as_possible_are_never_dropped_by_default(calib):
    # 2100 frames pushed by a plain loop into 2 workers: the loop outruns
    # the extraction (gauge_overflow="drop" loses most of them, which shows
    # it does), and by default it waits: 0 dropped, every frame in a sheet,
    # the same sheets as with the queue set to wait explicitly.
    pool = _frame_pool(calib)
    with flatline.Gauge(calib, gauge_workers=2, gauge_overflow="drop",
                        gauge_frame_spacing=2.0, gauge_queue_frames=8) as gauge:
        lossy = _push_frames_fast(gauge, pool, 2100)
        counters = gauge.counters()
        assert counters["dropped"] > 0
        # Every frame is in a sheet, dropped or before the strip; a sheet
        # that lost any says so.
        assert sum(sh.rows for sh in lossy) + counters["dropped"] + counters["no_strip"] == 2100
        assert all(sh.dropped == 0 or flatline.SheetFlag.LOST_ROWS in sh.flags for sh in lossy)
    runs = {}
    for overflow in ("auto", "wait"):
        with flatline.Gauge(calib, gauge_workers=2, gauge_overflow=overflow,
                            gauge_frame_spacing=2.0, gauge_queue_frames=8) as gauge:
            runs[overflow] = _push_frames_fast(gauge, pool, 2100)
            counters = gauge.counters()
            assert counters["dropped"] == 0 and counters["frames"] == 2100
            assert sum(sh.rows for sh in runs[overflow]) == 2100 - counters["no_strip"]
    assert all(sh.coverage == 1.0 and not sh.incomplete for sh in runs["auto"])
    _same_sheets(runs["auto"], runs["wait"])
    with flatline.Gauge(calib) as gauge:
        assert gauge.option("gauge_overflow") == flatline.capi.FLT_GAUGE_OVERFLOW_AUTO


def test_readme_streaming_pattern_returns_every_sheet(calib):
    # The README's pattern: read the sheets while pushing, then flush and
    # read the rest. At a latency_mm of 6000 the strip's first rows wait up
    # to 11.8 m (twice the latency at a strip's head), longer than this
    # 10.2 m strip, so the 10 sheets of 1 m all finish at the flush: more
    # than the 4 sheet slots, and every one comes out, in order.
    s, h, g, _ = reference_sheet(3400)  # 10.2 m
    got = []
    with flatline.Gauge(calib, rigid_motion=True, robust="huber", latency_mm=6000.0,
                        gauge_frame_spacing=2.0) as gauge:
        for c in range(1000, 10000, 1000):
            gauge.cut(float(c))
        for r in range(len(s)):
            gauge.push_row(s[r], h[r], g[r])
            for sheet in gauge:
                got.append(sheet)
        gauge.flush()
        got.extend(gauge)
        counters = gauge.counters()
    assert [sh.id for sh in got] == list(range(1, 11))
    assert counters["sheets_dropped"] == 0 and counters["sheets_grown"] > 0
    assert all(not sh.incomplete for sh in got)


def test_a_sheet_missing_rows_is_not_judged(calib):
    # Rows every 3 mm with 100 of the first sheet's 1000 missing (a camera
    # that lost them): coverage 0.9 < 0.95, incomplete, shape and verdict
    # "not judged"; the second sheet is whole.
    s, h, g, _ = reference_sheet(2000)
    keep = np.ones(len(s), bool)
    keep[400:500] = False
    rules = flatline.ToleranceRules.loads(VERDICT_RULES)
    with flatline.Gauge(calib, gauge_frame_spacing=2.0) as gauge:
        gauge.set_rules(rules, thickness_mm=4.0, width_mm="measured")
        gauge.cut(3000.0)
        for r in np.flatnonzero(keep):
            gauge.push_row(s[r], h[r], g[r])
        gauge.flush()
        first, second = list(gauge)
    assert first.incomplete and first.coverage == 0.9
    assert (first.rows, first.missing, first.rows_expected) == (900, 100, 1000)
    assert first.shape == flatline.Shape.NOT_JUDGED and str(first.shape) == "not judged: incomplete"
    assert first.verdict_state == flatline.VerdictState.NOT_JUDGED
    assert all(r.state == flatline.VerdictState.NOT_JUDGED for r in first.verdict)
    assert not second.incomplete and second.coverage == 1.0
    assert second.verdict_state != flatline.VerdictState.NOT_JUDGED


def test_thickness_and_width_are_required_and_no_band_is_not_judged(calib):
    rules = flatline.ToleranceRules.loads(VERDICT_RULES)  # bands: 1..10 mm thick
    s, h, g, _ = reference_sheet(2000)
    with flatline.Gauge(calib, gauge_frame_spacing=2.0) as gauge:
        with pytest.raises(TypeError, match="thickness_mm"):
            gauge.set_rules(rules)
        with pytest.raises(TypeError, match="width_mm"):
            gauge.set_rules(rules, thickness_mm=4.0)
        with pytest.raises(ValueError, match="measured"):
            gauge.set_rules(rules, thickness_mm=4.0, width_mm="nominal")
        assert gauge.rules is None
        # 0.5 mm is in no band: every rule NO_BAND, each sheet not judged,
        # and the coil counts 0 passed, 0 failed, 2 not judged.
        gauge.set_rules(rules, thickness_mm=0.5, width_mm=1500.0)
        gauge.cut(3000.0)
        for r in range(len(s)):
            gauge.push_row(s[r], h[r], g[r])
        gauge.flush()
        sheets = list(gauge)
        stats = gauge.coil_stats(last=True)
    assert len(sheets) == 2
    assert all(sh.verdict_state == flatline.VerdictState.NOT_JUDGED for sh in sheets)
    assert all(r.state == flatline.VerdictState.NO_BAND for sh in sheets for r in sh.verdict)
    assert stats is not None
    assert (stats.sheets, stats.passed, stats.failed, stats.not_judged, stats.judged) == \
        (2, 0, 0, 2, 0)
    assert stats.rules[0].no_band == 2


def test_a_second_thread_pushing_is_refused_and_the_gauge_goes_on(calib):
    # While the main thread is in a push (a queue of 1 frame and one worker
    # keep it waiting for room), a second thread's pushes are refused at
    # once with StateError;
    # those that land between the main thread's pushes are behind the
    # strip (a short reversal) and skipped. Every main row is in a sheet.
    s, h, g, _ = reference_sheet(3000)
    refused, taken = [], []
    extra = 0
    stop = threading.Event()
    with flatline.Gauge(calib, gauge_workers=1, gauge_queue_frames=1, lag_knots=4,
                        gauge_frame_spacing=2.0, gauge_reversal_length=1e8) as gauge:
        for c in range(600, 9000, 600):
            gauge.cut(float(c))
        for r in range(10):
            gauge.push_row(s[r], h[r], g[r])

        def second():
            while not stop.is_set():
                try:
                    gauge.push_row(0.0, h[0], g[0])
                    taken.append(1)
                except flatline.StateError as e:
                    assert "another thread is pushing" in str(e)
                    refused.append(1)
                stop.wait(0.001)

        other = threading.Thread(target=second)
        other.start()
        try:
            r = 10
            while r < len(s):  # refused too when it comes while the other pushes
                try:
                    gauge.push_row(s[r], h[r], g[r])
                    r += 1
                except flatline.StateError:
                    pass
            # A fast machine may push every row before the two threads met:
            # the last row again (a line stop, skipped) until they have, for
            # at most 20 s.
            deadline = time.monotonic() + 20.0
            while not refused and time.monotonic() < deadline:
                try:
                    gauge.push_row(s[-1], h[-1], g[-1])
                    extra += 1
                except flatline.StateError:
                    pass
        finally:
            stop.set()
            other.join()
        gauge.flush()
        sheets = list(gauge)
        counters = gauge.counters()
    assert refused, "the second thread never met the first one's push"
    assert sum(sh.rows for sh in sheets) == len(s)
    assert counters["frames"] == len(s) + len(taken) + extra
    assert counters["skipped_reversal"] + counters["skipped_stop"] == len(taken) + extra


def _write_png(path, image):
    """An 8-bit grey PNG without an imaging library."""
    import struct
    import zlib

    raw = b"".join(b"\0" + image[r].tobytes() for r in range(image.shape[0]))

    def chunk(tag, body):
        return (struct.pack(">I", len(body)) + tag + body
                + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", image.shape[1], image.shape[0], 8, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                + chunk(b"IDAT", zlib.compress(raw, 1)) + chunk(b"IEND", b""))


def test_run_a_recording_to_its_end(calib, tmp_path):
    # 150 recorded frames 10 mm apart, cuts at 500 and 1000 mm: run() yields
    # the 3 sheets, the last one after the source's end (the flush), and
    # nothing is dropped (a recording waits for room).
    with flatline.SimulatedLine(calib, sim_frame_spacing=10.0) as sim:
        sim.add_defect("centre_buckle", 4.0, 800.0)
        for i in range(150):
            _write_png(tmp_path / f"frame_{i:03d}.png", sim.next_frame().image)
    for workers in (0, 2):
        with flatline.Gauge(calib, gauge_workers=workers, gauge_frame_spacing=8.0, lag_knots=4,
                            gauge_queue_frames=4) as gauge:
            gauge.cut(500.0)
            gauge.cut(1000.0)
            with flatline.Source.images(tmp_path, step=10.0) as source:
                sheets = list(gauge.run(source))
            counters = gauge.counters()
        assert [sh.id for sh in sheets] == [1, 2, 3]
        assert [sh.s_end for sh in sheets[:2]] == [500.0, 1000.0]
        assert flatline.SheetFlag.FLUSHED in sheets[2].flags
        assert counters["frames"] == 150 and counters["dropped"] == 0
        assert sum(sh.rows for sh in sheets) + counters["no_strip"] == 150
        assert counters["acquiring"] == 0
    with flatline.Gauge(calib) as gauge:
        with pytest.raises(TypeError, match="Source"):
            next(gauge.run("recording/"))


def test_the_log_reaches_logging(calib, caplog):
    # A gauge that drops frames (gauge_overflow="drop", a queue of 1 and a
    # plain loop pushing faster than one worker extracts: most are dropped),
    # a cut given for a strip that ended, and an overexposed line: the logger "flatline"
    # gets a message for each, at its level, by the time flush returns.
    with flatline.SimulatedLine(calib, sim_frame_spacing=10.0, sim_line_peak=1.5) as sim:
        frames = [sim.next_frame().image for _ in range(200)]
    caplog.set_level(logging.INFO, logger="flatline")
    # An earlier test's drops may have used this place's 5 messages of the
    # last 10 s: a new installation starts the rate limits afresh.
    flatline._log.install()
    with flatline.Gauge(calib, gauge_workers=1, gauge_queue_frames=1, gauge_overflow="drop",
                        gauge_frame_spacing=8.0, lag_knots=4) as gauge:
        for i, frame in enumerate(frames):
            gauge.push_frame(frame, 10.0 * i)
        gauge.flush()
        dropped = gauge.counters()["dropped"]
        sheets = list(gauge)
        gauge.cut(1200.0)  # the next strip's head (5000 mm) is past it: ignored
        gauge.push_frame(frames[0], 5000.0)
        gauge.flush()
        counters = gauge.counters()
    messages = [(r.levelname, r.getMessage()) for r in caplog.records if r.name == "flatline"]
    drops = [m for level, m in messages if " dropped: " in m]
    assert dropped > 0
    assert 1 <= len(drops) <= 5 and all(m.startswith("gauge: frame at encoder") for m in drops)
    assert sum("cut ignored, the last at encoder 1200.0 mm" in m for _, m in messages) == 1
    saturated = [level for level, m in messages if " are saturated " in m]
    assert len(sheets) >= 1 and saturated == ["WARNING"] * counters["sheets"]
    # (a burst of drops wider than the tail length ends a strip: one head each)
    assert sum("the strip's head at" in m for _, m in messages) == counters["strips"] >= 2
    assert all(level in ("INFO", "WARNING") for level, _ in messages)


def test_flags_print_by_name():
    # print(sheet.flags) names the bits (IntFlag alone prints the number)
    flags = flatline.SheetFlag.HEAD | flatline.SheetFlag.FLUSHED
    assert "HEAD" in str(flags) and "FLUSHED" in str(flags) and "HEAD" in f"{flags}"
    assert int(flags) == flatline.capi.FLT_SHEET_FLAG_HEAD | flatline.capi.FLT_SHEET_FLAG_FLUSHED
    assert "BOW" in str(flatline.ShapeComponent.BOW)
