# SPDX-License-Identifier: Apache-2.0
"""The coil report from the archive: a short simulated coil archived by the
gauge; the page shows its identity, the gauge's verdicts exactly as the
gauge gave them (never computed again), the run chart, the disposition and
sign-off; the archived maps decode to the gauge's within half the map's
quantum; a 30-sheet coil printed by headless Chromium keeps every sheet's
row on one page and repeats the table's header on every page it continues
on; the same coil read from PostgreSQL gives the same page."""

import json
import math
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser

import numpy as np
import pytest

import flatline

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import coil_report  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
RULES = os.path.join(HERE, "example_rules.json")
PG_CLUSTER = os.path.join(HERE, "..", "..", "tests", "postgres", "pg_cluster.sh")
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


class Page(HTMLParser):
    """The page's images and table rows (per table id: the cells' text)."""

    def __init__(self, path):
        super().__init__()
        self.images, self.tables = [], {}
        self._table, self._row, self._cell = None, None, None
        with open(path, encoding="utf-8") as f:
            self.text = f.read()
        self.feed(self.text)

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a["src"])
        elif tag == "table":
            self._table = a.get("id", "")
            self.tables[self._table] = []
        elif tag == "tr" and self._table is not None:
            self._row = []
        elif tag in ("td", "th") and self._row is not None:
            self._cell = ""

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self._cell is not None:
            self._row.append(re.sub(r"[a-z]{2}\d+[az]", "", self._cell).strip())
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._table].append(self._row)
            self._row = None
        elif tag == "table":
            self._table = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell += data


def one_coil(sheets, sheet_length=1500.0):
    c = coil_report.DEFAULT_COILS[0]
    return [coil_report.SimCoil(c.coil, sheets, c.defects, c.leveler_change)]


@pytest.fixture(scope="module")
def archived(tmp_path_factory):
    """A coil of 3 sheets (1.5 m each) archived by the gauge."""
    folder = tmp_path_factory.mktemp("archive")
    path = str(folder / "archive.sqlite")
    sheets = coil_report.simulate_line(path, RULES, one_coil(3), sheet_length_mm=1500.0,
                                       progress=None)
    return path, sheets


def test_page_holds_the_gauges_verdicts(archived, tmp_path):
    path, sheets = archived
    assert len(sheets) == 3
    reports = coil_report.write_reports(path, str(tmp_path), progress=None)
    assert len(reports) == 1
    r = reports[0]
    page = Page(r.path)
    # The identity at the top.
    identity = {row[0]: row[1] for row in page.tables["identity"]}
    assert identity["coil id"] == "SIM-4711" and identity["grade"] == "S355MC"
    assert identity["customer"] == "Acme Trailers" and identity["line"] == "CTL 2"
    # Every image exists; the run chart is among them.
    for src in page.images:
        assert os.path.getsize(os.path.join(os.path.dirname(r.path), src)) > 1000
    assert "run_chart.png" in page.images
    # The counts are the gauge's own verdicts.
    verdicts = [s.values["verdict"] for s in sheets]
    assert r.passed == sum(v == float(flatline.VerdictState.PASS) for v in verdicts)
    assert r.failed == sum(v == float(flatline.VerdictState.FAIL) for v in verdicts)
    # The CSV's worst values are the gauge's, to the last bit.
    csv_path = os.path.join(os.path.dirname(r.path), "verdicts.csv")
    import csv
    with open(csv_path, encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    got = {(int(x["sheet_in_coil"]), x["rule"]): float(x["worst"]) for x in rows}
    for s in sheets:
        for res in s.verdict:
            want = res.worst
            have = got[(s.index, res.rule.name)]
            assert (math.isnan(want) and math.isnan(have)) or want == have
    # One row per sheet, the disposition per run of verdicts, the sign-off.
    assert len(page.tables["sheets"]) == 1 + 3
    assert page.tables["disposition-table"][1][0] in ("1", "1–2", "1–3")
    assert [row[0] for row in page.tables["sign-off"][1:]] == ["quality engineer", "production"]
    # The leveler change noted in the middle of the coil is in a sheet's notes.
    notes = [row[-1] for row in page.tables["sheets"][1:]]
    assert sum("leveler" in n for n in notes) == 1


def test_archived_maps_are_the_gauges(archived):
    path, sheets = archived
    coil = coil_report.read_coil(path, "SIM-4711")
    assert [s.index for s in coil.sheets] == [1, 2, 3]
    for mine, gauges in zip(coil.sheets, sheets):
        assert mine.z.shape == gauges.z.shape
        finite = np.isfinite(gauges.z)
        assert np.array_equal(np.isfinite(mine.z), finite)
        # Quantized to 0.001 mm: within half of it (and a rounding ulp).
        assert np.max(np.abs(mine.z[finite] - gauges.z[finite])) <= 0.0005 + 1e-12
        assert np.array_equal(mine.s, gauges.s)


def _pdf_pages(pdf):
    info = subprocess.run(["pdfinfo", pdf], capture_output=True, text=True, check=True).stdout
    return int(re.search(r"Pages:\s+(\d+)", info).group(1))


def _page_text(pdf, page):
    return subprocess.run(["pdftotext", "-f", str(page), "-l", str(page), "-layout", pdf, "-"],
                          capture_output=True, text=True, check=True).stdout


@pytest.mark.skipif(CHROMIUM is None or shutil.which("pdftotext") is None,
                    reason="needs Debian's chromium and poppler-utils")
def test_thirty_sheets_print_without_split_rows(tmp_path):
    archive = str(tmp_path / "thirty.sqlite")
    coil_report.simulate_line(archive, RULES, one_coil(30), sheet_length_mm=600.0,
                              width_mm=1000.0, progress=None)
    reports = coil_report.write_reports(archive, str(tmp_path / "out"), progress=None)
    page = reports[0].path
    pdf = str(tmp_path / "coil.pdf")
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                    "--no-first-run", "--disable-background-networking",
                    "--disable-component-update", "--disable-sync",
                    f"--user-data-dir={tmp_path / 'chromium'}", "--no-pdf-header-footer",
                    f"--print-to-pdf={pdf}", "file://" + page],
                   capture_output=True, timeout=120, check=True)
    pages = _pdf_pages(pdf)
    text = [_page_text(pdf, p) for p in range(1, pages + 1)]
    # Each row of the sheet tables: its first cell's marker ("qa17a") and
    # every cell's end marker ("qa17z") on the same page.
    for table in ("qa", "qf"):
        for n in range(1, 31):
            starts = [p for p, t in enumerate(text) if f"{table}{n}a" in t]
            ends = {p for p, t in enumerate(text) if f"{table}{n}z" in t}
            if table == "qf" and not starts:
                continue  # the sheet passed: not in the failed-only table
            assert len(starts) == 1, (table, n, starts)
            assert ends == set(starts), f"row {table}{n} is split across pages {starts} {ends}"
    # The header repeats on every page the table of every sheet continues on.
    for t in text:
        if re.search(r"qa\d+a", t):
            assert "coverage" in t, "a page of the sheet table without its header"
    # 30 sheets, figures and the sign-off: a handful of A4 pages.
    assert 4 <= pages <= 12, pages
    shots = os.environ.get("FLT_REPORT_SCREENSHOTS")
    if shots:
        os.makedirs(shots, exist_ok=True)
        subprocess.run(["pdftoppm", "-r", "60", "-png", pdf, os.path.join(shots, "page")],
                       check=True)
    print(f"30 sheets: {pages} pages, every row on one page")


@pytest.mark.skipif(not os.path.exists("/usr/lib/postgresql") or
                    subprocess.run([sys.executable, "-c", "import psycopg2"],
                                   capture_output=True).returncode != 0,
                    reason="needs Debian's postgresql and python3-psycopg2")
def test_report_from_postgresql(tmp_path):
    folder = f"/tmp/fltpgr.{os.getpid()}"
    start = subprocess.run(["bash", PG_CLUSTER, "start", folder], capture_output=True,
                           text=True)
    if start.returncode != 0:
        pytest.skip(f"no PostgreSQL server to start: {start.stderr.strip()}")
    try:
        location = "pg:" + start.stdout.strip()
        sheets = coil_report.simulate_line(location, RULES, one_coil(2),
                                           sheet_length_mm=1500.0, progress=None)
        coil = coil_report.read_coil(location, "SIM-4711")
        assert [s.index for s in coil.sheets] == [1, 2]
        assert coil.grade == "S355MC" and coil.extras == {"line": "CTL 2"}
        for mine, gauges in zip(coil.sheets, sheets):
            finite = np.isfinite(gauges.z)
            assert np.max(np.abs(mine.z[finite] - gauges.z[finite])) <= 0.0005 + 1e-12
            assert [r.worst for r in mine.rules] == pytest.approx(
                [r.worst for r in gauges.verdict], nan_ok=True, rel=0, abs=0)
        report = coil_report.write_reports(location, str(tmp_path), progress=None)[0]
        assert report.sheets == 2
    finally:
        subprocess.run(["bash", PG_CLUSTER, "remove", folder], capture_output=True)


def test_advice_is_checked():
    with pytest.raises(ValueError, match="confidence"):
        coil_report.read_advice([{"sheet": 1, "changes": {"a": 1.0}, "confidence": 1.5}])
    with pytest.raises(ValueError, match="number"):
        coil_report.read_advice([{"sheet": 1, "changes": {"a": "up"}}])
    got = coil_report.read_advice([{"sheet": 2, "changes": {"roll 3": -0.1}, "confidence": 0.8}])
    assert got[2].changes == {"roll 3": -0.1}


def test_command_line(tmp_path):
    out = tmp_path / "cli"
    assert coil_report.main(["--out", str(out), "--coils", "1", "--sheets", "1",
                             "--sheet-length", "1200", "--quiet"]) == 0
    assert (out / "index.html").exists() and (out / "archive.sqlite").exists()
    # The archive it made reports again, by coil id.
    assert coil_report.main([str(out / "archive.sqlite"), "--coil", "SIM-4711", "--out",
                             str(tmp_path / "again"), "--quiet"]) == 0
    assert (tmp_path / "again" / "coil_SIM-4711" / "index.html").exists()
