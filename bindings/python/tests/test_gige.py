# SPDX-License-Identifier: Apache-2.0
"""GigE Vision from Python: aravis's fake camera (arv-fake-gv-camera-0.8,
Debian package aravis-tools), started here on 127.0.0.1, found by
discovery, opened by address, its features set and frames compared with
the ramp aravis fills them with: pixel (x, y) of frame id f is
(x + y + f) % 255. Linux only (the fake camera); skipped elsewhere or when
it is not installed."""

import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

import flatline

FAKE = "arv-fake-gv-camera-0.8"


@pytest.fixture(scope="module")
def camera():
    if not sys.platform.startswith("linux"):
        pytest.skip("aravis's fake GigE camera runs on Linux only")
    if shutil.which(FAKE) is None:
        pytest.skip(f"{FAKE} (Debian package aravis-tools) is not installed")
    serial = f"PY{os.getpid() % 1000000}"
    process = subprocess.Popen([FAKE, "-i", "127.0.0.1", "-s", serial],
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        # It answers within ~50 ms; 10 s covers a loaded machine.
        for _ in range(50):
            found = flatline.Source.list_gige_cameras("127.0.0.1", 200)
            if found:
                if found[0].serial != serial:
                    pytest.skip("another camera answers on 127.0.0.1:3956")
                break
            time.sleep(0.2)
        else:
            pytest.skip(f"{FAKE} did not answer a discovery within 10 s")
        yield serial
    finally:
        process.terminate()
        process.wait()


def ramp(width, height, frame_id):
    y, x = np.mgrid[0:height, 0:width]
    return ((x + y + frame_id) % 255).astype(np.uint8)


def test_discovery_lists_the_camera(camera):
    found = flatline.Source.list_gige_cameras("127.0.0.1", 500)
    assert len(found) == 1
    assert found[0].vendor == "Aravis"
    assert found[0].model == "Fake"
    assert found[0].serial == camera
    assert found[0].address == "127.0.0.1"
    assert found[0].speed_mbps == 0


def test_frames_are_aravis_ramp(camera):
    with flatline.Source.gige("127.0.0.1", gige_resend_timeout=25) as source:
        assert source.kind == flatline.SourceKind.GIGE
        assert source.camera_string("serial") == camera
        assert source.camera_value("ip_address") == 0x7F000001
        assert source.camera_value("packet_size") == 1400  # no test packets: its own
        source.set_int("Width", 128)
        source.set_int("Height", 64)
        source.set_float("AcquisitionFrameRate", 100.0)
        assert source.get_int("PayloadSize") == 128 * 64
        source.start()
        previous = None
        for _ in range(20):
            frame = source.next(timeout_ms=2000)
            assert frame.pixels.shape == (64, 128)
            if previous is not None:
                assert frame.block_id == previous + 1
            previous = frame.block_id
            frame_id = (frame.block_id - 1) % 65535 + 1  # unwrapped 16-bit id
            assert np.array_equal(frame.pixels, ramp(128, 64, frame_id))
        counters = source.counters()
        assert counters["frames"] == 20
        assert counters["dropped"] == 0
        assert counters["packets_missing"] == 0


def test_bad_arguments():
    with pytest.raises(ValueError, match="timeout_ms"):
        flatline.Source.list_gige_cameras("127.0.0.1", 0)
    with pytest.raises(flatline.InvalidArgumentError, match="address"):
        flatline.Source.list_gige_cameras("camera.local", 10)
    with pytest.raises(flatline.FlatlineError, match="127.0.0.1:9"):
        flatline.Source.gige("127.0.0.1:9", gige_control_timeout=10, gige_command_attempts=1)
