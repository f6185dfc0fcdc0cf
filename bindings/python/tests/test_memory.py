"""Memory: creating and destroying reconstructors, and repeating large calls,
leaves the resident set flat."""

import gc
import tracemalloc

import numpy as np

import flatline

from conftest import noisy_sheet, rss_bytes

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
