# SPDX-License-Identifier: Apache-2.0
# Profile rows of a flat strip with a small wave, as the two lasers measure
# them: s (N,) mm, height and slope (N, K); frames in blocks of 100 rows.
import numpy as np

N, K = 400, 9
s = np.arange(N) * 5.0                                   # a row every 5 mm
height = np.tile(0.5 * np.sin(2 * np.pi * s / 1000.0)[:, None], (1, K))
slope = np.tile((0.5 * 2 * np.pi / 1000.0 * np.cos(2 * np.pi * s / 1000.0))[:, None], (1, K))
frames = [(s[i:i + 100], height[i:i + 100], slope[i:i + 100]) for i in range(0, N, 100)]
# SNIPPET
assert np.all(np.isfinite(z)), "the snippet's reconstruction has gaps"
