# SPDX-License-Identifier: Apache-2.0
# A few frames of the simulated line for the gauge.
import flatline

calib = flatline.Calibration.reference()
with flatline.SimulatedLine(calib, sim_seed=1) as sim:
    frames = [sim.next_frame() for _ in range(20)]
# SNIPPET
