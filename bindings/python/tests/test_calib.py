# SPDX-License-Identifier: Apache-2.0
"""The calibration model through Python: the reference sensor, setters and
getters, finishing, files (round trip and every error mapping), mapping,
estimation of homographies and intrinsics, lifetime."""

import glob
import os
import pickle
import re
import threading

import numpy as np
import pytest

import flatline
from flatline import capi

from conftest import CALIBRATION_DATA, bits, read_png

REFERENCE_FX = 6.0 / 0.0055  # f = 6 mm over 5.5 um pixels, px


@pytest.fixture(scope="module")
def reference():
    return flatline.Calibration.reference()


def plane_grid(x_step=100.0, z_step=25.0):
    """(x, z) points of a laser plane target, mm: -1000..1000 across, -50..50
    up (the reference camera sees +-1 m of width and +-50 mm of height)."""
    x, z = np.meshgrid(np.arange(-1000, 1001, x_step), np.arange(-50, 51, z_step))
    return np.column_stack([x.ravel(), z.ravel()])


def copy_of(calib):
    """An unfinished model with every part of `calib`, set through the
    setters."""
    out = flatline.Calibration()
    out.frame_size = calib.frame_size
    out.intrinsics = calib.intrinsics
    for laser in (0, 1):
        out.set_homography(laser, calib.homography(laser))
    out.laser_offsets = calib.laser_offsets
    out.encoder_scale = calib.encoder_scale
    out.fiber_grid = calib.fiber_grid
    return out


# --- the reference sensor and the accessors ------------------------------------


def test_reference_sensor_is_the_documented_one(reference):
    assert reference.finished
    assert reference.frame_size == (2048, 2048)
    cam = reference.intrinsics
    assert cam.fx == pytest.approx(REFERENCE_FX, rel=1e-12) and cam.fy == cam.fx
    assert (cam.cx, cam.cy) == (1030.25, 1019.75)
    assert (cam.k1, cam.k2, cam.p1, cam.p2, cam.k3) == (-0.08, 0.012, 1.5e-4, -1e-4, -0.002)
    assert (cam.k4, cam.k5, cam.k6) == (0.0, 0.0, 0.0)
    assert reference.laser_offsets == (-50.0, 50.0)
    assert reference.laser_spacing == 100.0
    assert reference.encoder_scale == 0.01
    assert reference.fiber_grid == (-1000.0, 2.0, 1001)
    x = reference.fiber_x
    assert x.shape == (1001,) and x[0] == -1000.0 and x[-1] == 1000.0
    # The header's numbers: at z = 0 the lines lie near rows 1044 (laser 0)
    # and 996 (laser 1), and +1 mm moves them about 0.48 px up.
    rows = [reference.plane_to_image(laser, [[0.0, 0.0], [0.0, 1.0]])[:, 1] for laser in (0, 1)]
    assert rows[0][0] == pytest.approx(1044, abs=1) and rows[1][0] == pytest.approx(996, abs=1)
    assert rows[0][0] - rows[0][1] == pytest.approx(0.48, abs=0.01)


def test_roi_reference_moves_the_principal_point():
    roi = flatline.Calibration.reference(892, 256, -500.0, 10.0, 101)
    assert roi.frame_size == (2048, 256)
    assert roi.intrinsics.cy == 1019.75 - 892
    assert roi.fiber_grid == (-500.0, 10.0, 101)


def test_intrinsics_value_type():
    cam = flatline.Intrinsics(fx=1000.0, fy=1001.0, cx=640.0, cy=480.0, k1=-0.1, p2=0.002,
                              k6=0.5)
    np.testing.assert_array_equal(cam.camera_matrix,
                                  [[1000, 0, 640], [0, 1001, 480], [0, 0, 1]])
    # OpenCV's order: k1 k2 p1 p2 k3 k4 k5 k6
    np.testing.assert_array_equal(cam.distortion, [-0.1, 0, 0, 0.002, 0, 0, 0, 0.5])
    assert flatline.Intrinsics.from_arrays(cam.camera_matrix, cam.distortion) == cam
    assert flatline.Intrinsics(**cam.as_dict()) == cam
    assert flatline.Intrinsics.from_arrays([1000, 1001, 640, 480], [-0.1]).k1 == -0.1


def test_setters_then_finish_give_the_same_model_bit_for_bit(reference):
    calib = copy_of(reference)
    assert not calib.finished
    calib.finish()
    assert calib.finished
    # Every value went through Python and back exactly: the saved text, which
    # holds every double to 17 digits, is identical.
    assert calib.dumps() == reference.dumps()
    for laser in (0, 1):
        np.testing.assert_array_equal(bits(calib.homography(laser)),
                                      bits(reference.homography(laser)))


def test_intrinsics_accept_a_dict_or_keywords_with_zero_default_distortion():
    calib = flatline.Calibration()
    calib.intrinsics = {"fx": 900.0, "fy": 901.0, "cx": 500.0, "cy": 400.0, "k1": -0.05}
    assert calib.intrinsics == flatline.Intrinsics(900.0, 901.0, 500.0, 400.0, k1=-0.05)
    calib.set_intrinsics(fx=800, fy=800, cx=1, cy=2)
    assert calib.intrinsics.distortion.tolist() == [0.0] * 8
    with pytest.raises(TypeError, match="unexpected key 'f'"):
        calib.intrinsics = {"f": 1.0, "fx": 1, "fy": 1, "cx": 0, "cy": 0}
    with pytest.raises(TypeError, match="missing 'cy'"):
        calib.set_intrinsics(fx=800, fy=800, cx=1)


def test_finish_names_the_first_missing_part_and_stays_usable(reference):
    calib = flatline.Calibration()
    with pytest.raises(flatline.StateError, match="lacks the frame size") as info:
        calib.finish()
    assert info.value.status == capi.FLT_ERR_STATE
    calib.frame_size = reference.frame_size
    with pytest.raises(flatline.StateError, match="lacks the intrinsics"):
        calib.finish()
    calib.intrinsics = reference.intrinsics
    calib.set_homography(0, reference.homography(0))
    with pytest.raises(flatline.StateError, match="lacks laser 1's homography"):
        calib.finish()
    assert not calib.finished


def test_getters_of_unset_parts_are_state_errors():
    calib = flatline.Calibration()
    for get, needle in [(lambda: calib.frame_size, "frame size is not set"),
                        (lambda: calib.intrinsics, "intrinsics are not set"),
                        (lambda: calib.homography(1), "laser 1's homography is not set"),
                        (lambda: calib.laser_offset(0), "laser 0's offset is not set"),
                        (lambda: calib.laser_spacing, "both laser offsets must be set"),
                        (lambda: calib.encoder_scale, "encoder scale is not set"),
                        (lambda: calib.fiber_grid, "fiber grid is not set")]:
        with pytest.raises(flatline.StateError, match=needle):
            get()


def test_setters_on_a_finished_model_are_state_errors_and_change_nothing(reference):
    calib = flatline.Calibration.loads(reference.dumps())
    before = calib.dumps()
    setters = [
        lambda: setattr(calib, "frame_size", (640, 480)),
        lambda: setattr(calib, "intrinsics", reference.intrinsics),
        lambda: calib.set_homography(0, np.eye(3)),
        lambda: calib.set_laser_offset(1, 60.0),
        lambda: setattr(calib, "encoder_scale", 0.02),
        lambda: setattr(calib, "fiber_grid", (0.0, 1.0, 10)),
        lambda: calib.estimate_homography(0, np.zeros((4, 2)), np.zeros((4, 2))),
        lambda: calib.estimate_intrinsics([], columns=9, rows=6, pitch_mm=60),
        calib.finish,
    ]
    for setter in setters:
        with pytest.raises(flatline.StateError, match="finished and immutable") as info:
            setter()
        assert info.value.status == -3 and isinstance(info.value, RuntimeError)
    assert calib.dumps() == before


def test_bad_values_are_invalid_arguments_naming_them():
    calib = flatline.Calibration()
    with pytest.raises(flatline.InvalidArgumentError, match=r"camera\[0\] \(fx\)' = nan"):
        calib.set_intrinsics(fx=float("nan"), fy=1.0, cx=0.0, cy=0.0)
    with pytest.raises(flatline.InvalidArgumentError, match="fx = -5, fy = 1"):
        calib.set_intrinsics(fx=-5.0, fy=1.0, cx=0.0, cy=0.0)
    with pytest.raises(flatline.InvalidArgumentError, match=r"'distortion\[4\]' = inf"):
        calib.set_intrinsics(fx=1.0, fy=1.0, cx=0.0, cy=0.0, k3=float("inf"))
    with pytest.raises(flatline.InvalidArgumentError, match="'offset_mm' = nan"):
        calib.set_laser_offset(1, float("nan"))
    with pytest.raises(ValueError, match=r"'laser_offsets\[1\]' = inf"):
        calib.laser_offsets = (0.0, float("inf"))
    with pytest.raises(flatline.StateError):  # both or neither: laser 0 was not set
        calib.laser_offset(0)
    with pytest.raises(flatline.InvalidArgumentError, match="not invertible"):
        calib.set_homography(0, np.ones((3, 3)))
    with pytest.raises(flatline.InvalidArgumentError):
        calib.encoder_scale = 0.0
    with pytest.raises(flatline.InvalidArgumentError):
        calib.fiber_grid = (0.0, -2.0, 10)
    with pytest.raises(flatline.InvalidArgumentError):
        calib.frame_size = (0, 480)
    # Caught in Python, with the argument's name:
    with pytest.raises(ValueError, match=r"'laser' must be in \[0, 1\], got 2"):
        calib.set_laser_offset(2, 0.0)
    with pytest.raises(TypeError, match="'laser' must be an int"):
        calib.homography(0.0)
    with pytest.raises(ValueError, match=r"'h' must have shape \(3, 3\)"):
        calib.set_homography(0, np.eye(4))
    with pytest.raises(TypeError, match="'offset_mm' must be a real number"):
        calib.set_laser_offset(0, "50")
    with pytest.raises(TypeError, match="pair"):
        calib.frame_size = 640
    # ...and the library's own check of the laser index, through the raw layer.
    with pytest.raises(flatline.InvalidArgumentError, match="'laser' = 2 is not 0 or 1"):
        capi.flt_calib_set_laser_offset(calib._live(), 2, 0.0)


# --- files ----------------------------------------------------------------------


def test_save_load_save_is_byte_identical(reference, tmp_path):
    first = tmp_path / "sensor.json"
    reference.save(first)  # a pathlib.Path
    text = first.read_bytes()
    assert text == reference.dumps().encode()
    assert text.startswith(b'{\n  "format": "flatline-calibration",\n  "version": 1,')
    loaded = flatline.Calibration.load(str(first))  # a str
    assert loaded.finished
    second = tmp_path / "again.json"
    loaded.save(os.fsencode(second))  # bytes
    assert second.read_bytes() == text
    assert flatline.Calibration.loads(text).dumps() == text.decode()
    assert flatline.Calibration.loads(text.decode()).dumps() == text.decode()
    assert not list(tmp_path.glob("*.tmp"))  # the temporary files were renamed


def test_malformed_file_is_a_format_error_naming_the_field(reference, tmp_path):
    path = tmp_path / "bad.json"
    good = reference.dumps()
    cases = [
        (good.replace('"pitch_mm": 2', '"pitch_mm": "2"'), "field 'fibers.pitch_mm'"),
        (good.replace('"width": 2048', '"width": 2048.5'), "'frame.width' = 2048.5 must be a whole"),
        (re.sub(r'"k1": [^,]*', '"k1": 1e999', good), "'camera.distortion.k1' = 1e999"),
        (good.replace('"version": 1', '"version": 2'), "'version' = 2"),
        (good.replace('"fy"', '"fz"'), "unknown field 'camera.fz'"),
        (good.replace("-0.0013260955154821112", '"x"'), "lasers[0].homography[4]"),
        (good[: len(good) // 2], "truncated"),
    ]
    for text, needle in cases:
        path.write_text(text)
        with pytest.raises(flatline.FormatError) as info:
            flatline.Calibration.load(path)
        assert needle in info.value.message, (needle, info.value.message)
        assert str(path) in info.value.message
        assert info.value.status == capi.FLT_ERR_FORMAT == -6
        assert isinstance(info.value, ValueError)
        with pytest.raises(flatline.FormatError, match=re.escape(needle)):
            flatline.Calibration.loads(text)
    with pytest.raises(flatline.FormatError, match="empty"):
        flatline.Calibration.loads("")


def test_missing_file_is_a_file_error_and_unwritable_path_too(reference, tmp_path):
    missing = tmp_path / "nowhere" / "sensor.json"
    with pytest.raises(flatline.FileError, match="cannot open") as info:
        flatline.Calibration.load(missing)
    assert info.value.status == capi.FLT_ERR_IO == -5
    assert isinstance(info.value, OSError) and str(missing) in info.value.message
    with pytest.raises(flatline.FileError, match="cannot create"):
        reference.save(missing)
    with pytest.raises(ValueError, match="NUL"):
        flatline.Calibration.load("a\0b")
    with pytest.raises(TypeError, match="'path'"):
        flatline.Calibration.load(3.5)
    with pytest.raises(TypeError, match="str or bytes"):
        flatline.Calibration.loads(42)


def test_unfinished_model_cannot_be_saved_or_map(reference, tmp_path):
    calib = copy_of(reference)
    for call in (calib.dumps, lambda: calib.save(tmp_path / "x.json"),
                 lambda: calib.image_to_plane(0, [[1.0, 2.0]]),
                 lambda: calib.plane_to_image(1, [[1.0, 2.0]])):
        with pytest.raises(flatline.StateError, match="not finished"):
            call()
    with pytest.raises(TypeError, match="finished"):
        pickle.dumps(calib)
    # undistort needs only the intrinsics.
    # The principal point has no distortion: it maps to itself (to the
    # Newton solve's 1e-9 px).
    np.testing.assert_allclose(calib.undistort([[1030.25, 1019.75]]), [[1030.25, 1019.75]],
                               rtol=0, atol=1e-9)


def test_finished_model_pickles_as_its_text(reference):
    clone = pickle.loads(pickle.dumps(reference))
    assert clone is not reference and clone.dumps() == reference.dumps()


# --- mapping ----------------------------------------------------------------------


def test_plane_to_image_and_back_is_the_identity(reference):
    # The inverse distortion is solved to ~1e-9 px; 1 px is at most ~2 mm on
    # the plane at the frame's edge (1 mm ~ 0.48 px in height), so 1e-6 mm
    # bounds the round trip with three decades of margin.
    points = plane_grid()
    for laser in (0, 1):
        image = reference.plane_to_image(laser, points)
        assert image.shape == points.shape and np.isfinite(image).all()
        assert (image[:, 0] > 0).all() and (image[:, 0] < 2047).all()
        back = reference.image_to_plane(laser, image)
        assert np.abs(back - points).max() < 1e-6


def test_undistort_gives_the_pinhole_image_of_the_homography(reference):
    # Undistorted points are H^-1 (x, z, 1): the homography maps undistorted
    # pixels to the plane. Agreement to 1e-6 px (the Newton solve reaches 1e-9).
    points = plane_grid(200.0, 50.0)
    h = reference.homography(0)
    pinhole = np.linalg.solve(h, np.column_stack([points, np.ones(len(points))]).T).T
    pinhole = pinhole[:, :2] / pinhole[:, 2:]
    undistorted = reference.undistort(reference.plane_to_image(0, points))
    assert np.abs(undistorted - pinhole).max() < 1e-6


def test_nan_points_stay_nan_and_empty_batches_are_fine(reference):
    out = reference.image_to_plane(0, [[np.nan, 1000.0], [1000.0, 1044.0]])
    assert np.isnan(out[0]).all() and np.isfinite(out[1]).all()
    assert reference.plane_to_image(1, np.zeros((0, 2))).shape == (0, 2)
    assert reference.undistort(np.empty((0, 2))).shape == (0, 2)


def test_mapping_arguments_are_checked_with_their_name(reference):
    with pytest.raises(ValueError, match=r"'points' must have shape \(N, 2\), got \(4, 3\)"):
        reference.image_to_plane(0, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="'points' must have 2 dimensions"):
        reference.undistort([1.0, 2.0])
    with pytest.raises(TypeError, match="'points' has dtype complex128"):
        reference.plane_to_image(0, np.zeros((2, 2), complex))
    with pytest.raises(ValueError, match="'laser'"):
        reference.image_to_plane(-1, np.zeros((1, 2)))
    # The raw layer refuses inconsistent arrays itself.
    with pytest.raises(flatline.InvalidArgumentError, match=r"plane_out.shape\[0\] is 2 but should be 3"):
        reference._live().image_to_plane_into(0, np.zeros((3, 2)), np.zeros((2, 2)))
    with pytest.raises(TypeError):  # numpy.i: the output must be float64 in place
        reference._live().undistort_into(np.zeros((3, 2)), np.zeros((3, 2), np.float32))


def test_any_array_like_maps_like_c_contiguous_float64(reference):
    points = plane_grid()
    want = reference.plane_to_image(1, points)
    for variant in (points.tolist(), np.asfortranarray(points), points.astype(">f8"),
                    np.repeat(points, 2, axis=0)[::2]):
        np.testing.assert_array_equal(bits(reference.plane_to_image(1, variant)), bits(want))
    ints = plane_grid().astype(np.int64)  # exact in float64
    np.testing.assert_array_equal(bits(reference.plane_to_image(1, ints)), bits(want))


def test_one_finished_model_maps_in_parallel_threads_like_serially(reference):
    rng = np.random.default_rng(3)
    batches = [rng.uniform([0, 900], [2047, 1100], (200_000, 2)) for _ in range(2)]
    serial = [reference.image_to_plane(i, b) for i, b in enumerate(batches)]
    results = [None, None]
    barrier = threading.Barrier(2)

    def work(i):
        barrier.wait()
        for _ in range(3):
            results[i] = reference.image_to_plane(i, batches[i])

    threads = [threading.Thread(target=work, args=(i,)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for got, want in zip(results, serial):
        np.testing.assert_array_equal(bits(got), bits(want))


# --- estimation ----------------------------------------------------------------------


def test_estimate_homography_recovers_the_reference_plane(reference):
    # Exact correspondences of the reference sensor: the estimate maps like
    # the reference to 1e-6 mm (LM converges to rounding; 1 px ~ 2 mm).
    plane = plane_grid()
    calib = flatline.Calibration()
    calib.frame_size = reference.frame_size
    calib.intrinsics = reference.intrinsics
    image = reference.plane_to_image(1, plane)
    fit = calib.estimate_homography(1, image, plane)
    assert isinstance(fit, flatline.HomographyFit)
    assert fit.rms_px < 1e-6 and fit.rms_mm < 1e-6
    assert fit.residual_px.shape == fit.residual_mm.shape == fit.inliers.shape == (len(plane),)
    assert fit.inliers.dtype == np.bool_ and fit.inliers.all()
    h = fit.homography / fit.homography[2, 2]
    want = reference.homography(1) / reference.homography(1)[2, 2]
    assert np.abs(h - want).max() <= 1e-9 * np.abs(want).max()
    np.testing.assert_array_equal(fit.homography, calib.homography(1))


def test_ransac_flags_exactly_the_outliers(reference):
    # 1/16 px of noise on every point and 8 mis-identified points 5-20 px off:
    # RANSAC (threshold 1 px, 16 sigma of the noise) keeps all the others,
    # and the RMS over inliers is the noise's (0.0625 * sqrt(2) = 0.088 px
    # per point, less the fit's absorbed share).
    rng = np.random.default_rng(7)
    plane = plane_grid()
    image = reference.plane_to_image(0, plane) + rng.normal(0, 1 / 16, (len(plane), 2))
    bad = rng.choice(len(plane), 8, replace=False)
    image[bad] += rng.uniform(5, 20, (8, 2)) * rng.choice([-1, 1], (8, 2))
    calib = flatline.Calibration()
    calib.intrinsics = reference.intrinsics
    fit = calib.estimate_homography(0, image, plane, ransac=True, calib_ransac_seed=3)
    expected = np.ones(len(plane), bool)
    expected[bad] = False
    np.testing.assert_array_equal(fit.inliers, expected)
    assert 0.04 < fit.rms_px < 0.1
    assert (fit.residual_px[bad] > 4).all()
    # Without RANSAC the outliers spoil the fit.
    plain = calib.estimate_homography(0, image, plane)
    assert plain.inliers.all() and plain.rms_px > 1.0
    # Deterministic: the same seed gives the same bits.
    again = calib.estimate_homography(0, image, plane, ransac=True, calib_ransac_seed=3)
    np.testing.assert_array_equal(bits(again.residual_px), bits(fit.residual_px))
    with pytest.raises(TypeError, match="'ransac=True'"):
        calib.estimate_homography(0, image, plane, calib_ransac=1)
    with pytest.raises(TypeError, match="another component"):
        calib.estimate_homography(0, image, plane, sim_seed=1)
    with pytest.raises(flatline.InvalidArgumentError, match="calib_ransac_threshold"):
        calib.estimate_homography(0, image, plane, ransac=True, calib_ransac_threshold=-1)


def test_degenerate_correspondences_are_numeric_errors_leaving_the_model(reference):
    calib = flatline.Calibration()
    calib.intrinsics = reference.intrinsics
    line = np.column_stack([np.linspace(-500, 500, 10), np.zeros(10)])  # collinear
    with pytest.raises(flatline.NumericError) as info:
        calib.estimate_homography(0, reference.plane_to_image(0, line), line)
    assert info.value.status == -10 and isinstance(info.value, ArithmeticError)
    with pytest.raises(flatline.InvalidArgumentError, match="'count' = 3; a homography needs"):
        calib.estimate_homography(0, np.zeros((3, 2)), np.ones((3, 2)))
    with pytest.raises(flatline.StateError):  # nothing was stored
        calib.homography(0)
    with pytest.raises(ValueError, match="'plane_points' has shape"):
        calib.estimate_homography(0, np.zeros((5, 2)), np.zeros((4, 2)))
    with pytest.raises(flatline.StateError, match="intrinsics"):  # they come first
        flatline.Calibration().estimate_homography(0, line, line)


@pytest.fixture(scope="module")
def chessboard_views():
    paths = sorted(glob.glob(os.path.join(CALIBRATION_DATA, "view_*.png")))
    assert len(paths) == 10
    return [read_png(p) for p in paths]


def test_estimate_intrinsics_from_the_example_chessboards(chessboard_views):
    # examples/calibrate/data: 10 views of a 9 x 6 inner-corner chessboard,
    # 60 mm squares, through the binned reference camera (fx = 545.45 px,
    # principal point (515.25, 509.75)). The C test's bounds: focal length
    # within 0.5 %, RMS reprojection error below 0.1 px.
    truth = dict(fx=6.0 / 0.011, cx=515.25, cy=509.75, k1=-0.08)
    blank = np.full((1024, 1024), 128, np.uint8)  # a view without a target
    calib = flatline.Calibration()
    calib.frame_size = (1024, 1024)
    fit = calib.estimate_intrinsics(chessboard_views + [blank], pattern="chessboard",
                                    columns=9, rows=6, pitch_mm=60.0)
    assert isinstance(fit, flatline.IntrinsicsFit)
    assert fit.rms_px < 0.1
    assert fit.view_rms_px.shape == (11,)
    assert np.isfinite(fit.view_rms_px[:10]).all() and np.isnan(fit.view_rms_px[10])
    assert (fit.view_rms_px[:10] < 0.2).all()
    cam = calib.intrinsics
    assert cam == fit.intrinsics
    assert abs(cam.fx / truth["fx"] - 1) < 0.005 and abs(cam.fy / truth["fx"] - 1) < 0.005
    assert abs(cam.cx - truth["cx"]) < 2 and abs(cam.cy - truth["cy"]) < 2
    assert abs(cam.k1 - truth["k1"]) < 0.01
    # A (views, height, width) block gives the same estimate bit for bit (and
    # is passed without a copy).
    stack = np.stack(chessboard_views)
    again = flatline.Calibration()
    again.frame_size = (1024, 1024)
    fit2 = again.estimate_intrinsics(stack, pattern=flatline.Target.CHESSBOARD, columns=9,
                                     rows=6, pitch_mm=60.0)
    assert fit2.rms_px == fit.rms_px and again.intrinsics == cam


def test_estimate_intrinsics_errors(chessboard_views):
    calib = flatline.Calibration()
    args = dict(columns=9, rows=6, pitch_mm=60.0)
    with pytest.raises(flatline.StateError, match="frame size"):
        calib.estimate_intrinsics(chessboard_views, **args)
    calib.frame_size = (1024, 1024)
    blank = np.full((1024, 1024), 128, np.uint8)
    with pytest.raises(flatline.NumericError, match="found in 0 of 3 views") as info:
        calib.estimate_intrinsics([blank] * 3, **args)
    assert info.value.status == capi.FLT_ERR_NUMERIC
    with pytest.raises(flatline.StateError):  # the model is unchanged
        calib.intrinsics
    with pytest.raises(TypeError, match=r"'images\[1\]' has dtype uint16"):
        calib.estimate_intrinsics([blank, blank.astype(np.uint16)], **args)
    with pytest.raises(ValueError, match=r"'images\[0\]' has shape \(512, 1024\)"):
        calib.estimate_intrinsics([blank[:512]], **args)
    with pytest.raises(ValueError, match="'pattern' = 'checkerboard' is not one of"):
        calib.estimate_intrinsics([blank], pattern="checkerboard", **args)
    with pytest.raises(flatline.InvalidArgumentError, match="'views' is 0"):
        calib.estimate_intrinsics([], **args)
    with pytest.raises(flatline.InvalidArgumentError, match="'columns' = 2 is outside"):
        calib.estimate_intrinsics([blank], columns=2, rows=6, pitch_mm=60.0)
    with pytest.raises(flatline.InvalidArgumentError, match="'pitch_mm' = nan"):
        calib.estimate_intrinsics([blank], columns=9, rows=6, pitch_mm=float("nan"))
    with pytest.raises(flatline.InvalidArgumentError, match="'target' = 7"):
        calib.estimate_intrinsics([blank], pattern=7, **args)
    with pytest.raises(TypeError, match="sequence"):
        calib.estimate_intrinsics(blank, **args)  # one 2-D image, not a list


# --- lifetime -------------------------------------------------------------------------


def test_close_and_context_manager():
    with flatline.Calibration.reference() as calib:
        assert not calib.closed and "finished frame=2048x2048" in repr(calib)
    assert calib.closed and repr(calib) == "<flatline.Calibration closed>"
    with pytest.raises(flatline.StateError, match="closed"):
        calib.fiber_grid
    calib.close()  # idempotent
    assert repr(flatline.Calibration()) == "<flatline.Calibration unfinished>"
