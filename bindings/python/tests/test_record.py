# SPDX-License-Identifier: Apache-2.0
"""The quality record from Python: coil identities, a recording written and
read back (through libflatline and through examples/python/read_recording.py,
which uses only the standard library and numpy: the two agree bit for bit),
and the archive's life cycle."""

import importlib.util
import math
import os
import pathlib
import sqlite3
import sys

import numpy as np
import pytest

import flatline

REPO = pathlib.Path(__file__).resolve().parents[3]


def _reader():
    spec = importlib.util.spec_from_file_location(
        "read_recording", REPO / "examples" / "python" / "read_recording.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def _calib(fibers=32):
    return flatline.Calibration.reference(first_row=0, rows=2048, first_x_mm=-500.0,
                                          pitch_mm=30.0, fibers=fibers)


def test_coil_info_round_trip_and_checks():
    coil = flatline.CoilInfo("4711", grade="S355MC", heat="H 88", thickness_mm=4.0,
                             width_mm=1500.0, extras={"line": "CTL 2 \"Süd\""})
    back = flatline.CoilInfo._from_handle(coil._handle())
    assert back == coil
    with pytest.raises(flatline.InvalidArgumentError, match="coil_id"):
        flatline.CoilInfo("")._handle()
    with pytest.raises(flatline.InvalidArgumentError, match="control"):
        flatline.CoilInfo("a", grade="x\ny")._handle()
    with pytest.raises(flatline.InvalidArgumentError, match="thickness"):
        flatline.CoilInfo("a", thickness_mm=-1)._handle()
    with pytest.raises(flatline.InvalidArgumentError, match="key"):
        flatline.CoilInfo("a", extras={"bad key": "v"})._handle()


def test_recording_written_and_read_two_ways(tmp_path):
    calib = _calib()
    path = tmp_path / "r.flrec"
    rng = np.random.default_rng(3)
    rows = 700
    heights = 2.0 * np.sin(np.arange(rows)[:, None] * 0.01 + np.arange(32) * 0.1) \
        + 0.05 * rng.standard_normal((rows, 32))
    slopes = 0.001 * rng.standard_normal((rows, 32))
    valid = np.ones((rows, 32), dtype=bool)
    valid[::7, :3] = False
    with flatline.Recorder(path, calib, record_block_rows=64) as rec:
        rec.set_coil(flatline.CoilInfo("C-1", grade="DC01", thickness_mm=2.0))
        for r in range(rows):
            if r == 300:
                rec.cut(300.0)
            rec.push_row(float(r), heights[r], slopes[r], valid[r])
        rec.sync()
        counters = rec.counters()
        assert counters["rows_stored"] == rows and counters["rows_lost"] == 0
        # Bytes per sample of this synthetic noise (0.05 mm): both lasers
        # and the state in well under 4 bytes (2 x 16 bits raw).
        assert counters["bytes"] / counters["samples"] < 3.0
    with pytest.raises(flatline.FileError, match="exists"):
        flatline.Recorder(path, calib)

    with flatline.Recording(path) as rd:
        assert rd.rows == rows and rd.fibers == 32 and rd.rows_lost == 0
        assert rd.quantum_mm == 2.0 ** -8
        rd.verify()
        got = rd.read_rows()
        assert got.height.shape == (rows, 32)
        # Quantization: each laser within half a quantum of what was pushed.
        spacing = calib.laser_spacing
        zb = heights - slopes * spacing / 2
        err = np.nanmax(np.abs((got.height - got.slope * spacing / 2) - zb)[valid])
        assert err <= rd.quantum_mm / 2 + 1e-9
        assert np.array_equal(np.isnan(got.height), ~valid)
        assert np.array_equal(got.encoder_mm, np.arange(rows, dtype=float))

    # The same rows without libflatline: bit for bit.
    reader = _reader()
    meta = reader.read(str(path))
    assert meta.fibers == 32
    assert [e["kind"] for e in meta.events] == ["coil", "cut"]
    assert meta.events[0]["coil"]["coil_id"] == "C-1"
    assert meta.events[1]["before_row"] == 300
    blocks = list(reader.rows(meta))
    h = np.concatenate([b.height for b in blocks])
    s = np.concatenate([b.slope for b in blocks])
    assert np.array_equal(h, got.height, equal_nan=True)
    assert np.array_equal(s, got.slope, equal_nan=True)


def test_recording_read_by_the_standalone_reader_finds_damage(tmp_path):
    path = tmp_path / "d.flrec"
    with flatline.Recorder(path, _calib(), record_block_rows=16) as rec:
        for r in range(64):
            rec.push_row(float(r), np.zeros(32), np.zeros(32))
    db = sqlite3.connect(path)
    payload = bytearray(db.execute("SELECT payload FROM blocks WHERE block = 2").fetchone()[0])
    payload[40] ^= 0xFF
    db.execute("UPDATE blocks SET payload = ? WHERE block = 2", (bytes(payload),))
    db.commit()
    db.close()
    reader = _reader()
    with pytest.raises(ValueError, match="CRC"):
        list(reader.rows(reader.read(str(path))))
    with flatline.Recording(path) as rd:
        with pytest.raises(flatline.FormatError, match="block 2"):
            rd.verify()


def test_archive_opens_and_counts(tmp_path):
    with flatline.Archive(tmp_path / "a.sqlite", line="CTL 2", archive_retry_interval=50) as ar:
        assert ar.backend == "sqlite"
        ar.flush(1000)
        assert ar.prune() == 0
        assert ar.counters()["stored"] == 0
    with pytest.raises(TypeError, match="record_quantum"):
        flatline.Archive(tmp_path / "b.sqlite", record_quantum=0.001)
    db = sqlite3.connect(tmp_path / "a.sqlite")
    assert dict(db.execute("SELECT key, value FROM archive_meta")) == {
        "format": "flatline-archive", "version": "1"}
