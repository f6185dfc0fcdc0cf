#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""flatline.reconstruct in a loop, to set beside the C figure of
examples/bench/bench_recon built against the same library ("batch ...
then N calls"): the reference's
production sheet (2000 rows x 1150 fibers, 6000 mm x 2300 mm at 3 mm x
2 mm), noise-free, default options. Prints the first call (which sets up
the working memory the library keeps for the next call of the same shape),
then per call over the loop: wall-clock and CPU time of the process, and the
page faults (none once the library and numpy reuse their memory). Then the
binding against the C path in the same process: calls of
flatline.reconstruct alternating with flt_reconstruct of the same loaded
library called straight (ctypes), each timed by this thread's CPU clock;
the median ratio of each pair is the binding's cost over C, unmoved by what
else the machine runs (separate runs of this and bench_recon on a busy
machine differ by more than the 10 % they are to be within).

Usage (with the package the dev preset builds, not installed), and the C
figure from the same build:
    PYTHONPATH=build/dev/bindings/python/package \\
        taskset -c 1 /usr/bin/python3 examples/python/bench_reconstruct.py [calls]
    taskset -c 1 build/dev/examples/bench/bench_recon 3 [calls]
The dev preset's library is built -O2 (RelWithDebInfo), at which GCC 12
vectorises little: its times are about five times the release build's
(the ratio of the pairs is the same). For the release figures, copy the
package and put the release library in it:
    cp -r build/dev/bindings/python/package /tmp/flt-release
    cp -L build/release/lib/libflatline.so.0.* /tmp/flt-release/flatline/
    PYTHONPATH=/tmp/flt-release /usr/bin/python3 examples/python/bench_reconstruct.py
"""

import ctypes
import resource
import sys
import time

import numpy as np

import flatline

ROWS, FIBERS, DX, PITCH, LASER = 2000, 1150, 3.0, 2.0, 100.0


def surface(x, s):
    """12 mm waves, 1800 mm along and 1500 mm across (bench_recon's)."""
    return 12.0 * np.sin(2 * np.pi * s / 1800.0)[:, None] * np.cos(2 * np.pi * x / 1500.0)[None, :]


def c_reconstruct():
    """flt_reconstruct of the libflatline the binding loaded, to be called
    straight through ctypes; None where /proc/self/maps does not say which
    file that is (not Linux)."""
    try:
        with open("/proc/self/maps", encoding="ascii", errors="replace") as maps:
            paths = sorted({line.split()[-1] for line in maps if "/libflatline." in line})
    except OSError:
        return None
    if len(paths) != 1:
        return None
    function = ctypes.CDLL(paths[0]).flt_reconstruct  # already loaded: the same library
    pointer, size = ctypes.c_void_p, ctypes.c_size_t
    function.argtypes = [pointer, size, size] + [pointer] * 6
    function.restype = ctypes.c_int
    return function


def paired(calls, s, height, slope):
    """Median CPU time (s) per call of the binding and of the C path, and
    the median of their ratios, calls alternating (who goes first too)."""
    function = c_reconstruct()
    if function is None:
        return None
    z = np.empty(height.shape)
    flags = np.empty(height.shape, dtype=np.uint8)

    def direct():
        status = function(None, height.shape[0], height.shape[1], s.ctypes.data,
                          height.ctypes.data, slope.ctypes.data, None, z.ctypes.data,
                          flags.ctypes.data)
        if status != 0:
            raise RuntimeError(f"flt_reconstruct returned {status}")

    direct()
    if not np.array_equal(z, flatline.reconstruct(s, height, slope)):
        raise RuntimeError("the binding and the C path disagree")
    binding, c, ratio = [], [], []
    for i in range(calls):
        spent = {}
        for name in (("python", "c") if i % 2 == 0 else ("c", "python")):
            start = time.thread_time()
            if name == "python":
                flatline.reconstruct(s, height, slope)
            else:
                direct()
            spent[name] = time.thread_time() - start
        binding.append(spent["python"])
        c.append(spent["c"])
        ratio.append(spent["python"] / spent["c"])
    return float(np.median(binding)), float(np.median(c)), float(np.median(ratio))


def main():
    calls = int(sys.argv[1]) if len(sys.argv) > 1 else 100
    s = np.arange(ROWS) * DX
    x = (np.arange(FIBERS) - 0.5 * (FIBERS - 1)) * PITCH
    behind, ahead = surface(x, s - LASER / 2), surface(x, s + LASER / 2)
    height, slope = 0.5 * (behind + ahead), (ahead - behind) / LASER

    start = time.perf_counter()
    z = flatline.reconstruct(s, height, slope)
    first = time.perf_counter() - start
    error = np.abs(z - surface(x, s)).max()

    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    wall, cpu = time.perf_counter(), time.process_time()
    for i in range(calls):
        flatline.reconstruct(s, height, slope)
        if (i + 1) % 10 == 0:
            print(f"\rcall {i + 1}/{calls}", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
    print(f"flatline.reconstruct, {ROWS} rows x {FIBERS} fibers: first call {1e3 * first:.2f} ms; "
          f"then {calls} calls: {1e3 * wall / calls:.2f} ms per call, CPU {1e3 * cpu / calls:.2f} ms, "
          f"{faults / calls:.0f} page faults per call; max error {1e3 * error:.2g} um")
    pair = paired(calls, s, height, slope)
    if pair is None:
        print("binding against C: skipped (the loaded libflatline is not known)")
    else:
        print(f"binding against C, {calls} pairs of calls: CPU median {1e3 * pair[0]:.2f} ms "
              f"against {1e3 * pair[1]:.2f} ms, ratio {pair[2]:.3f} (median of the pairs)   "
              f"[goal <= 1.10]")


if __name__ == "__main__":
    main()
