# SPDX-License-Identifier: Apache-2.0
# The sensor file the snippet loads: the reference sensor's calibration.
import flatline

flatline.Calibration.reference().save("sensor.json")
# SNIPPET
