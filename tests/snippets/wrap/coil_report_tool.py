# SPDX-License-Identifier: Apache-2.0
# The coil report from the source tree's tools/coil_report (the snippet's
# relative sys.path), the example rules as my_rules.json, the reference
# sensor and 300 frames of the simulated line (one sheet, ended by the flush).
import os
import shutil

import flatline

source = os.environ["FLT_SOURCE_DIR"]
os.makedirs("tools", exist_ok=True)
if not os.path.exists("tools/coil_report"):
    os.symlink(os.path.join(source, "tools", "coil_report"), "tools/coil_report")
shutil.copy(os.path.join(source, "tools", "coil_report", "example_rules.json"), "my_rules.json")
calib = flatline.Calibration.reference()
with flatline.SimulatedLine(calib, sim_seed=1) as sim:
    sim.add_defect("centre_buckle", 6.0, 1800.0)
    frames = [sim.next_frame() for _ in range(300)]
# SNIPPET
assert sheets, "the gauge gave no sheet"
assert os.listdir("coil-report"), "the report folder is empty"
