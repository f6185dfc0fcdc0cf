# SPDX-License-Identifier: Apache-2.0
"""Threads: each thread with its own reconstructor gets exactly the serial
results, and the GIL is really released during the C calls."""

import threading
import time

import numpy as np

import flatline

from conftest import bits, noisy_sheet


def stream(sheet, lag_knots=8, block=200):
    s, h, sl, valid = sheet
    out = []
    with flatline.Reconstructor(h.shape[1], lag_knots=lag_knots) as recon:
        for start in range(0, len(s), block):
            part = slice(start, start + block)
            recon.push(s[part], h[part], sl[part], valid[part])
            out.append(recon.pull())
        recon.end_sheet()
        out.append(recon.pull())
    return tuple(np.concatenate(parts) for parts in zip(*out))


def test_two_threads_with_their_own_reconstructors_match_serial_runs_bitwise():
    sheets = [noisy_sheet(seed, rows=3000, fibers=40) for seed in (31, 32)]
    serial = [stream(sheet) for sheet in sheets]
    batch_serial = [flatline.reconstruct(*sheet) for sheet in sheets]
    results = [None, None]
    batch = [None, None]
    errors = []
    barrier = threading.Barrier(2)

    def work(i):
        try:
            barrier.wait()
            for _ in range(3):  # overlap for a while
                results[i] = stream(sheets[i])
                batch[i] = flatline.reconstruct(*sheets[i])
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for i in range(2):
        for got, want in zip(results[i], serial[i]):
            np.testing.assert_array_equal(bits(got) if got.dtype != np.uint8 else got,
                                          bits(want) if want.dtype != np.uint8 else want)
        np.testing.assert_array_equal(bits(batch[i]), bits(batch_serial[i]))


def test_the_gil_is_released_during_reconstruct():
    # A long C call in a worker; the main thread keeps stamping times. With
    # the GIL held for the whole call, no Python code of the main thread
    # could run in the middle of it (the 10 ms margins absorb twice the
    # switch interval, 5 ms, around entry and exit).
    rng = np.random.default_rng(5)
    rows, fibers = 3000, 300  # with 10 mm knots: 0.15-0.4 s in one C call
    s = np.arange(rows) * 3.0
    h = rng.normal(0, 1, (rows, fibers))
    sl = rng.normal(0, 1e-3, (rows, fibers))
    window = {}

    def work():
        window["start"] = time.perf_counter()
        flatline.reconstruct(s, h, sl, knot_spacing=10.0)
        window["end"] = time.perf_counter()

    stamps = []
    worker = threading.Thread(target=work)
    worker.start()
    while worker.is_alive():
        stamps.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    duration = window["end"] - window["start"]
    assert duration > 0.05, f"the call took {duration:.3f} s, too short to judge"
    inside = [t for t in stamps if window["start"] + 0.01 < t < window["end"] - 0.01]
    # ~1 stamp per ms when the GIL is free; demand a fifth of that.
    assert len(inside) >= (duration - 0.02) * 1000 / 5, (len(inside), duration)


def test_one_reconstructor_shared_by_threads_is_serialised_not_corrupted():
    # Misuse the C contract forbids (one handle, two threads): the binding's
    # lock serialises the calls; every row comes out once, in order.
    s, h, sl, valid = noisy_sheet(41, rows=4000, fibers=8)
    recon = flatline.Reconstructor(8, lag_knots=4)
    pulled = []
    lock = threading.Lock()
    done = threading.Event()

    def pusher():
        for start in range(0, len(s), 100):
            recon.push(s[start:start + 100], h[start:start + 100],
                       sl[start:start + 100], valid[start:start + 100])
        done.set()

    def puller():
        while not done.is_set() or recon.ready:
            try:
                part = recon.pull()
            except flatline.StateError:  # before the first push
                continue
            with lock:
                pulled.append(part)

    threads = [threading.Thread(target=pusher), threading.Thread(target=puller)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    recon.end_sheet()
    pulled.append(recon.pull())
    recon.close()
    out_s = np.concatenate([p[0] for p in pulled])
    np.testing.assert_array_equal(out_s, s)
    serial = stream((s, h, sl, valid), lag_knots=4, block=100)
    np.testing.assert_array_equal(bits(np.concatenate([p[1] for p in pulled])), bits(serial[1]))


def simulate(calib, seed, frames):
    """Rows and frames of a noisy simulator, then the frames through an
    extractor: everything a thread of a commissioning script would do."""
    with flatline.SimulatedLine(calib, sim_seed=seed, sim_heave_sigma=2.5,
                                sim_peak_sigma=1 / 16) as sim, \
            flatline.Extractor(calib) as extractor:
        sim.add_defect("centre_buckle", 12.0, 1800.0)
        rows = sim.next_rows(1500)
        images, extracted = [], []
        for _ in range(frames):
            frame = sim.next_frame()
            images.append(frame.image)
            extracted.append(extractor.process(frame.image, frame.encoder_mm).height)
    return rows.height, rows.truth, np.array(images), np.array(extracted)


def test_two_simulators_in_two_threads_match_serial_runs_bitwise():
    from conftest import roi_reference

    calib = roi_reference(fibers=101, pitch=20.0)  # one calibration, shared read-only
    serial = [simulate(calib, seed, 12) for seed in (1, 2)]
    results = [None, None]
    errors = []
    barrier = threading.Barrier(2)

    def work(i):
        try:
            barrier.wait()
            for _ in range(2):
                results[i] = simulate(calib, i + 1, 12)
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    for got, want in zip(results, serial):
        for g, w in zip(got, want):
            np.testing.assert_array_equal(bits(g) if g.dtype == np.float64 else g,
                                          bits(w) if w.dtype == np.float64 else w)
    # The two seeds really differ (so the comparison could fail).
    assert not np.array_equal(serial[0][0], serial[1][0])


def test_the_gil_is_released_while_simulating():
    # As for reconstruct: 5000 rows x 1001 fibers take ~0.5 s in one C call;
    # the main thread must keep running meanwhile.
    window = {}

    def work():
        with flatline.SimulatedLine(sim_peak_sigma=1 / 16) as sim:
            sim.add_defect("centre_buckle", 12.0, 1800.0)
            window["start"] = time.perf_counter()
            sim.next_rows(5000)
            window["end"] = time.perf_counter()

    stamps = []
    worker = threading.Thread(target=work)
    worker.start()
    while worker.is_alive():
        stamps.append(time.perf_counter())
        time.sleep(0.001)
    worker.join()
    duration = window["end"] - window["start"]
    assert duration > 0.05, f"the call took {duration:.3f} s, too short to judge"
    inside = [t for t in stamps if window["start"] + 0.01 < t < window["end"] - 0.01]
    assert len(inside) >= (duration - 0.02) * 1000 / 5, (len(inside), duration)
