#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Reads a libflatline recording with Python's standard library and numpy
alone (no libflatline): the file format of docs/record.md, decoded here in
one page so that a support engineer can read a customer's file anywhere.

    python3 read_recording.py line.flrec            # a summary
    python3 read_recording.py line.flrec --csv rows.csv --first 0 --count 100

As a module: ``read(path)`` returns a Recording (meta, events, coils) and
``rows(recording)`` yields each block's rows as numpy arrays. Every block's
CRC-32 is checked (zlib.crc32) before it is decoded.
"""

from __future__ import annotations

import argparse
import sqlite3
import struct
import sys
import zlib
from dataclasses import dataclass, field
from typing import Dict, Iterator, List, NamedTuple

import numpy as np

APPLICATION_ID = 0x464C5452  # "FLTR"
BLOCK_MAGIC = 0x42524C46  # "FLRB"
RICE_ESCAPE = 48


class Block(NamedTuple):
    """One block's rows (docs/record.md, "Block payload")."""

    first_row: int
    encoder_mm: np.ndarray  # (R,)
    time_ns: np.ndarray  # (R,) int64, UTC
    left_mm: np.ndarray  # (R,) strip edges, sensor x (NaN: not seen)
    right_mm: np.ndarray  # (R,)
    saturated: np.ndarray  # (R,) uint32
    peaks: np.ndarray  # (R,)
    skipped_stop: np.ndarray  # (R,) frames skipped at a line stop before the row
    skipped_reversal: np.ndarray  # (R,)
    dropped: np.ndarray  # (R,) frames dropped at a full queue before it
    missing: np.ndarray  # (R,) frames the encoder says never came
    row_flags: np.ndarray  # (R,) uint8: 1 new strip, 2 from a frame, 4 extractor error
    strip_flags: np.ndarray  # (R,) uint8 (flatline/extractor.h FLT_STRIP_*)
    flags: np.ndarray  # (R, K) uint8: 0 valid, 1 invalid input, 8 off the strip
    valid: np.ndarray  # (R, K) bool: the extractor's validity
    z_behind: np.ndarray  # (R, K) mm: the laser reading the smaller s (NaN where flags != 0)
    z_ahead: np.ndarray  # (R, K) mm
    height: np.ndarray  # (R, K) mm: (z_behind + z_ahead) / 2
    slope: np.ndarray  # (R, K) mm/mm: (z_ahead - z_behind) / laser spacing


@dataclass
class Recording:
    path: str
    meta: Dict[str, str]
    fibers: int
    quantum_mm: float
    laser_spacing_mm: float
    gauge_options: Dict[str, float]
    events: List[dict] = field(default_factory=list)


def _rice(payload: bytes, offset: int, n: int, k: int, unary_bytes: int, binary_bytes: int,
          escapes: int) -> "tuple[np.ndarray, int]":
    """n Rice-coded values: the unary stream's set bits end the values, the
    binary stream holds k bits per value (both least significant bit first)."""
    unary = np.frombuffer(payload, np.uint8, unary_bytes, offset)
    offset += unary_bytes
    binary = np.frombuffer(payload, np.uint8, binary_bytes, offset)
    offset += binary_bytes
    escaped = np.frombuffer(payload, "<u8", escapes, offset)
    offset += 8 * escapes
    ones = np.flatnonzero(np.unpackbits(unary, bitorder="little"))[:n]
    if len(ones) != n:
        raise ValueError("the unary stream ends early")
    q = np.diff(ones, prepend=-1) - 1
    u = q.astype(np.uint64) << np.uint64(k)
    if k:
        bits = np.unpackbits(binary, bitorder="little")[: n * k].reshape(n, k)
        weights = np.uint64(1) << np.arange(k, dtype=np.uint64)
        u |= (bits.astype(np.uint64) * weights).sum(axis=1, dtype=np.uint64)
    esc = q == RICE_ESCAPE
    if esc.sum() != escapes:
        raise ValueError("the escapes do not match")
    u[esc] = escaped
    return u, offset


def _unzigzag(u: np.ndarray) -> np.ndarray:
    return (u >> np.uint64(1)).astype(np.int64) ^ -(u & np.uint64(1)).astype(np.int64)


def decode_block(payload: bytes, first_row: int, fibers: int, quantum: float,
                 spacing: float) -> Block:
    magic, rows, k_fibers = struct.unpack_from("<III", payload, 0)
    (q_file,) = struct.unpack_from("<d", payload, 12)
    if magic != BLOCK_MAGIC or k_fibers != fibers or q_file != quantum:
        raise ValueError("not a block of this recording")
    side_bytes, deflated = struct.unpack_from("<II", payload, 20)
    side = zlib.decompress(payload[28:28 + deflated])
    if len(side) != side_bytes:
        raise ValueError("side data of the wrong size")
    offset = 28 + deflated
    R, K = rows, fibers
    at = 0

    def take(dtype: str, count: int) -> np.ndarray:
        nonlocal at
        a = np.frombuffer(side, dtype, count, at)
        at += a.nbytes
        return a

    encoder = take("<f8", R)
    time_ns = take("<i8", R)
    left, right = take("<f8", R), take("<f8", R)
    counters = [take("<u4", R) for _ in range(6)]
    row_flags, strip_flags = take("u1", R), take("u1", R)
    state = take("u1", R * K).reshape(R, K)
    flags = state & 0x0F
    used = (flags == 0).ravel()
    lasers = []
    for _ in range(2):
        k = payload[offset]
        n, ub, bb, ne = struct.unpack_from("<IIII", payload, offset + 1)
        offset += 17
        u, offset = _rice(payload, offset, n, k, ub, bb, ne)
        q = np.cumsum(_unzigzag(u))  # each used sample predicted by the one before
        z = np.full(R * K, np.nan)
        z[used] = q * quantum
        lasers.append(z.reshape(R, K))
    zb, za = lasers
    return Block(first_row, encoder, time_ns, left, right, *counters, row_flags, strip_flags,
                 flags, (state & 0x80) != 0, zb, za, (zb + za) * 0.5, (za - zb) / spacing)


def read(path: str) -> Recording:
    db = sqlite3.connect(path)
    try:
        if db.execute("PRAGMA application_id").fetchone()[0] != APPLICATION_ID:
            raise ValueError(f"{path} is no flatline recording")
        version = db.execute("PRAGMA user_version").fetchone()[0]
        if version != 1:
            raise ValueError(f"{path}: format version {version} (this reader knows 1)")
        meta = dict(db.execute("SELECT key, value FROM meta"))
        options = {name: value for name, value in
                   db.execute("SELECT name, value FROM gauge_options")}
        rec = Recording(path, meta, int(meta["fibers"]), float(meta["quantum_mm"]),
                        float(meta["laser_spacing_mm"]), options)
        for event, before, kind, encoder_mm, count in db.execute(
                "SELECT event, before_row, kind, encoder_mm, count FROM events ORDER BY event"):
            e = {"before_row": before, "kind": kind, "encoder_mm": encoder_mm, "count": count}
            if kind == "coil":
                row = db.execute("SELECT coil_id, order_no, heat, grade, customer, "
                                 "nominal_thickness_mm, nominal_width_mm FROM coils WHERE "
                                 "event = ?", (event,)).fetchone()
                e["coil"] = dict(zip(("coil_id", "order", "heat", "grade", "customer",
                                      "thickness_mm", "width_mm"), row))
                e["coil"]["extras"] = dict(db.execute(
                    "SELECT key, value FROM coil_extras WHERE event = ? ORDER BY position",
                    (event,)))
            rec.events.append(e)
        return rec
    finally:
        db.close()


def rows(rec: Recording) -> Iterator[Block]:
    db = sqlite3.connect(rec.path)
    try:
        for block, first_row, codec, crc, payload in db.execute(
                "SELECT block, first_row, codec, crc32, payload FROM blocks ORDER BY first_row"):
            if codec != 1:
                raise ValueError(f"block {block}: codec {codec} unknown")
            if zlib.crc32(payload) != crc:
                raise ValueError(f"block {block}: its CRC-32 does not match")
            yield decode_block(payload, first_row, rec.fibers, rec.quantum_mm,
                               rec.laser_spacing_mm)
    finally:
        db.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("recording")
    parser.add_argument("--csv", help="write rows (encoder_mm and heights) as CSV")
    parser.add_argument("--first", type=int, default=0)
    parser.add_argument("--count", type=int, default=100)
    args = parser.parse_args()
    rec = read(args.recording)
    total = 0
    out = open(args.csv, "w") if args.csv else None
    for block in rows(rec):
        if out:
            for i in range(len(block.encoder_mm)):
                r = block.first_row + i
                if args.first <= r < args.first + args.count:
                    out.write(",".join([repr(float(block.encoder_mm[i]))] +
                                       [repr(float(v)) for v in block.height[i]]) + "\n")
        total += len(block.encoder_mm)
    if out:
        out.close()
    cuts = sum(1 for e in rec.events if e["kind"] == "cut")
    coils = [e["coil"]["coil_id"] for e in rec.events if e["kind"] == "coil"]
    print(f"{args.recording}: {total} rows x {rec.fibers} fibers, quantum "
          f"{rec.quantum_mm} mm, {cuts} cuts, coils {coils}, library "
          f"{rec.meta.get('library', '?')}; every block's CRC-32 checked")
    return 0


if __name__ == "__main__":
    sys.exit(main())
