# SPDX-License-Identifier: Apache-2.0
# A reconstructed sheet (the reference sensor, a centre buckle), as rows
# out of a reconstructor: z, s, fiber_x, calib, and s_out, z_out, flags.
import numpy as np
import flatline

calib = flatline.Calibration.reference()
with flatline.SimulatedLine(calib, sim_seed=1) as sim:
    sim.add_defect("centre_buckle", 6.0, 1800.0)
    truth = sim.next_rows(1200)
fiber_x = -1000.0 + 2.0 * np.arange(1001)
s, z = truth.s, truth.truth
s_out, z_out = s, z
flags = np.zeros(z.shape, dtype=np.uint8)
# SNIPPET
