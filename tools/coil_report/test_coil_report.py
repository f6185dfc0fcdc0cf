# SPDX-License-Identifier: Apache-2.0
"""The coil report on a short simulated coil: the page links only to files
that exist, holds one zone-profile plot, and its verdict table is, row for
row, what a flatline.Verdict computed here gives; a known defect fails the
rule whose limit is below it and passes the one above it."""

import json
import math
import os
import sys
from html.parser import HTMLParser

import numpy as np
import pytest

import flatline

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import coil_report  # noqa: E402

AMPLITUDE = 2.0  # mm, the centre buckle's amplitude
PERIOD = 800.0  # mm along travel
THICKNESS = 3.0  # mm
# A 1 m straightedge bridges an 800 mm wave: at the centre fiber (x = 0,
# where the buckle's profile cos^2(pi x / W) is 1) it rests on two crests
# and the gap is the full height, 2 A (flatline/verdict.h, "Measures").
DEVIATION = 2 * AMPLITUDE

RULES = {
    "format": "flatline-tolerances", "version": 1, "name": "test rules",
    "rules": [
        {"name": "below the defect", "measure": "straightedge_along", "length_mm": 1000,
         "bands": [{"thickness_mm": [1, 6], "width_mm": [0, 3000], "limit": 0.9 * DEVIATION}]},
        {"name": "above the defect", "measure": "straightedge_along", "length_mm": 1000,
         "bands": [{"thickness_mm": [1, 6], "width_mm": [0, 3000], "limit": 1.1 * DEVIATION}]},
        {"name": "across", "measure": "straightedge_across", "length_mm": 500,
         "bands": [{"thickness_mm": [1, 6], "width_mm": [0, 3000], "limit": 1.0}]},
        {"name": "I-Units", "measure": "zone_i_units",
         "bands": [{"thickness_mm": [1, 6], "width_mm": [0, 3000], "limit": 10}]},
        {"name": "wave height", "measure": "wave_height",
         "bands": [{"thickness_mm": [1, 6], "width_mm": [0, 3000], "limit": 5}]},
        {"name": "bow", "measure": "bow",
         "bands": [{"thickness_mm": [1, 6], "width_mm": [0, 3000], "limit": 1}]},
        # Thicker strip only: this coil is not judged by it (no band).
        {"name": "crossbow, thick strip", "measure": "crossbow",
         "bands": [{"thickness_mm": [10, 20], "width_mm": [0, 3000], "limit": 1}]},
    ],
}


class Page(HTMLParser):
    """The page's links, images and table rows (attributes and cells)."""

    def __init__(self, path):
        super().__init__()
        self.links, self.images, self.rows, self.tags = [], [], [], []
        self._cell = None
        with open(path, encoding="utf-8") as f:
            self.text = f.read()
        self.feed(self.text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        self.tags.append((tag, a))
        if tag == "a" and "href" in a:
            self.links.append(a["href"])
        if tag == "img":
            self.images.append(a["src"])
        if tag == "tr":
            self.rows.append((a, []))
        if tag in ("td", "th"):
            self._cell = [a, ""]
            self.rows[-1][1].append(self._cell)

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell[1] += data


@pytest.fixture(scope="module")
def line():
    # Noise-free: the reconstruction is then within 1 um of the truth.
    coil = coil_report.SimCoil(THICKNESS, 2, (("centre_buckle", AMPLITUDE, PERIOD),))
    return coil_report.simulate_line([coil], sheet_length_mm=1500.0, vibration_mm=0.0,
                                     peak_noise_px=0.0, progress=None)


@pytest.fixture(scope="module")
def report(line, tmp_path_factory):
    out = tmp_path_factory.mktemp("report")
    rules = out / "rules.json"
    rules.write_text(json.dumps(RULES), encoding="utf-8")
    messages = []
    reports = coil_report.write_reports(line.sheets, str(out), str(rules), line.thickness_mm,
                                        line.fiber_x, progress=messages.append)
    return out, rules, reports, messages


def direct_verdicts(line, rules_path):
    """The verdicts, computed here without the tool: the whole-sheet
    measures where the report's README says it puts them."""
    verdict = flatline.Verdict(flatline.ToleranceRules.load(rules_path))
    out = []
    for sheet in line.sheets:
        mid = 0.5 * (sheet.s_start + sheet.s_end)
        zone = int(np.nanargmax(sheet.zones.i_units))
        for measure, value, x in (
                (flatline.Measure.ZONE_I_UNITS, sheet.max_i_units, sheet.zones.centre_x[zone]),
                (flatline.Measure.WAVE_STEEPNESS, sheet.wave_steepness_percent, sheet.wave_x),
                (flatline.Measure.WAVE_HEIGHT, sheet.wave_height, sheet.wave_x),
                (flatline.Measure.BOW, sheet.bow_mm, sheet.strip_centre),
                (flatline.Measure.CROSSBOW, sheet.crossbow_mm, sheet.strip_centre)):
            verdict.set_measure(measure, value, x, mid)
        out.append(verdict.evaluate(THICKNESS, sheet.strip_width, sheet.s, line.fiber_x,
                                    sheet.z, sheet.z_flags))
    return out


def same(a, b):
    # The page writes repr(float): exact, so 1e-12 only absorbs nothing.
    return (math.isnan(a) and math.isnan(b)) or abs(a - b) <= 1e-12


def test_pages_link_only_to_files_beside_them(line, report):
    out, _, reports, messages = report
    assert [r.coil for r in reports] == [1]
    assert len(line.sheets) == 2
    for page_path in (out / "index.html", out / "coil_1" / "index.html"):
        page = Page(page_path)
        assert page.links or page.images
        for target in page.links + page.images:
            assert "://" not in target and not target.startswith("/"), target
            assert (page_path.parent / target).is_file(), target
        # Self-contained: no scripts, no external style sheets or fonts.
        assert not any(tag in ("script", "link", "iframe") for tag, _ in page.tags)
        assert "@import" not in page.text and "url(" not in page.text
    page = Page(out / "coil_1" / "index.html")
    for image in page.images:
        with open(out / "coil_1" / image, "rb") as f:
            assert f.read(8) == b"\x89PNG\r\n\x1a\n", image
    # One zone-profile plot, and a height map per sheet beside the coil's.
    assert [i for i in page.images if "zone" in i] == ["zone_profiles.png"]
    assert "coil_heights.png" in page.images
    assert sorted(link for link in page.links if link.startswith("sheet_")) == sorted(
        f"sheet_{sh.id}_heights.png" for sh in line.sheets)
    # Progress: sheet i of n.
    assert "coil 1: judging sheet 2 of 2" in messages


def test_verdict_table_is_the_verdict(line, report):
    out, rules_path, reports, _ = report
    page = Page(out / "coil_1" / "index.html")
    rows = [(a, cells) for a, cells in page.rows if "verdict" in a.get("class", "")]
    n_rules = len(RULES["rules"])
    assert len(rows) == n_rules * len(line.sheets)
    expected = direct_verdicts(line, rules_path)
    seen = set()
    for attrs, cells in rows:
        sheet_id, k = int(attrs["data-sheet"]), int(attrs["data-rule"])
        seen.add((sheet_id, k))
        i = [sh.id for sh in line.sheets].index(sheet_id)
        want = expected[i][k]
        values = [float(c[0]["data-value"]) for c in cells if "data-value" in c[0]]
        # limit, worst, x, s, margin in the table's column order.
        got = dict(zip(("limit", "worst", "x_mm", "s_mm", "margin"), values))
        for key, value in got.items():
            assert same(value, getattr(want, key)), (sheet_id, k, key, value, want)
        assert len(got) == 5
        state = {flatline.VerdictState.PASS: "pass", flatline.VerdictState.FAIL: "fail",
                 flatline.VerdictState.NO_BAND: "no_band",
                 flatline.VerdictState.NOT_MEASURED: "not_measured",
                 flatline.VerdictState.NOT_JUDGED: "not_judged"}[want.state]
        assert state in attrs["class"].split()
    assert len(seen) == len(rows)

    # The summary's counts per rule, and the coil's on the index page.
    summary = [(a, cells) for a, cells in page.rows if a.get("class") == "rule"]
    assert len(summary) == n_rules
    for attrs, cells in summary:
        k = int(attrs["data-rule"])
        passed, failed = (float(c[0]["data-value"]) for c in cells[3:5])
        assert passed == sum(v[k].state == flatline.VerdictState.PASS for v in expected)
        assert failed == sum(v[k].state == flatline.VerdictState.FAIL for v in expected)
    # A sheet passes only when every rule judged it and passed: the
    # "thick strip" rule has no band for this coil, so no sheet can pass.
    bad = sum(any(r.state == flatline.VerdictState.FAIL for r in v) for v in expected)
    good = sum(all(r.state == flatline.VerdictState.PASS for r in v) for v in expected)
    assert (reports[0].passed, reports[0].failed, reports[0].not_judged) == \
        (good, bad, len(expected) - good - bad)
    index = Page(out / "index.html")
    coil_row = [cells for a, cells in index.rows if cells and cells[0][1] == "coil 1"][0]
    assert [c[1] for c in coil_row[1:]] == [str(len(expected)), str(good), str(bad),
                                             str(len(expected) - good - bad)]


def test_sheets_no_rule_could_judge_are_shown_as_not_judged(line, tmp_path):
    # A rule every sheet passes, and one whose band is for thicker strip:
    # no sheet failed, but none was judged by every rule, so none passed.
    rules = {"format": "flatline-tolerances", "version": 1, "name": "pass + no band",
             "rules": [RULES["rules"][1], RULES["rules"][6]]}
    path = tmp_path / "rules.json"
    path.write_text(json.dumps(rules), encoding="utf-8")
    reports = coil_report.write_reports(line.sheets, str(tmp_path), str(path),
                                        line.thickness_mm, line.fiber_x, progress=None)
    n = len(line.sheets)
    assert (reports[0].passed, reports[0].failed, reports[0].not_judged) == (0, 0, n)
    page = Page(tmp_path / "coil_1" / "index.html")
    assert f"0 of {n} sheets within every rule" in page.text
    assert "not judged: sheets " + ", ".join(str(sh.index) for sh in line.sheets) in page.text
    sheet_rows = [cells for _, cells in page.rows
                  if len(cells) == 11 and cells[8][1] in ("pass", "FAIL", "not judged")]
    assert [cells[8][1] for cells in sheet_rows] == ["not judged"] * n


def test_known_defect_fails_below_and_passes_above(line, report):
    _, _, reports, _ = report
    for results in reports[0].results:
        below, above = results[0], results[1]
        # Noise-free reconstruction (< 1 um) and rows every 3 mm (a crest
        # missed by 1.5 mm lowers it by A (1 - cos(2 pi 1.5 / 800)) = 0.3 um):
        # 0.01 mm is far above both and far below the 10% the limits keep.
        assert below.worst == pytest.approx(DEVIATION, abs=0.01)
        assert abs(below.x_mm) <= 10.0  # the centre fiber (or a neighbour, 10 mm away)
        assert below.state == flatline.VerdictState.FAIL
        assert below.margin < 0
        assert above.state == flatline.VerdictState.PASS
        assert above.worst == below.worst
        assert results[6].state == flatline.VerdictState.NO_BAND


def test_advisor_section(line, report, tmp_path):
    out, rules_path, _, _ = report
    page = Page(out / "coil_1" / "index.html")
    assert "No advisor configured" in page.text
    first, second = line.sheets
    advice = [{"sheet": first.id, "changes": {"entry gap": -0.25, "flight 3": 0.5},
               "confidence": 0.8, "units": {"entry gap": "mm"}},
              {"sheet": second.id, "changes": {"flight 3": 0.125}, "confidence": 0.4,
               "note": "small step"}]
    coil_report.write_reports(line.sheets, str(tmp_path), str(rules_path), THICKNESS,
                              line.fiber_x, advice=advice, progress=None)
    page = Page(tmp_path / "coil_1" / "index.html")
    assert "No advisor configured" not in page.text
    rows = {int(a["data-sheet"]): cells for a, cells in page.rows if a.get("class") == "advice"}
    assert sorted(rows) == [first.id, second.id]
    header = [cells for a, cells in page.rows
              if cells and cells[0][1] == "sheet" and any("confidence" in c[1] for c in cells)][0]
    assert [c[1] for c in header] == ["sheet", "confidence", "entry gap [mm]", "flight 3", "note"]
    assert [float(c[0]["data-value"]) for c in rows[first.id][1:4]] == [0.8, -0.25, 0.5]
    assert float(rows[second.id][3][0]["data-value"]) == 0.125
    assert rows[second.id][2][1] == "–"  # no change given for the entry gap
    with pytest.raises(ValueError, match=r"advice\[0\]\['confidence'\]"):
        coil_report.read_advice([{"sheet": 1, "changes": {"a": 1.0}, "confidence": 1.5}])
    with pytest.raises(ValueError, match=r"advice\[0\]\['changes'\]\['a'\]"):
        coil_report.read_advice([{"sheet": 1, "changes": {"a": "up"}}])
    with pytest.raises(ValueError, match="not among the sheets"):
        coil_report.write_reports(line.sheets, str(tmp_path), str(rules_path), THICKNESS,
                                  line.fiber_x, progress=None,
                                  advice=[{"sheet": 999, "changes": {"a": 1.0}}])


def test_command_line(tmp_path):
    advice = tmp_path / "advice.json"
    advice.write_text(json.dumps([{"sheet": 1, "changes": {"tilt": 0.1}, "confidence": 0.5}]))
    out = tmp_path / "out"
    assert coil_report.main(["--out", str(out), "--coils", "1", "--sheets", "1",
                             "--sheet-length", "1200", "--quiet",
                             "--advice", str(advice)]) == 0
    page = Page(out / "coil_1" / "index.html")
    rows = [a for a, _ in page.rows if "verdict" in a.get("class", "")]
    # The example rule file beside the tool: 7 rules, one sheet.
    assert len(rows) == len(flatline.ToleranceRules.load(coil_report.EXAMPLE_RULES)) == 7
    assert "tilt" in page.text
