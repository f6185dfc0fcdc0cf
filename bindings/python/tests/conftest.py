# SPDX-License-Identifier: Apache-2.0
"""Shared fixtures: reference sheets and a ctypes view of the very libflatline
the extension loaded (for bit-for-bit comparisons with the C API)."""

import ctypes
import os

import numpy as np
import pytest

import flatline

LASER_SPACING = 100.0  # mm, the library default and the reference sensor's


def measure(z_of_s, s, spacing=LASER_SPACING):
    """What the two lasers report for a surface z(s): the mean of the heights
    and the secant slope over `spacing`, at each row position s."""
    behind, ahead = z_of_s(s - spacing / 2), z_of_s(s + spacing / 2)
    return (behind + ahead) / 2, (ahead - behind) / spacing


def sine_sheet(fibers=4, length=9000.0, step=3.0, amplitude=12.0, period=1800.0):
    """The reference sheet along travel: z = A sin(2 pi s / P), same for every
    fiber but shifted by 5 mm per fiber so fibers differ. Returns
    (s, height, slope, z_true), arrays (N,) and (N, K)."""
    s = np.arange(0.0, length, step)
    shift = 5.0 * np.arange(fibers)

    def z(pos):
        return amplitude * np.sin(2 * np.pi * (pos[:, None] + shift) / period)

    height, slope = measure(z, s)
    return s, height, slope, z(s)


def noisy_sheet(seed, rows=1500, fibers=6, step=3.0):
    """A sheet with vibration (2.5 mm common per row) and peak noise, jittered
    row positions and some invalid samples: realistic input for comparisons."""
    rng = np.random.default_rng(seed)
    s = np.cumsum(rng.uniform(0.8 * step, 1.2 * step, rows))
    x = np.linspace(0, 1500, fibers)
    z = lambda pos: 12 * np.sin(2 * np.pi * pos[:, None] / 1800) * np.cos(2 * np.pi * x / 1500)
    height, slope = measure(z, s)
    height = height + rng.normal(0, 2.5, (rows, 1)) + rng.normal(0, 0.05, (rows, fibers))
    slope = slope + rng.normal(0, 0.05 * np.sqrt(2) / LASER_SPACING, (rows, fibers))
    valid = rng.random((rows, fibers)) > 0.02
    return s, height, slope, valid


def loaded_library_path():
    """The libflatline shared object mapped into this process by the
    extension (so ctypes calls the same code, not another copy)."""
    with open("/proc/self/maps") as maps:
        for line in maps:
            path = line.split()[-1]
            if "libflatline.so" in path:
                return path
    return os.environ.get("FLATLINE_LIBRARY")


class CLib:
    """Direct ctypes access to the C API, the reference side of round trips."""

    def __init__(self, path):
        self.lib = lib = ctypes.CDLL(path)
        P = ctypes.c_void_p
        dp = ctypes.POINTER(ctypes.c_double)
        up = ctypes.POINTER(ctypes.c_uint8)
        sz = ctypes.c_size_t
        lib.flt_options_create.argtypes = [ctypes.POINTER(P)]
        lib.flt_options_set.argtypes = [P, ctypes.c_int, ctypes.c_double]
        lib.flt_options_destroy.argtypes = [P]
        lib.flt_option_find.argtypes = [ctypes.c_char_p, ctypes.POINTER(ctypes.c_int)]
        lib.flt_reconstruct.argtypes = [P, sz, sz, dp, dp, dp, up, dp, up]
        lib.flt_recon_create.argtypes = [sz, P, ctypes.POINTER(P)]
        lib.flt_recon_destroy.argtypes = [P]
        lib.flt_recon_push.argtypes = [P, sz, sz, dp, dp, dp, up]
        lib.flt_recon_pull.argtypes = [P, sz, sz, dp, dp, up, ctypes.POINTER(sz)]
        lib.flt_recon_ready.argtypes = [P, ctypes.POINTER(sz)]
        lib.flt_recon_end_sheet.argtypes = [P]
        lib.flt_last_error_message.restype = ctypes.c_char_p
        u32 = ctypes.c_uint32
        PP = ctypes.POINTER(P)
        lib.flt_calib_load_text.argtypes = [ctypes.c_char_p, sz, PP]
        lib.flt_calib_destroy.argtypes = [P]
        lib.flt_calib_image_to_plane.argtypes = [P, ctypes.c_uint, sz, dp, dp]
        lib.flt_calib_plane_to_image.argtypes = [P, ctypes.c_uint, sz, dp, dp]
        lib.flt_calib_undistort.argtypes = [P, sz, dp, dp]
        lib.flt_sim_create.argtypes = [P, P, PP]
        lib.flt_sim_destroy.argtypes = [P]
        lib.flt_sim_add_defect.argtypes = [P, ctypes.c_int, ctypes.c_double, ctypes.c_double]
        lib.flt_sim_next_rows.argtypes = [P, sz, sz, dp, dp, dp, dp, up, dp]
        lib.flt_sim_next_frame.argtypes = [P, P, sz, sz, dp, sz, dp, dp, sz]
        lib.flt_extractor_create.argtypes = [P, P, PP]
        lib.flt_extractor_destroy.argtypes = [P]
        lib.flt_sim_fibers.argtypes = [P, ctypes.POINTER(sz)]
        lib.flt_extractor_fibers.argtypes = [P, ctypes.POINTER(sz)]
        lib.flt_extractor_process.argtypes = [P, P, ctypes.c_int, u32, u32, sz,
                                              ctypes.c_double, sz, dp, dp, dp, up]

    def _check(self, status):
        if status != 0:
            raise AssertionError(self.lib.flt_last_error_message().decode())

    @staticmethod
    def _ptr(array, ctype):
        return array.ctypes.data_as(ctypes.POINTER(ctype)) if array is not None else None

    def options(self, **kwargs):
        bag = ctypes.c_void_p()
        self._check(self.lib.flt_options_create(ctypes.byref(bag)))
        for name, value in kwargs.items():
            key = ctypes.c_int()
            self._check(self.lib.flt_option_find(name.encode(), ctypes.byref(key)))
            self._check(self.lib.flt_options_set(bag, key.value, float(value)))
        return bag

    def reconstruct(self, s, height, slope, valid=None, **options):
        rows, fibers = height.shape
        s, height, slope = (np.ascontiguousarray(a, np.float64) for a in (s, height, slope))
        mask = None if valid is None else np.ascontiguousarray(valid, np.uint8)
        z = np.empty((rows, fibers))
        flags = np.empty((rows, fibers), np.uint8)
        bag = self.options(**options)
        try:
            self._check(self.lib.flt_reconstruct(
                bag, rows, fibers, self._ptr(s, ctypes.c_double),
                self._ptr(height, ctypes.c_double), self._ptr(slope, ctypes.c_double),
                self._ptr(mask, ctypes.c_uint8), self._ptr(z, ctypes.c_double),
                self._ptr(flags, ctypes.c_uint8)))
        finally:
            self.lib.flt_options_destroy(bag)
        return z, flags

    def stream(self, blocks, fibers, **options):
        """Pushes (s, height, slope, valid) blocks, pulling after each, then
        ends the sheet and pulls the rest. Returns (s, z, flags)."""
        bag = self.options(**options)
        handle = ctypes.c_void_p()
        self._check(self.lib.flt_recon_create(fibers, bag, ctypes.byref(handle)))
        self.lib.flt_options_destroy(bag)
        out_s, out_z, out_f = [], [], []

        def pull():
            ready = ctypes.c_size_t()
            self._check(self.lib.flt_recon_ready(handle, ctypes.byref(ready)))
            n = ready.value
            s = np.empty(n)
            z = np.empty((n, fibers))
            f = np.empty((n, fibers), np.uint8)
            got = ctypes.c_size_t()
            self._check(self.lib.flt_recon_pull(
                handle, n, fibers, self._ptr(s, ctypes.c_double),
                self._ptr(z, ctypes.c_double), self._ptr(f, ctypes.c_uint8),
                ctypes.byref(got)))
            assert got.value == n
            out_s.append(s), out_z.append(z), out_f.append(f)

        try:
            for s, height, slope, valid in blocks:
                rows = len(s)
                s, height, slope = (np.ascontiguousarray(a, np.float64) for a in (s, height, slope))
                mask = None if valid is None else np.ascontiguousarray(valid, np.uint8)
                self._check(self.lib.flt_recon_push(
                    handle, rows, fibers, self._ptr(s, ctypes.c_double),
                    self._ptr(height, ctypes.c_double), self._ptr(slope, ctypes.c_double),
                    self._ptr(mask, ctypes.c_uint8)))
                pull()
            self._check(self.lib.flt_recon_end_sheet(handle))
            pull()
        finally:
            self.lib.flt_recon_destroy(handle)
        return np.concatenate(out_s), np.concatenate(out_z), np.concatenate(out_f)


    # -- calibration, simulator, extractor: each call builds its handles from
    # -- the saved text of a flatline.Calibration, so both sides use one model.

    def _calib(self, text):
        handle = ctypes.c_void_p()
        raw = text.encode()
        self._check(self.lib.flt_calib_load_text(raw, len(raw), ctypes.byref(handle)))
        return handle

    def map_points(self, text, which, laser, points):
        """flt_calib_<which> over (N, 2) points; which is image_to_plane,
        plane_to_image or undistort."""
        calib = self._calib(text)
        points = np.ascontiguousarray(points, np.float64)
        out = np.empty_like(points)
        try:
            args = [self._ptr(points, ctypes.c_double), self._ptr(out, ctypes.c_double)]
            if which == "undistort":
                self._check(self.lib.flt_calib_undistort(calib, len(points), *args))
            else:
                function = getattr(self.lib, f"flt_calib_{which}")
                self._check(function(calib, laser, len(points), *args))
        finally:
            self.lib.flt_calib_destroy(calib)
        return out

    def sim_rows(self, text, defects, blocks, **options):
        """A simulator of that calibration with `defects` [(kind, amplitude,
        period)]; next_rows for each block size in `blocks`, concatenated:
        (encoder, s, height, slope, valid, truth)."""
        calib = self._calib(text)
        bag = self.options(**options)
        sim = ctypes.c_void_p()
        try:
            self._check(self.lib.flt_sim_create(calib, bag, ctypes.byref(sim)))
        finally:
            self.lib.flt_options_destroy(bag)
            self.lib.flt_calib_destroy(calib)
        parts = []
        try:
            for kind, amplitude, period in defects:
                self._check(self.lib.flt_sim_add_defect(sim, int(kind), amplitude, period))
            fibers = ctypes.c_size_t()
            self._check(self.lib.flt_sim_fibers(sim, ctypes.byref(fibers)))
            k = fibers.value
            for n in blocks:
                arrays = (np.empty(n), np.empty(n), np.empty((n, k)), np.empty((n, k)),
                          np.empty((n, k), np.uint8), np.empty((n, k)))
                ptrs = [self._ptr(a, ctypes.c_uint8 if a.dtype == np.uint8 else ctypes.c_double)
                        for a in arrays]
                self._check(self.lib.flt_sim_next_rows(sim, n, k, *ptrs))
                parts.append(arrays)
        finally:
            self.lib.flt_sim_destroy(sim)
        return tuple(np.concatenate(p) for p in zip(*parts))

    def extract(self, text, frames, encoders, pixel_format=8, **options):
        """flt_extractor_process over C-contiguous frames: (heights, slopes,
        valids, s) stacked."""
        calib = self._calib(text)
        bag = self.options(**options)
        extractor = ctypes.c_void_p()
        try:
            self._check(self.lib.flt_extractor_create(calib, bag, ctypes.byref(extractor)))
        finally:
            self.lib.flt_options_destroy(bag)
            self.lib.flt_calib_destroy(calib)
        out = []
        try:
            count = ctypes.c_size_t()
            self._check(self.lib.flt_extractor_fibers(extractor, ctypes.byref(count)))
            fibers = count.value
            for frame, encoder in zip(frames, encoders):
                frame = np.ascontiguousarray(frame)
                height, width = frame.shape
                h, g, v, s = np.empty(fibers), np.empty(fibers), np.empty(fibers, np.uint8), \
                    ctypes.c_double()
                self._check(self.lib.flt_extractor_process(
                    extractor, frame.ctypes.data, pixel_format, width, height,
                    frame.strides[0], encoder, fibers, ctypes.byref(s),
                    self._ptr(h, ctypes.c_double), self._ptr(g, ctypes.c_double),
                    self._ptr(v, ctypes.c_uint8)))
                out.append((h, g, v, s.value))
        finally:
            self.lib.flt_extractor_destroy(extractor)
        return tuple(np.array(p) for p in zip(*out))


@pytest.fixture(scope="session")
def clib():
    path = loaded_library_path()
    assert path, "libflatline is not mapped into the process"
    return CLib(path)


def bits(array):
    """The raw bits of a float64 array, so NaNs compare equal to themselves
    and -0.0 differs from 0.0: equality of these is bit-for-bit equality."""
    return np.ascontiguousarray(array, np.float64).view(np.uint64)


def rss_bytes():
    """Resident set size of this process, from /proc/self/statm."""
    with open("/proc/self/statm") as statm:
        resident_pages = int(statm.read().split()[1])
    return resident_pages * os.sysconf("SC_PAGE_SIZE")


REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
CALIBRATION_DATA = os.path.join(REPO, "examples", "calibrate", "data")


def read_png(path):
    """An 8-bit grey PNG as written by examples/calibrate/make_dataset.py
    (filter "Sub" on every row), without an imaging library."""
    import struct
    import zlib

    with open(path, "rb") as f:
        data = f.read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", path
    pos, idat = 8, b""
    while pos < len(data):
        length, tag = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        pos += 12 + length
        if tag == b"IHDR":
            width, height, depth, colour = struct.unpack(">IIBB", body[:10])
        elif tag == b"IDAT":
            idat += body
    assert depth == 8 and colour == 0, path
    raw = np.frombuffer(zlib.decompress(idat), np.uint8).reshape(height, width + 1)
    assert (raw[:, 0] == 1).all(), "only the Sub filter is decoded"
    return np.cumsum(raw[:, 1:], axis=1, dtype=np.uint8)  # Sub: running sum mod 256


def roi_reference(fibers=101, pitch=20.0):
    """The reference sensor's rows 892..1147 (both lines and +-50 mm of
    height fit; an eighth of the full frame to render), fibers centred on
    x = 0: what tests/c/test_extractor.c uses."""
    return flatline.Calibration.reference(892, 256, -0.5 * pitch * (fibers - 1), pitch,
                                          fibers)
