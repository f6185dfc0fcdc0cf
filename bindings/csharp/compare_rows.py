# SPDX-License-Identifier: Apache-2.0
"""Compares two row dumps of the C# example (s, then z per fiber, per line).

usage: compare_rows.py A B TOLERANCE_MM NAME_A NAME_B

Both runs reconstruct the same simulated line through the same package, one
on Linux, one on Windows (win-x64 under wine). Every row must have the same
s and every z must agree within TOLERANCE_MM; prints the largest difference.
"""
import math
import sys


def rows(path: str) -> list[list[float]]:
    with open(path, encoding="ascii") as f:
        return [[float(v) for v in line.split()] for line in f if line.strip()]


def main() -> int:
    a_path, b_path, tolerance, a_name, b_name = sys.argv[1:6]
    bound = float(tolerance)
    a, b = rows(a_path), rows(b_path)
    if not a or len(a) != len(b):
        print(f"{a_name}: {len(a)} rows, {b_name}: {len(b)} rows: not the same run")
        return 1
    worst, worst_at, values = 0.0, (0, 0), 0
    for r, (ra, rb) in enumerate(zip(a, b)):
        if len(ra) != len(rb) or ra[0] != rb[0]:
            print(f"row {r}: s or fiber count differ ({ra[0]} / {rb[0]})")
            return 1
        for k, (za, zb) in enumerate(zip(ra[1:], rb[1:])):
            if math.isnan(za) or math.isnan(zb):
                if math.isnan(za) != math.isnan(zb):
                    print(f"row {r} fiber {k}: {za} / {zb}")
                    return 1
                continue
            values += 1
            if abs(za - zb) > worst:
                worst, worst_at = abs(za - zb), (r, k)
    fibers = len(a[0]) - 1
    verdict = "agree" if worst <= bound else "DIFFER"
    print(f"{a_name} and {b_name} {verdict}: {len(a)} rows x {fibers} fibers ({values} heights), "
          f"max |dz| = {worst:.3g} mm at row {worst_at[0]} fiber {worst_at[1]} (bound {bound:g} mm)")
    return 0 if worst <= bound else 1


if __name__ == "__main__":
    sys.exit(main())
