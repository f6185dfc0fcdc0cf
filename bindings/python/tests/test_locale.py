# SPDX-License-Identifier: Apache-2.0
"""Number text under a decimal-comma locale. A script may call
locale.setlocale(locale.LC_ALL, "de_DE.UTF-8"); that sets the C library's
locale of the whole process, so the library's own printf/strtod would write
"1090,9" and stop reading "1090.9" at the dot. Calibration text saved under
one locale must load under the other with every value bit-identical
(tolerance 0: the writer writes the shortest text that reads back as the same
double), and messages write numbers with '.'. Skipped with a message where
the machine has no German locale (.ci/deps generates de_DE.UTF-8)."""

import locale
import os
import re
import struct

import numpy as np
import pytest

import flatline

GERMAN = ("de_DE.UTF-8", "de_DE.utf8", "German_Germany.1252")


@pytest.fixture
def german():
    """Returns a function that switches the process to German; the C locale
    is restored after the test."""
    saved = locale.setlocale(locale.LC_ALL)

    def use():
        for name in GERMAN:
            try:
                locale.setlocale(locale.LC_ALL, name)
            except locale.Error:
                continue
            # The locale really uses a decimal comma, else nothing is tested.
            assert locale.localeconv()["decimal_point"] == ","
            return
        pytest.skip("the de_DE.UTF-8 locale is not installed (Debian: apt-get install "
                    "locales; enable de_DE.UTF-8 in /etc/locale.gen; locale-gen)")

    yield use
    locale.setlocale(locale.LC_ALL, saved)


def use_c():
    locale.setlocale(locale.LC_ALL, "C")


def calibration():
    """The reference sensor with values no short decimal writes: fractional
    intrinsics, offsets, scale and grid."""
    calib = flatline.Calibration()
    ref = flatline.Calibration.reference()
    calib.frame_size = ref.frame_size
    calib.set_intrinsics(fx=6 / 0.0055, fy=6 / 0.0055 + 1 / 3, cx=1023.5 + 1 / 7,
                         cy=1023.5 - 1 / 9, k1=-0.1 / 3, k2=0.01 / 7)
    for laser in (0, 1):
        calib.set_homography(laser, ref.homography(laser) * (1 + 1e-3 / 3))
    calib.laser_offsets = (-50 - 1 / 3, 50 + 1 / 7)
    calib.encoder_scale = 0.01 / 3
    calib.fiber_grid = (-999.9, 2 / 3, 1000)
    calib.finish()
    return calib


def bits(values):
    return struct.pack(f"{len(values)}d", *values)


def values_of(calib):
    """Every number of the model, for a bit-for-bit comparison."""
    i = calib.intrinsics
    out = [i.fx, i.fy, i.cx, i.cy, i.k1, i.k2, i.k3, i.k4, i.k5, i.k6, i.p1, i.p2]
    for laser in (0, 1):
        out += list(calib.homography(laser).ravel())
    out += list(calib.laser_offsets) + [calib.encoder_scale]
    grid = calib.fiber_grid
    out += [grid.first_x_mm, grid.pitch_mm]
    return out


def no_decimal_comma(text):
    # JSON's commas end a line; a digit on both sides is a decimal comma.
    assert not re.search(r"\d,\d", text), text
    assert "1090.9" in text


@pytest.mark.parametrize("save_german", [True, False], ids=["de-to-C", "C-to-de"])
def test_text_round_trip(german, save_german):
    calib = calibration()
    expected = values_of(calib)
    german() if save_german else use_c()
    text = calib.dumps()
    no_decimal_comma(text)
    use_c() if save_german else german()
    loaded = flatline.Calibration.loads(text)
    assert bits(values_of(loaded)) == bits(expected)
    assert loaded.dumps() == text
    points = np.array([[100.5, 300.25], [1023.5, 1100.75], [1900.125, 1500.5]])
    for laser in (0, 1):
        assert calib.image_to_plane(laser, points).tobytes() == \
            loaded.image_to_plane(laser, points).tobytes()


def test_file_round_trip(german, tmp_path):
    calib = calibration()
    path = os.path.join(tmp_path, "sensor.json")
    german()
    calib.save(path)
    use_c()
    assert bits(values_of(flatline.Calibration.load(path))) == bits(values_of(calib))
    german()
    assert bits(values_of(flatline.Calibration.load(path))) == bits(values_of(calib))


def test_components_copy_the_model(german):
    """The extractor and the simulator copy the calibration through its text."""
    calib = calibration()
    german()
    with flatline.Extractor(calib) as ex:
        assert ex is not None
    with flatline.SimulatedLine(calib) as line:
        # The copy is the same model: the same saved text, bit for bit.
        assert line.calibration.dumps() == calib.dumps()


def test_messages_use_a_decimal_point(german):
    calib = flatline.Calibration()
    german()
    with pytest.raises(flatline.InvalidArgumentError) as info:
        calib.fiber_grid = (-999.5, -0.25, 10)
    assert "-0.25" in str(info.value) and "-0,25" not in str(info.value)
