# SPDX-License-Identifier: Apache-2.0
"""Memory: creating and destroying reconstructors, and repeating large calls,
leaves the resident set flat."""

import gc
import math
import tracemalloc

import numpy as np
import pytest

import flatline

from conftest import noisy_sheet, roi_reference, rss_bytes

MB = 1 << 20


def test_10000_create_destroy_cycles_leave_rss_flat():
    # Each reconstructor of 16 fibers holds row_capacity x fibers x 9 bytes =
    # 8192 x 16 x 9 = 1.18 MB of zero-initialised (hence resident) buffers.
    # Leaking one handle in every four cycles would add > 2,900 MB; the
    # bound of 4 MB allows allocator noise only.
    for _ in range(200):  # warm-up: allocator arenas, imports, caches
        with flatline.Reconstructor(16):
            pass
    gc.collect()
    before = rss_bytes()
    tracemalloc.start()
    python_before = tracemalloc.get_traced_memory()[0]
    for i in range(10_000):
        recon = flatline.Reconstructor(16, lag_knots=8 + i % 3)
        if i % 2:
            recon.close()  # explicit release
        else:
            del recon  # release by reference count
    gc.collect()
    python_growth = tracemalloc.get_traced_memory()[0] - python_before
    tracemalloc.stop()
    growth = rss_bytes() - before
    print(f"RSS growth over 10,000 cycles: {growth / 1024:.0f} KiB; "
          f"Python heap growth {python_growth} B")
    assert growth < 4 * MB
    # No Python object survives a cycle either: a leaked proxy (>= 48 bytes)
    # per cycle would be >= 480 KB.
    assert python_growth < 64 * 1024


def test_release_reconstruct_memory_returns_what_batch_calls_kept():
    # 2000 rows x 300 fibers, 3 mm apart: 64 knots 100 mm apart. recon.h
    # gives about 20 doubles per fiber and knot of kept working memory; the
    # bound is half that. Then nothing is left.
    s, h, sl, valid = noisy_sheet(52, rows=2000, fibers=300)
    flatline.reconstruct(s, h, sl, valid)
    knots = (s[-1] - s[0] + 100.0) / 100.0 + 4
    freed = flatline.release_reconstruct_memory()
    print(f"freed {freed / 1e6:.1f} MB")
    assert freed >= 10 * 8 * knots * 300
    assert flatline.release_reconstruct_memory() == 0.0
    z = flatline.reconstruct(s, h, sl, valid)  # allocates again, as the first call did
    assert np.isfinite(z).any()


def test_repeated_large_calls_leave_rss_flat():
    # 2000 rows x 300 fibers: each call makes a 4.8 MB z and flags array and
    # ~100 doubles per fiber and knot of working memory inside the library
    # (~16 MB). Leaking any of them once per call over 15 calls would add
    # > 70 MB; the bound is 8 MB.
    s, h, sl, valid = noisy_sheet(51, rows=2000, fibers=300)

    def calls():
        z = flatline.reconstruct(s, h, sl, valid)
        with flatline.Reconstructor(300, lag_knots=8) as recon:  # streaming too
            recon.push(s, h, sl, valid)
            recon.end_sheet()
            out = recon.pull()
        assert z.shape == out[1].shape == (2000, 300)

    for _ in range(2):  # warm-up: the allocator's arenas reach their size
        calls()
    gc.collect()
    before = rss_bytes()
    for _ in range(15):
        calls()
    gc.collect()
    growth = rss_bytes() - before
    print(f"RSS growth over 15 large calls: {growth / 1024:.0f} KiB")
    assert growth < 8 * MB


def test_simulator_and_extractor_create_destroy_cycles_leave_rss_flat():
    # A SimulatedLine of the 256-row ROI sensor holds its frame scratch (4
    # bytes per pixel: 2 MB), a copy of the calibration and per-fiber
    # tables; an Extractor holds its column maps (~0.5 MB). Leaking either
    # once in 2,000 cycles would add > 1,000 MB; the bound, 4 MB, allows
    # allocator noise only.
    calib = roi_reference(fibers=101, pitch=20.0)

    def cycle(i):
        with flatline.SimulatedLine(calib, sim_seed=i) as sim:
            sim.add_defect("bow", 1.0)
            sim.next_rows(2)
        extractor = flatline.Extractor(calib)
        if i % 2:
            extractor.close()
        del extractor

    for i in range(50):  # warm-up
        cycle(i)
    gc.collect()
    before = rss_bytes()
    for i in range(2_000):
        cycle(i)
    gc.collect()
    growth = rss_bytes() - before
    print(f"RSS growth over 2,000 simulator + extractor cycles: {growth / 1024:.0f} KiB")
    assert growth < 4 * MB


def test_calibration_create_destroy_cycles_leave_rss_flat():
    # A C model holds the camera, two homographies and their inverses and the
    # geometry: >= 50 doubles, so >= 400 bytes per leaked handle, 8 MB over
    # 20,000 cycles (more with the saved text of the loads cycles). The
    # bound, 2 MB, allows allocator noise only; the Python heap must not
    # keep a proxy per cycle either (>= 48 bytes each: 960 KB).
    calib = flatline.Calibration.reference(892, 256)
    text = calib.dumps()

    def cycle(i):
        if i % 3 == 0:
            loaded = flatline.Calibration.loads(text)
            assert loaded.dumps() == text
        elif i % 3 == 1:
            with flatline.Calibration.reference(892, 256) as loaded:
                loaded.intrinsics
        else:
            loaded = flatline.Calibration()
            loaded.frame_size = (640, 480)
            try:  # the error path must not leak either
                loaded.finish()
            except flatline.StateError:
                pass

    for i in range(300):  # warm-up
        cycle(i)
    gc.collect()
    before = rss_bytes()
    tracemalloc.start()
    python_before = tracemalloc.get_traced_memory()[0]
    for i in range(20_000):
        cycle(i)
    gc.collect()
    python_growth = tracemalloc.get_traced_memory()[0] - python_before
    tracemalloc.stop()
    growth = rss_bytes() - before
    print(f"RSS growth over 20,000 calibration cycles: {growth / 1024:.0f} KiB; "
          f"Python heap growth {python_growth} B")
    assert growth < 2 * MB
    assert python_growth < 64 * 1024


def test_repeated_large_simulator_calls_leave_rss_flat():
    # 1500 rows x 1001 fibers: five (n, K) arrays of 12 MB each per call, and
    # a full 2048 x 2048 frame (4 MB; 16 MB of scratch inside). Leaking one
    # array per call over 5 calls would add > 60 MB; the bound is 12 MB.
    with flatline.SimulatedLine() as sim:
        sim.add_defect("centre_buckle", 12.0, 1800.0)

        def calls():
            rows = sim.next_rows(1500)
            frame = sim.next_frame()
            assert rows.height.shape == (1500, 1001) and frame.image.shape == (2048, 2048)

        for _ in range(2):
            calls()
        gc.collect()
        before = rss_bytes()
        for _ in range(5):
            calls()
        gc.collect()
    growth = rss_bytes() - before
    print(f"RSS growth over 5 large simulator calls: {growth / 1024:.0f} KiB")
    assert growth < 12 * MB


def _peak_rss_bytes():
    """The process's peak resident set (VmHWM) so far, or None where the
    kernel does not report it."""
    try:
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def test_close_frees_now_while_tracebacks_hold_the_call():
    # A test framework keeps the exceptions of failing calls, and with them
    # the frames of the binding's methods that raised, whose locals hold the
    # C handle. close() must free the C buffers anyway: otherwise every kept
    # failure pins its object (a contract suite drawing large capacities
    # once held gigabytes this way). Each round creates a Flatness of
    # 200,000 rows (about 22 MB of buffers: flatness.h), a Reconstructor of
    # 64 fibers x 32,768 rows (about 19 MB: recon.h) and an Extractor, keeps
    # a refusal of each (its traceback), and closes them. Twelve rounds that
    # each pinned their objects would add > 480 MB (measured: 590 MB when
    # close() only dropped its reference); the bound of 16 MB allows the
    # kept exceptions (~0.1 MB a round) and the allocator's noise, not one
    # round's buffers (> 40 MB).
    kept = []
    calib = roi_reference(fibers=64, pitch=20.0)

    def round_trip():
        flat = flatline.Flatness(np.arange(3) * 100.0, flat_row_capacity=200_000)
        recon = flatline.Reconstructor(64, row_capacity=32_768)
        ex = flatline.Extractor(calib)
        for fn, args in [(flat.evaluate, (np.zeros(1), np.zeros((1, 3)))),
                         (recon.push, (np.array([np.nan]), np.zeros((1, 64)), np.zeros((1, 64)))),
                         (ex.process, (np.zeros(ex.frame_size[::-1], dtype=np.uint8), math.nan))]:
            try:
                fn(*args)
            except flatline.FlatlineError as error:
                kept.append(error)  # with its traceback: the frames hold the handles
            else:
                raise AssertionError(f"{fn.__name__} took a bad call")
        flat.close()
        recon.close()
        ex.close()

    for _ in range(2):  # warm-up: glibc's mmap threshold rises after the first free
        round_trip()
    gc.collect()
    before = rss_bytes()
    peak_before = _peak_rss_bytes()
    for _ in range(12):
        round_trip()
    gc.collect()
    growth = rss_bytes() - before
    assert len(kept) == 42 and all(e.__traceback__ is not None for e in kept)
    print(f"RSS growth over 12 rounds with their refusals kept: {growth / MB:.1f} MB")
    assert growth < 16 * MB
    # A closed object is closed for good, and a stale handle in a kept frame
    # reaches the library as NULL, which it refuses.
    frame_locals = kept[0].__traceback__.tb_next.tb_frame.f_locals
    handle = frame_locals.get("handle")
    if handle is not None:
        with pytest.raises(flatline.InvalidArgumentError, match="NULL"):
            flatline.capi.flt_flatness_finish(handle)
    if peak_before is not None:
        peak_growth = _peak_rss_bytes() - peak_before
        print(f"peak RSS growth: {peak_growth / MB:.1f} MB")
        assert peak_growth < 16 * MB
