# SPDX-License-Identifier: Apache-2.0
"""Verdicts from Python: the straightedge deviation against its closed
form, rule files and their errors, a sheet judged by band."""

import math

import numpy as np
import pytest

import flatline

RULES = """{
  "format": "flatline-tolerances", "version": 1, "name": "python test",
  "rules": [
    { "name": "1 m along", "measure": "straightedge_along", "length_mm": 1000,
      "bands": [ { "thickness_mm": [1, 3], "width_mm": [0, 2000], "limit": 3 },
                 { "thickness_mm": [3, 6], "width_mm": [0, 2000], "limit": 5 } ] },
    { "name": "250 mm along", "measure": "straightedge_along", "length_mm": 250,
      "bands": [ { "thickness_mm": [1, 6], "width_mm": [0, 2000], "limit": 0.5 } ] },
    { "name": "I-Units", "measure": "zone_i_units",
      "bands": [ { "thickness_mm": [1, 6], "width_mm": [0, 2000], "limit": 10 } ] }
  ]
}"""


def sine_deviation(amplitude, period, length):
    """A straightedge of length L <= P rests on the points L/2 either side
    of a trough: A (1 - cos(pi L / P)); a longer one bridges two crests: 2 A."""
    if length >= period:
        return 2.0 * amplitude
    return amplitude * (1.0 - math.cos(math.pi * length / period))


@pytest.mark.parametrize("length", [100.0, 250.0, 400.0, 500.0, 1200.0])
def test_sine_closed_form(length):
    p = np.arange(3001, dtype=float)  # a sample every mm: troughs and contacts on samples
    z = 2.0 * np.cos(2 * np.pi * p / 500.0)
    d, at = flatline.straightedge_deviation(p, z, length)
    # cos()'s rounding on heights of 2 mm.
    assert abs(d - sine_deviation(2.0, 500.0, length)) < 1e-12
    assert abs(2.0 * math.cos(2 * np.pi * at / 500.0) + 2.0) < 1e-12  # at a trough


def test_straightedge_bad_input():
    with pytest.raises(flatline.InvalidArgumentError, match="length_mm"):
        flatline.straightedge_deviation([0, 1, 2], [0, 1, 0], 0.0)
    with pytest.raises(flatline.InvalidArgumentError, match="increase strictly"):
        flatline.straightedge_deviation([0, 2, 1], [0, 1, 0], 5.0)
    with pytest.raises(flatline.InvalidArgumentError, match="heights.shape"):
        flatline.straightedge_deviation([0, 1, 2], [0, 1], 5.0)
    with pytest.raises(flatline.NotFoundError, match="fewer than 2"):
        flatline.straightedge_deviation([0, 1, 2], [math.nan, 1, math.nan], 5.0)


def test_rules_read_and_errors(tmp_path):
    rules = flatline.ToleranceRules.loads(RULES)
    assert len(rules) == 3
    assert rules[0] == flatline.ToleranceRule("1 m along", flatline.Measure.STRAIGHTEDGE_ALONG, 1000.0)
    assert rules[-1].measure == flatline.Measure.ZONE_I_UNITS
    assert rules[2].length_mm == 0.0
    path = tmp_path / "rules.json"
    path.write_text(RULES, encoding="utf-8")
    assert [r.name for r in flatline.ToleranceRules.load(path)] == ["1 m along", "250 mm along", "I-Units"]
    with pytest.raises(flatline.FormatError, match=r"'rules\[0\]\.bands\[1\]' \(line 6\) overlaps"):
        flatline.ToleranceRules.loads(RULES.replace("[3, 6]", "[2, 6]"))
    with pytest.raises(flatline.FormatError, match=r"missing field 'rules\[1\]\.length_mm'"):
        flatline.ToleranceRules.loads(RULES.replace('"length_mm": 250,', ""))
    with pytest.raises(flatline.FileError):
        flatline.ToleranceRules.load(tmp_path / "absent.json")
    with pytest.raises(IndexError):
        rules[3]


def test_sheet_judged():
    rows, fibers = 3001, 21
    s = np.arange(rows, dtype=float)
    x = np.linspace(-750.0, 750.0, fibers)
    # A 1.2 mm wave of period 800 mm along every fiber.
    z = np.repeat((1.2 * np.cos(2 * np.pi * s / 800.0))[:, None], fibers, axis=1)
    verdict = flatline.Verdict(flatline.ToleranceRules.loads(RULES))
    verdict.set_measure(flatline.Measure.ZONE_I_UNITS, 12.0, x_mm=-300.0, s_mm=1500.0)
    results = verdict.evaluate(2.0, 1500.0, s, x, z)
    # 1 m bridges the wave: 2.4 mm, limit 3 (band 0).
    assert results[0].state == flatline.VerdictState.PASS
    assert results[0].band == 0
    assert abs(results[0].worst - 2.4) < 1e-12
    assert abs(results[0].margin - 0.6) < 1e-12
    # 250 mm dips into it: 1.2 (1 - cos(pi 250 / 800)) = 0.595 > 0.5.
    assert results[1].state == flatline.VerdictState.FAIL
    assert abs(results[1].worst - sine_deviation(1.2, 800.0, 250.0)) < 1e-12
    assert results[1].margin < 0
    # I-Units 12 > 10 at the position given.
    assert results[2].state == flatline.VerdictState.FAIL
    assert (results[2].x_mm, results[2].s_mm) == (-300.0, 1500.0)
    assert verdict.failed == 2
    # 4 mm thick: band 1 (limit 5); no map: the straightedges are not
    # measured; I-Units no longer given.
    verdict.set_measure(flatline.Measure.ZONE_I_UNITS, None)
    results = verdict.evaluate(4.0, 1500.0)
    assert results[0].state == flatline.VerdictState.NOT_MEASURED
    assert results[0].limit == 5.0 and results[0].band == 1
    assert math.isnan(results[0].worst)
    assert results[2].state == flatline.VerdictState.NOT_MEASURED
    assert verdict.failed == 0
    # Wider than every band.
    assert all(r.state == flatline.VerdictState.NO_BAND for r in verdict.evaluate(2.0, 2500.0))
    # NO_DATA samples are left out: a hole over every trough but one still
    # leaves that one's 2.4 mm.
    flags = np.zeros((rows, fibers), np.uint8)
    hole = z.copy()
    for trough in (1200, 2000, 2800):
        hole[trough - 50:trough + 50, :] = np.nan
        flags[trough - 50:trough + 50, :] = flatline.FLAG_NO_DATA
    results = verdict.evaluate(2.0, 1500.0, s, x, hole, flags)
    assert abs(results[0].worst - 2.4) < 1e-12
    assert abs(results[0].s_mm - 400.0) < 1e-9
    with pytest.raises(flatline.InvalidArgumentError, match="thickness_mm"):
        verdict.evaluate(-1.0, 1500.0, s, x, z)
    with pytest.raises(flatline.InvalidArgumentError, match="x.shape"):
        verdict.evaluate(2.0, 1500.0, s, x[:-1], z)
