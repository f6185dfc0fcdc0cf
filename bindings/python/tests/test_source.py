# SPDX-License-Identifier: Apache-2.0
"""Frame sources: the simulator, image sequences and the simulated USB3
Vision camera (features, counters, injected faults and their errors), the
camera -> Source -> Extractor -> reconstruct loop bit for bit, lifetimes."""

import gc
import struct
import weakref
import zlib

import numpy as np
import pytest

import flatline
import flatline.testing

from conftest import bits, roi_reference

WIDTH, HEIGHT = 64, 32  # px, the small test-pattern camera


def pattern(block, width=WIDTH, height=HEIGHT):
    """The simulated camera's test pattern (flatline/source.h): payload byte
    i of block b is (b * 131 + i * 7 + (i >> 9)) mod 256."""
    i = np.arange(width * height, dtype=np.int64)
    return ((block * 131 + i * 7 + (i >> 9)) % 256).astype(np.uint8).reshape(height, width)


@pytest.fixture
def bus():
    with flatline.testing.U3VSimBus() as b:
        assert b.add_camera("Flatline", "Test camera", "S1", WIDTH, HEIGHT) == 0
        assert b.add_camera("Flatline", "Second", "S2", WIDTH, HEIGHT) == 1
        yield b


@pytest.fixture(scope="module")
def calib():
    return roi_reference(fibers=101, pitch=20.0)  # 2048 x 256 px frames


def write_png(path, image):
    """A grey PNG (8 or 16 bits, filter None) without an imaging library."""
    depth = 8 if image.dtype == np.uint8 else 16
    data = image.astype(">u2").tobytes() if depth == 16 else image.tobytes()
    row = image.shape[1] * depth // 8
    raw = b"".join(b"\0" + data[r * row:(r + 1) * row] for r in range(image.shape[0]))

    def chunk(tag, body):
        return (struct.pack(">I", len(body)) + tag + body
                + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", image.shape[1], image.shape[0], depth, 0, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


# -- simulated USB3 Vision camera ----------------------------------------------------


def test_cameras_are_listed_with_their_strings(bus):
    cameras = flatline.list_cameras(bus)
    assert cameras == [flatline.CameraInfo("Flatline", "Test camera", "S1", 5000),
                       flatline.CameraInfo("Flatline", "Second", "S2", 5000)]
    assert bus.cameras() == cameras == flatline.Source.list_cameras(bus)


def test_u3v_frames_are_the_test_pattern_with_fixed_step_positions(bus):
    with flatline.Source.u3v("S1", bus=bus, source_encoder_step=2.5) as cam:
        assert cam.kind is flatline.SourceKind.U3V
        assert cam.camera_string("serial") == "S1"
        assert cam.camera_string("model") == "Test camera"
        assert cam.camera_value("xml_zipped") == 1
        cam.start()
        assert bus.get(0, "acquiring") == 1
        first = cam.next()
        out = np.empty((HEIGHT, WIDTH), np.uint8)
        frames = [first] + [cam.next(out=out if i == 2 else None) for i in range(4)]
        for frame in frames:
            assert frame.pixel_format is flatline.PixelFormat.MONO8
            assert np.array_equal(frame.pixels, pattern(frame.block_id))
        assert frames[3].pixels is out  # decoded into the caller's buffer
        # encoder = start + step * (block id - first block id)
        assert [f.encoder_mm for f in frames] == [2.5 * (f.block_id - first.block_id)
                                                  for f in frames]
        # Frames are copies: still intact after later frames.
        assert np.array_equal(first.pixels, pattern(first.block_id))
        counters = cam.counters()
        assert counters["frames"] == 5 and counters["dropped"] == 0 and counters["lost"] == 0
        assert len(counters) == 21  # 17 + the four GigE packet counters
        cam.stop()
        assert bus.get(0, "acquiring") == 0
    assert bus.get(0, "open") == 0  # closing the source released the camera


def test_features_by_name_registers_and_mapping(bus):
    with flatline.Source.u3v("S2", bus=bus) as cam:
        assert cam.get_int("Width") == WIDTH
        cam.set_int("Height", 16)
        assert cam.get_int("Height") == 16 == bus.peek(1, 0x10004)
        cam.set_float("Gain", 2.5)
        assert cam.get_float("Gain") == 2.5  # float32 register, 2.5 exact
        cam.set_enum("TriggerMode", "On")
        assert cam.get_int("TriggerMode") == bus.peek(1, 0x10024)
        cam.execute("AcquisitionStop")
        # ExposureTime is a Converter of its raw register (us, FROM - 0)...
        cam.set_float("ExposureTime", 1234.0)
        assert cam.get_float("ExposureTime") == 1234.0
        assert bus.peek(1, 0x1001C) == 1234
        # ...and a feature the camera lacks can be mapped onto a register.
        with pytest.raises(flatline.NotFoundError, match="ExposureAbs"):
            cam.get_int("ExposureAbs")
        cam.map_feature("ExposureAbs", 0x1001C, 4)
        assert cam.get_int("ExposureAbs") == 1234
        # Raw GenCP memory access.
        cam.write_memory(0x1001C, struct.pack("<I", 777))
        assert cam.read_memory(0x1001C, 4) == struct.pack("<I", 777)
        with pytest.raises(flatline.NotFoundError, match="NoSuchFeature"):
            cam.get_int("NoSuchFeature")
        with pytest.raises(ValueError, match="'which'"):
            cam.camera_string("colour")


def test_injected_stream_faults_are_dropped_counted_and_reported(bus):
    # Block ids start at 1. A short frame at block 2 and a bad trailer at 4
    # are dropped; three ids skipped from 6 are lost; the frames around them
    # arrive intact.
    bus.inject(0, flatline.testing.U3VFault.SHORT_FRAME, at=2)
    bus.inject(0, "trailer_status", at=4)
    bus.inject(0, "skip_block_ids", at=6, count=3)
    with flatline.Source.u3v("S1", bus=bus) as cam:
        cam.start()
        ids = [cam.next().block_id for _ in range(5)]
        assert ids == [1, 3, 5, 9, 10]
        c = cam.counters()
        assert (c["short"], c["dropped"], c["lost"], c["frames"]) == (2, 2, 3, 5)
        assert cam.stream_error != ""


def test_timeout_and_unplug_raise_timeout_and_device_errors(bus):
    bus.inject(0, "stream_timeout", at=2)
    bus.inject(0, "unplug", at=4)
    with flatline.Source.u3v("S1", bus=bus) as cam:
        cam.start()
        assert cam.next(timeout_ms=50).block_id == 1
        with pytest.raises(flatline.TimeoutError) as timeout:
            cam.next(timeout_ms=50)
        assert isinstance(timeout.value, TimeoutError)  # the built-in one too
        assert timeout.value.status == -8
        assert cam.counters()["timeouts"] == 1
        assert cam.next(timeout_ms=50).block_id == 3  # the stream recovers
        with pytest.raises(flatline.DeviceError, match="unplugged") as gone:
            cam.next(timeout_ms=50)
        assert isinstance(gone.value, OSError) and gone.value.status == -7
        with pytest.raises(flatline.DeviceError):  # and on every later call
            cam.next(timeout_ms=50)
        assert cam.counters()["disconnects"] == 1
    # destroy still works: the bus can open the other camera.
    with flatline.Source.u3v("S2", bus=bus) as other:
        assert other.get_int("Width") == WIDTH


def test_control_faults_are_retried_and_counted(bus):
    bus.inject(0, "pending_ack", count=2)
    with flatline.Source.u3v("S1", bus=bus) as cam:
        assert cam.get_int("Width") == WIDTH
        assert cam.counters()["pending_acks"] >= 2


def test_a_camera_left_streaming_is_stopped_on_open(bus):
    bus.set(0, flatline.testing.U3VSimParam.LEFT_STREAMING, 1)
    assert bus.get(0, "si_control") == 1
    with flatline.Source.u3v("S1", bus=bus) as cam:
        assert bus.get(0, "si_control") == 0 and bus.get(0, "acquiring") == 0
        assert cam.counters()["stream_recoveries"] == 1
        cam.start()
        frame = cam.next()
        assert np.array_equal(frame.pixels, pattern(frame.block_id))


def test_a_stop_the_camera_did_not_take_says_so_and_start_recovers(bus):
    with flatline.Source.u3v("S1", bus=bus) as cam:
        cam.start()
        cam.next()
        # Every command of the stop is lost (3 rounds of 3 attempts, 2 steps).
        bus.inject(0, "control_timeout", count=18)
        with pytest.raises(flatline.TimeoutError, match="may still be streaming"):
            cam.stop()
        # the camera really streams on; the host side is stopped
        assert bus.get(0, "si_control") == 1 and bus.get(0, "acquiring") == 1
        with pytest.raises(flatline.StateError):
            cam.next()
        assert bus.get(0, "faults_pending") == 0
        cam.start()  # stops the camera first, then starts it again
        assert cam.counters()["stream_recoveries"] == 1
        frame = cam.next()
        assert np.array_equal(frame.pixels, pattern(frame.block_id))
        cam.stop()
        assert bus.get(0, "si_control") == 0 and bus.get(0, "acquiring") == 0


def test_u3v_errors(bus):
    with pytest.raises(flatline.NotFoundError, match="nope"):
        flatline.Source.u3v("nope", bus=bus)
    with pytest.raises(TypeError, match="'bus'"):
        flatline.Source.u3v(bus="bus")
    with pytest.raises(TypeError, match="another component"):
        flatline.Source.u3v("S1", bus=bus, sim_seed=3)
    with pytest.raises(flatline.InvalidArgumentError):
        bus.add_camera("V", "M", "S9", 8, 8)  # below 16 px
    with pytest.raises(flatline.InvalidArgumentError):
        bus.inject(7, "unplug")  # no camera 7
    with pytest.raises(ValueError, match="'fault'"):
        bus.inject(0, "meteor")
    with flatline.Source.u3v("S1", bus=bus) as cam:
        with pytest.raises(flatline.StateError):
            cam.next()  # before start
        cam.start()
        with pytest.raises(flatline.StateError):
            cam.start()  # already started
        with pytest.raises(TypeError, match="uint8"):
            cam.next(out=np.empty((HEIGHT, WIDTH), np.uint16))
        with pytest.raises(ValueError, match="shape"):
            cam.next(out=np.empty((HEIGHT, WIDTH + 1), np.uint8))
        assert cam.next().pixels.shape == (HEIGHT, WIDTH)  # still usable
    with pytest.raises(flatline.StateError, match="closed"):
        cam.next()
    with pytest.raises(TypeError, match="Source.simulator"):
        flatline.Source()


# -- simulator and images --------------------------------------------------------


def test_simulator_source_gives_the_simulators_frames(calib):
    with flatline.SimulatedLine(calib, sim_seed=5) as direct:
        expected = [direct.next_frame() for _ in range(3)]
    sim = flatline.SimulatedLine(calib, sim_seed=5)
    with flatline.Source.simulator(sim) as source:
        assert source.kind is flatline.SourceKind.SIMULATOR
        source.start()
        for block, want in enumerate(expected):
            frame = source.next()
            assert frame.block_id == block
            assert frame.encoder_mm == want.encoder_mm
            assert np.array_equal(frame.pixels, want.image)
        with pytest.raises(flatline.StateError):
            source.camera_string("vendor")  # not a camera
        assert source.counters()["frames"] == 3


def test_a_source_keeps_its_simulated_line_alive(calib):
    sim = flatline.SimulatedLine(calib, sim_seed=9)
    ref = weakref.ref(sim)
    source = flatline.Source.simulator(sim)
    del sim
    gc.collect()
    assert ref() is not None  # held by the source
    ref().close()  # closing the Python object does not free the C simulator
    source.start()
    assert source.next().pixels.shape == (256, 2048)
    source.close()
    gc.collect()
    assert ref() is None  # released with the source


def test_a_source_keeps_its_bus_alive():
    bus = flatline.testing.U3VSimBus()
    bus.add_camera("V", "M", "S1", WIDTH, HEIGHT)
    ref = weakref.ref(bus)
    cam = flatline.Source.u3v(bus=bus)
    bus.close()  # the C bus lives on while the source uses it
    del bus
    gc.collect()
    cam.start()
    frame = cam.next()
    assert np.array_equal(frame.pixels, pattern(frame.block_id))
    del cam
    gc.collect()
    assert ref() is None


def test_image_sequences_with_csv_step_and_directory(tmp_path):
    rng = np.random.default_rng(1)
    images = [rng.integers(0, 256, (20, 30), dtype=np.uint8) for _ in range(3)]
    paths = []
    for i, image in enumerate(images):
        paths.append(tmp_path / f"f{i}.png")
        write_png(paths[-1], image)
    csv = tmp_path / "enc.csv"
    csv.write_text("file,encoder_mm\nf0.png,10.5\nf1.png,13.0\nf2.png,16.25\n")
    with flatline.Source.images(paths, csv) as source:
        assert source.kind is flatline.SourceKind.IMAGES
        source.start()
        frames = list(source)
        assert [f.encoder_mm for f in frames] == [10.5, 13.0, 16.25]
        assert [f.block_id for f in frames] == [0, 1, 2]
        for frame, image in zip(frames, images):
            assert np.array_equal(frame.pixels, image)
        assert source.next() is None  # stays at the end
    with flatline.Source.images(str(tmp_path), step=4.0, source_encoder_start=100.0) as source:
        source.start()
        assert [f.encoder_mm for f in source] == [100.0, 104.0, 108.0]
    # 16 bits, read as Mono12 on request.
    wide = (rng.integers(0, 4096, (20, 30))).astype(np.uint16)
    write_png(tmp_path / "w.png", wide)
    with flatline.Source.images([tmp_path / "w.png"], source_image_bits=12) as source:
        source.start()
        frame = source.next()
        assert frame.pixel_format is flatline.PixelFormat.MONO12
        assert np.array_equal(frame.pixels, wide)


def test_image_errors_name_the_file(tmp_path):
    write_png(tmp_path / "a.png", np.zeros((4, 4), np.uint8))
    with pytest.raises(flatline.FileError, match="missing.png"):
        flatline.Source.images([tmp_path / "missing.png"])
    bad = tmp_path / "bad.csv"
    bad.write_text("1.0\n2.0\n")  # two rows for one image
    with pytest.raises(flatline.FormatError, match="bad.csv"):
        flatline.Source.images([tmp_path / "a.png"], bad)
    empty = tmp_path / "empty"
    empty.mkdir()
    with pytest.raises(flatline.NotFoundError):
        flatline.Source.images(empty)
    with pytest.raises(TypeError, match="paths"):
        flatline.Source.images([tmp_path / "a.png", 7])
    with pytest.raises(flatline.InvalidArgumentError):
        flatline.Source.images([])


# -- the whole loop -----------------------------------------------------------------


def test_simulated_camera_to_source_to_extractor_to_reconstruct_round_trip(calib):
    # The simulator renders into a simulated USB3 Vision camera that appends
    # its encoder count as a chunk (10 um per count); the Source decodes the
    # USB transfers. The pixels equal the simulator's own frames byte for
    # byte, the chunk's encoder positions equal the simulator's (multiples
    # of 10 um here: 3 mm spacing), so extracted rows and the reconstructed
    # sheet equal the direct path's bit for bit.
    frames = 60  # 177 mm of travel: more than the 100 mm laser spacing
    with flatline.SimulatedLine(calib, sim_seed=11) as direct:
        direct.add_defect("centre_buckle", 8.0, 600.0)
        want = [direct.next_frame() for _ in range(frames)]
    sim = flatline.SimulatedLine(calib, sim_seed=11)
    sim.add_defect("centre_buckle", 8.0, 600.0)
    with flatline.testing.U3VSimBus() as bus:
        bus.add_camera("Flatline", "Sensor", "SIM-1", 64, 32)
        bus.set_frames(0, sim)
        bus.set(0, "encoder_chunk", 1)
        with flatline.Source.u3v(bus=bus, source_encoder_mode="chunk") as cam:
            cam.start()
            got = [cam.next() for _ in range(frames)]
    assert [g.encoder_mm for g in got] == [w.encoder_mm for w in want]
    assert all(np.array_equal(g.pixels, w.image) for g, w in zip(got, want))
    rows = []
    for source_frames in (got, want):
        with flatline.Extractor(calib) as extractor:
            out = [extractor.process(f.pixels if hasattr(f, "pixels") else f.image,
                                     f.encoder_mm) for f in source_frames]
        s = np.array([r.s for r in out])
        z = flatline.reconstruct(s, np.array([r.height for r in out]),
                                 np.array([r.slope for r in out]),
                                 np.array([r.valid for r in out]))
        rows.append(z)
    assert np.array_equal(bits(rows[0]), bits(rows[1]))
    # And the sheet is the simulator's: within 0.3 mm of the truth where
    # valid (8 mm buckle; the reconstruction of 177 mm of travel is short).
    truth = np.array([w.truth for w in want])
    valid = np.isfinite(rows[0])
    assert valid.mean() > 0.9
    assert np.abs(rows[0][valid] - truth[valid]).max() < 0.3


# -- memory -------------------------------------------------------------------------


def test_create_destroy_cycles_of_sources_buses_and_flatness_keep_rss_flat():
    from conftest import rss_bytes

    x = np.linspace(-500.0, 500.0, 51)

    def cycle(i):
        with flatline.testing.U3VSimBus() as bus:
            bus.add_camera("V", "M", "S1", WIDTH, HEIGHT)
            with flatline.Source.u3v(bus=bus) as cam:
                cam.start()
                cam.next()
        flat = flatline.Flatness(x)  # 8192 rows x 51 fibers of scratch
        if i % 2:
            flat.close()

    for i in range(50):
        cycle(i)
    gc.collect()
    before = rss_bytes()
    for i in range(400):
        cycle(i)
    gc.collect()
    growth = rss_bytes() - before
    # Measured resident sizes: a Flatness of 51 fibers 2.0 MB (its row
    # buffers for flat_row_capacity rows), a bus with an open, started
    # camera source 180 KB. Leaking either in one cycle of four would add
    # 200 MB or 18 MB; 8 MB allows allocator noise.
    assert growth < 8 * (1 << 20), growth


def test_host_encoder_positions_and_reprs(calib):
    # source_encoder_mode 2: each frame carries the position set last (NaN
    # before the first set_encoder); other modes refuse set_encoder.
    with flatline.SimulatedLine(calib) as sim, \
            flatline.Source.simulator(sim, source_encoder_mode="host") as source:
        source.start()
        assert np.isnan(source.next().encoder_mm)
        source.set_encoder(12.5)
        assert source.next().encoder_mm == 12.5
        assert repr(source) == "<flatline.Source simulator>"
        with flatline.Source.simulator(sim) as auto:
            with pytest.raises(flatline.StateError):
                auto.set_encoder(1.0)
    assert repr(source) == "<flatline.Source closed>"
    with flatline.testing.U3VSimBus() as bus:
        bus.add_camera("V", "M", "S1", WIDTH, HEIGHT)
        bus.set_frames(0, None)  # the test pattern (already the default)
        assert repr(bus) == "<flatline.testing.U3VSimBus>"
    assert bus.closed and repr(bus) == "<flatline.testing.U3VSimBus closed>"
    with pytest.raises(flatline.StateError, match="closed"):
        bus.add_camera("V", "M", "S2", WIDTH, HEIGHT)


@pytest.mark.parametrize("fault, at, ids, counted", [
    # A new leader mid-frame drops block 2 (INCOMPLETE).
    ("leader_mid_frame", 2, [1, 3, 4], {"dropped": 1, "incomplete": 1}),
    # 100 bytes outside any frame are discarded; no frame is lost.
    ("garbage", 2, [1, 2, 3], {"bad_packets": 1}),
    # A refused bulk submit drops the frame that was streaming (block 1).
    ("submit_refused", 0, [2, 3, 4], {"dropped": 1, "submit_dropped": 1,
                                      "submit_refused": 1}),
])
def test_more_stream_faults_drop_and_count(bus, fault, at, ids, counted):
    with flatline.Source.u3v("S1", bus=bus) as cam:
        cam.start()
        bus.inject(0, fault, at=at, count=1)
        got = [cam.next() for _ in range(3)]
        assert [f.block_id for f in got] == ids
        assert all(np.array_equal(f.pixels, pattern(f.block_id)) for f in got)
        nonzero = {k: v for k, v in cam.counters().items() if v and k != "frames"}
        assert nonzero == counted


def test_control_channel_timeouts_retry_then_raise_timeout_error(bus):
    with flatline.Source.u3v("S1", bus=bus, u3v_command_attempts=3) as cam:
        bus.inject(0, "control_timeout", count=1)  # one lost command: retried
        assert cam.get_int("Width") == WIDTH
        assert cam.counters()["command_retries"] == 1
        bus.inject(0, "control_timeout", count=3)  # every attempt lost
        with pytest.raises(flatline.TimeoutError, match="3 attempts"):
            cam.get_int("Width")
        assert cam.get_int("Width") == WIDTH  # the channel still works


def test_a_camera_source_serialises_with_the_simulator_it_renders(calib):
    # next() takes the lock of the SimulatedLine the bus renders: while
    # another thread holds it, next() waits. The frame is the simulator's.
    import threading

    with flatline.SimulatedLine(calib, sim_seed=4) as direct:
        want = direct.next_frame()
    with flatline.testing.U3VSimBus() as bus, flatline.SimulatedLine(calib, sim_seed=4) as sim:
        bus.add_camera("V", "M", "S1", WIDTH, HEIGHT)
        bus.set_frames(0, sim)
        with flatline.Source.u3v(bus=bus) as cam:
            with pytest.raises(flatline.StateError, match="open"):
                bus.set_frames(0, None)  # the C bus refuses while the camera is open
            cam.start()
            done = threading.Event()
            box = []
            worker = threading.Thread(target=lambda: (box.append(cam.next()), done.set()))
            with sim._lock:  # held elsewhere: next() must wait for it
                worker.start()
                assert not done.wait(0.2)
            worker.join(5.0)
            assert done.is_set()
            assert np.array_equal(box[0].pixels, want.image)
