# SPDX-License-Identifier: Apache-2.0
# The rule file the snippet loads (the coil report's example rules) and the
# reference sensor.
import os
import shutil

import flatline

shutil.copy(os.path.join(os.environ["FLT_SOURCE_DIR"], "tools", "coil_report",
                         "example_rules.json"), "grade-s355.json")
calib = flatline.Calibration.reference()
# SNIPPET
