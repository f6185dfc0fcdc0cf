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


def _simulated_rows(calib, rows=2400):
    with flatline.SimulatedLine(calib, sim_seed=4, sim_frame_spacing=3.0,
                                sim_heave_sigma=0.3, sim_peak_sigma=1 / 16) as sim:
        sim.add_defect("centre_buckle", 3.0, 900.0)
        return sim.next_rows(rows)


def _run_live(calib, rows, recorder=None, archive=None):
    sheets = []
    with flatline.Gauge(calib, gauge_frame_spacing=2.5, gauge_keep_maps=1,
                        rigid_motion=True, gauge_workers=2) as gauge:
        gauge.set_rules(flatline.ToleranceRules.loads(RULES), thickness_mm=4.0,
                        width_mm="measured")
        if recorder is not None:
            gauge.attach_recorder(recorder)
        if archive is not None:
            gauge.attach_archive(archive)
        gauge.set_coil(flatline.CoilInfo("4711", grade="S355MC", thickness_mm=4.0))
        for cut in (1000.0, 2000.0, 3000.0, 4000.0, 5000.0, 6000.0):
            gauge.cut(cut)
        for r in range(len(rows.s)):
            if r == 1200:
                gauge.note("leveler", "roll 3 +0.2 mm")
            gauge.push_row(rows.encoder_mm[r], rows.height[r], rows.slope[r], rows.valid[r])
            sheets.extend(gauge)
        gauge.flush()
        sheets.extend(gauge)
        if recorder is not None:
            gauge.attach_recorder(None)
        if archive is not None:
            gauge.attach_archive(None)
        last = gauge.coil_info(last=True)
    return sheets, last


RULES = """{ "format": "flatline-tolerances", "version": 1, "name": "py", "rules": [
  { "name": "I-Units", "measure": "zone_i_units",
    "bands": [ { "thickness_mm": [1, 10], "width_mm": [0, 3000], "limit": 8 } ] } ] }"""


def test_recorded_line_replays_bit_for_bit_and_is_archived(tmp_path):
    calib = flatline.Calibration.reference(first_x_mm=-400.0, pitch_mm=20.0, fibers=41)
    rows = _simulated_rows(calib)
    path = tmp_path / "line.flrec"
    with flatline.Recorder(path, calib) as rec, \
            flatline.Archive(tmp_path / "archive.sqlite", line="py") as archive:
        live, last = _run_live(calib, rows, rec, archive)
        archive.flush()
        assert archive.counters()["stored"] == len(live)
    assert len(live) == 7
    assert last == flatline.CoilInfo("4711", grade="S355MC", thickness_mm=4.0)
    assert all(s.coil_info.coil_id == "4711" for s in live)
    assert sum(len(s.notes) for s in live) == 1
    assert [n.kind for s in live for n in s.notes] == ["leveler"]

    with flatline.Recording(path) as rd:
        replay_calib, options = rd.calibration(), rd.options()
    assert options["rigid_motion"] == 1.0
    with flatline.Gauge(replay_calib, **options) as gauge:
        gauge.set_rules(flatline.ToleranceRules.loads(RULES), thickness_mm=4.0,
                        width_mm="measured")
        again = list(gauge.run(flatline.Source.open_recording(path)))
    assert len(again) == len(live)
    for a, b in zip(live, again):
        for key, value in a.values.items():
            assert np.array_equal(value, b.values[key], equal_nan=True), key
        assert b.finished_time >= a.finished_time > 1.6e9
        assert np.array_equal(a.z, b.z, equal_nan=True)  # bit for bit: tolerance 0
        assert a.coil_info == b.coil_info and a.notes == b.notes
        assert [r.worst for r in a.verdict] == [r.worst for r in b.verdict]

    # The archive: one query for the failed sheets of coil 4711.
    db = sqlite3.connect(tmp_path / "archive.sqlite")
    failed = [row[0] for row in db.execute(
        "SELECT sheet_index FROM sheets WHERE coil_id = '4711' AND verdict = 'fail' "
        "ORDER BY sheet_index")]
    assert failed == [s.index for s in live if s.values["verdict"] == 1.0]
    assert db.execute("SELECT count(*) FROM notes WHERE kind = 'leveler'").fetchone()[0] == 1
