#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Writes the seeds of fuzz_record (tests/fuzz/corpus/record; committed,
rerun only to regenerate them):

    PYTHONPATH=build/dev/bindings/python/package \\
        python3 tests/fuzz/make_record_seeds.py tests/fuzz/corpus/record

Blocks come from small recordings the library writes (7, 33 and 64
fibers, three quanta, invalid and NaN samples); height maps are encoded
here from docs/record.md ("Height maps") alone, which also checks that the
document is enough to write one: a small map, a wave, and one with an
escaped Rice value and a NaN."""

import os
import sqlite3
import struct
import sys
import tempfile
import zlib

import numpy as np

import flatline


def _zigzag(v: int) -> int:
    return 2 * v if v >= 0 else -2 * v - 1


def _rice(values, k):
    """The unary and binary streams (least significant bit first) and the
    escapes of docs/record.md, "Rice streams"."""
    unary, binary, escapes = [], [], []
    for v in values:
        q = v >> k
        if q >= 48:
            unary += [0] * 48 + [1]
            binary += [0] * k
            escapes.append(v)
        else:
            unary += [0] * q + [1]
            binary += [(v >> j) & 1 for j in range(k)]

    def pack(bits):
        out = bytearray((len(bits) + 7) // 8)
        for i, bit in enumerate(bits):
            if bit:
                out[i >> 3] |= 1 << (i & 7)
        return bytes(out)

    return pack(unary), pack(binary), escapes


def encode_map(s_mm, z_mm, flags, quantum, k):
    rows, fibers = z_mm.shape
    side_flags = flags & 0x7F
    side_flags[~np.isfinite(z_mm)] |= 0x80
    side = s_mm.astype("<f8").tobytes() + side_flags.astype(np.uint8).tobytes()
    values = []
    for f in range(fibers):
        q_prev = d_prev = 0
        for r in range(rows):
            z = z_mm[r, f]
            q = int(round(z / quantum)) if np.isfinite(z) else q_prev
            d = q - q_prev
            values.append(_zigzag(d - d_prev))
            q_prev, d_prev = q, d
    unary, binary, escapes = _rice(values, k)
    deflated = zlib.compress(side, 6)
    return (struct.pack("<IIId", 0x504D4C46, rows, fibers, quantum)
            + struct.pack("<II", len(side), len(deflated)) + deflated
            + struct.pack("<BIII", k, len(unary), len(binary), len(escapes))
            + unary + binary + b"".join(struct.pack("<Q", e) for e in escapes))


def main() -> int:
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(1)
    with tempfile.TemporaryDirectory() as tmp:
        for fibers, rows, q_exp in ((7, 40, 8), (33, 300, 10), (64, 20, 4)):
            calib = flatline.Calibration.reference(first_row=0, rows=2048, first_x_mm=-500.0,
                                                   pitch_mm=30.0, fibers=fibers)
            path = os.path.join(tmp, f"r{fibers}.flrec")
            with flatline.Recorder(path, calib, record_quantum=2.0 ** -q_exp,
                                   record_block_rows=max(16, rows // 2)) as rec:
                for i in range(rows):
                    h = np.sin(i * 0.05 + np.arange(fibers) * 0.3) \
                        + 0.02 * rng.standard_normal(fibers)
                    valid = np.ones(fibers, bool)
                    valid[i % fibers] = False
                    h[(i * 3) % fibers] = np.nan
                    rec.push_row(i * 1.5, h, 0.001 * rng.standard_normal(fibers), valid)
                rec.sync()
            db = sqlite3.connect(path)
            (payload,) = db.execute("SELECT payload FROM blocks ORDER BY first_row").fetchone()
            db.close()
            # The harness's header: block, fibers - 1, unused, quantum 2^-(4 + byte).
            with open(os.path.join(out, f"block_{fibers}_fibers"), "wb") as f:
                f.write(bytes([0, fibers - 1, 0, q_exp - 4]) + payload)
    rng = np.random.default_rng(2)
    for name, rows, fibers, k in (("map_small", 5, 3, 2), ("map_wave", 40, 9, 3),
                                  ("map_escape", 6, 2, 0)):
        s = np.arange(rows) * 0.5
        z = np.round((np.sin(np.arange(rows)[:, None] * 0.2 + np.arange(fibers))
                      + 0.01 * rng.standard_normal((rows, fibers))) / 0.001) * 0.001
        if name == "map_escape":
            z[3, 1] = 50.0  # a second difference far beyond k = 0's escape
        flags = np.zeros((rows, fibers), np.uint8)
        flags[1, 0] = 8  # off the strip
        z[2, 0] = np.nan
        with open(os.path.join(out, name), "wb") as f:
            f.write(b"\x01" + encode_map(s, z, flags, 0.001, k))
    return 0


if __name__ == "__main__":
    sys.exit(main())
