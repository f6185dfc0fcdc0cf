# SPDX-License-Identifier: Apache-2.0
# The coil report from the source tree's tools/coil_report (importable as
# coil_report), and archive.sqlite holding coil 4711: two 1.5 m sheets of
# the simulated line, judged by the example rules. Afterwards the report's
# page is there.
import os
import sys

source = os.environ["FLT_SOURCE_DIR"]
sys.path.insert(0, os.path.join(source, "tools", "coil_report"))
import flatline  # noqa: E402
import coil_report as _made  # noqa: E402

_made.simulate_line(
    "archive.sqlite",
    coils=[_made.SimCoil(flatline.CoilInfo("4711", grade="S355MC", thickness_mm=3.0,
                                           width_mm=1500.0), 2,
                         (("centre_buckle", 1.6, 1800.0),))],
    sheet_length_mm=1500.0, progress=None)
# SNIPPET
assert coil.coil_id == "4711" and len(coil.sheets) == 2, coil
assert os.path.exists(os.path.join("report", "index.html")), "no report page"
