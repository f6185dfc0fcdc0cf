// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/calib.h: the calibration model.
 *
 * Wrapped as they are: create, finish, is_finished, the scalar setters and
 * getters (frame size, laser offsets, laser spacing, encoder scale, fiber
 * grid) and load / load_text (a path or a str; both return a new, owned
 * handle). The calls with arrays (intrinsics, homographies, estimation,
 * mapping) and save_text are replaced by methods with numpy.i's argument
 * patterns; estimation and mapping release the GIL, so threads can map
 * through one finished model at once (it is immutable).
 *
 * The Python layer (flatline/_calib.py) validates its inputs first, with
 * messages naming the argument; the checks here keep direct callers of the
 * raw layer from passing arrays that disagree with each other.
 */

%ignore flt_calib_destroy;
%ignore flt_calib_set_intrinsics;
%ignore flt_calib_get_intrinsics;
%ignore flt_calib_estimate_intrinsics;
%ignore flt_calib_set_homography;
%ignore flt_calib_get_homography;
%ignore flt_calib_estimate_homography;
%ignore flt_calib_image_to_plane;
%ignore flt_calib_plane_to_image;
%ignore flt_calib_undistort;
%ignore flt_calib_save_text;

%typemap(in, numinputs=0) flt_calib **out (flt_calib *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_calib **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_calib *), SWIG_POINTER_OWN));
}

/* flt_calib_load_text takes a str with its length (embedded NULs and all). */
%apply (char *STRING, size_t LENGTH) { (const char *text, size_t length) };

%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *camera, size_t camera_count),
  (const double *distortion, size_t distortion_count)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *camera_out, size_t camera_out_count),
  (double *distortion_out, size_t distortion_out_count),
  (double *view_rms_px_out, size_t view_rms_px_out_count),
  (double *residual_px_out, size_t residual_px_out_count),
  (double *residual_mm_out, size_t residual_mm_out_count)
};
%apply (unsigned char *INPLACE_ARRAY1, size_t DIM1) {
  (unsigned char *inlier_out, size_t inlier_out_count)
};
%apply (double *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const double *h, size_t h_rows, size_t h_cols),
  (const double *points, size_t points_count, size_t points_dims),
  (const double *image_px, size_t image_count, size_t image_dims),
  (const double *plane_mm, size_t plane_count, size_t plane_dims)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *h_out, size_t h_out_rows, size_t h_out_cols),
  (double *points_out, size_t points_out_count, size_t points_out_dims)
};
%apply (unsigned char *IN_ARRAY3, size_t DIM1, size_t DIM2, size_t DIM3) {
  (const unsigned char *images, size_t views, size_t image_rows, size_t image_cols)
};

/* save_text's result: a new bytes object (UTF-8 JSON). */
%typemap(in, numinputs=0) PyObject **text_out (PyObject *temp = NULL) { $1 = &temp; }
%typemap(argout) PyObject **text_out { %append_output(*$1); }

%{
/* (count, 2) point arrays: the second dimension is the (u, v) or (x, z) pair. */
static flt_status flt_py_check_points(const char *function, const char *name,
                                      size_t dims, size_t count,
                                      size_t expected_count) {
    char what[64];
    if (dims != 2) {
        PyOS_snprintf(what, sizeof what, "%s.shape[1]", name);
        return flt_py_shape_error(function, what, dims, 2);
    }
    if (count != expected_count) {
        PyOS_snprintf(what, sizeof what, "%s.shape[0]", name);
        return flt_py_shape_error(function, what, count, expected_count);
    }
    return FLT_OK;
}
%}

%nodefaultctor flt_calib;
struct flt_calib {};
%extend flt_calib {
  ~flt_calib() { flt_calib_destroy($self); }

  /* camera (4,) fx fy cx cy px; distortion (8,) in OpenCV order. */
  flt_status set_intrinsics_array(const double *camera, size_t camera_count,
                                  const double *distortion, size_t distortion_count) {
    if (camera_count != 4)
        return flt_py_shape_error("flt_calib_set_intrinsics", "camera.shape[0]",
                                  camera_count, 4);
    if (distortion_count != FLT_CALIB_DISTORTION_COEFFS)
        return flt_py_shape_error("flt_calib_set_intrinsics", "distortion.shape[0]",
                                  distortion_count, FLT_CALIB_DISTORTION_COEFFS);
    return flt_calib_set_intrinsics($self, camera, camera_count, distortion, distortion_count);
  }

  flt_status get_intrinsics_into(double *camera_out, size_t camera_out_count,
                                 double *distortion_out, size_t distortion_out_count) {
    if (camera_out_count != 4)
        return flt_py_shape_error("flt_calib_get_intrinsics", "camera_out.shape[0]",
                                  camera_out_count, 4);
    if (distortion_out_count != FLT_CALIB_DISTORTION_COEFFS)
        return flt_py_shape_error("flt_calib_get_intrinsics", "distortion_out.shape[0]",
                                  distortion_out_count, FLT_CALIB_DISTORTION_COEFFS);
    return flt_calib_get_intrinsics($self, camera_out, camera_out_count, distortion_out,
                                    distortion_out_count);
  }

  /* images (views, height, width) uint8, one C-contiguous block: view i
   * starts at images + i * height * width, rows width bytes apart. Writes
   * each view's RMS into view_rms_px_out (views,) and returns the overall
   * RMS, px. The GIL is released (detection and calibrateCamera take
   * seconds). */
  flt_status estimate_intrinsics_stack(const unsigned char *images, size_t views,
                                       size_t image_rows, size_t image_cols,
                                       int target, unsigned columns, unsigned rows,
                                       double pitch_mm, const flt_options *options,
                                       double *view_rms_px_out,
                                       size_t view_rms_px_out_count, double *rms_px_out) {
    const uint8_t **pointers;
    uint32_t width = 0, height = 0;
    flt_status status;
    size_t i;
    if (view_rms_px_out_count != views)
        return flt_py_shape_error("flt_calib_estimate_intrinsics",
                                  "view_rms_px_out.shape[0]", view_rms_px_out_count,
                                  views);
    /* The C API reads `height` rows of each image: the stack must have the
     * frame size, or it would read past the end of the block. */
    if (flt_calib_get_frame_size($self, &width, &height) != FLT_OK)
        /* No frame size yet: the library's own check says so (it looks at
         * the frame size before the images). */
        return flt_calib_estimate_intrinsics($self, views, NULL, 0,
                                             (flt_calib_target)target, columns, rows,
                                             pitch_mm, options, rms_px_out, NULL);
    if (image_rows != height)
        return flt_py_shape_error("flt_calib_estimate_intrinsics",
                                  "images.shape[1] (rows)", image_rows, height);
    if (image_cols != width)
        return flt_py_shape_error("flt_calib_estimate_intrinsics",
                                  "images.shape[2] (columns)", image_cols, width);
    if (views == 0)  /* the library names it */
        return flt_calib_estimate_intrinsics($self, 0, NULL, width,
                                             (flt_calib_target)target, columns, rows,
                                             pitch_mm, options, rms_px_out, NULL);
    pointers = (const uint8_t **)PyMem_Malloc(views * sizeof *pointers);
    if (pointers == NULL) {
        PyErr_NoMemory();
        return FLT_ERR_OUT_OF_MEMORY;
    }
    for (i = 0; i < views; ++i) pointers[i] = images + i * image_rows * image_cols;
    Py_BEGIN_ALLOW_THREADS
    status = flt_calib_estimate_intrinsics($self, views, pointers, image_cols,
                                           (flt_calib_target)target, columns, rows,
                                           pitch_mm, options, rms_px_out,
                                           view_rms_px_out);
    Py_END_ALLOW_THREADS
    PyMem_Free(pointers);
    return status;
  }

  flt_status set_homography_array(unsigned laser, const double *h, size_t h_rows,
                                  size_t h_cols) {
    if (h_rows != 3)
        return flt_py_shape_error("flt_calib_set_homography", "h.shape[0]", h_rows, 3);
    if (h_cols != 3)
        return flt_py_shape_error("flt_calib_set_homography", "h.shape[1]", h_cols, 3);
    return flt_calib_set_homography($self, laser, h, h_rows * h_cols);
  }

  flt_status get_homography_into(unsigned laser, double *h_out, size_t h_out_rows,
                                 size_t h_out_cols) {
    if (h_out_rows != 3 || h_out_cols != 3)
        return flt_py_shape_error("flt_calib_get_homography", "h_out.size",
                                  h_out_rows * h_out_cols, 9);
    return flt_calib_get_homography($self, laser, h_out, h_out_rows * h_out_cols);
  }

  /* image_px and plane_mm (N, 2); residuals (N,), inliers (N,) uint8.
   * Returns (rms_px, rms_mm). The GIL is released (RANSAC + LM). */
  flt_status estimate_homography_arrays(unsigned laser,
                                        const double *image_px, size_t image_count,
                                        size_t image_dims,
                                        const double *plane_mm, size_t plane_count,
                                        size_t plane_dims, const flt_options *options,
                                        double *residual_px_out,
                                        size_t residual_px_out_count,
                                        double *residual_mm_out,
                                        size_t residual_mm_out_count,
                                        unsigned char *inlier_out,
                                        size_t inlier_out_count, double *rms_px_out,
                                        double *rms_mm_out) {
    const char *fn = "flt_calib_estimate_homography";
    flt_status status;
    if ((status = flt_py_check_points(fn, "image_px", image_dims, image_count,
                                      image_count)) != FLT_OK ||
        (status = flt_py_check_points(fn, "plane_mm", plane_dims, plane_count,
                                      image_count)) != FLT_OK)
        return status;
    if (residual_px_out_count != image_count)
        return flt_py_shape_error(fn, "residual_px_out.shape[0]", residual_px_out_count,
                                  image_count);
    if (residual_mm_out_count != image_count)
        return flt_py_shape_error(fn, "residual_mm_out.shape[0]", residual_mm_out_count,
                                  image_count);
    if (inlier_out_count != image_count)
        return flt_py_shape_error(fn, "inlier_out.shape[0]", inlier_out_count,
                                  image_count);
    Py_BEGIN_ALLOW_THREADS
    status = flt_calib_estimate_homography($self, laser, image_count, image_px, plane_mm,
                                           options, residual_px_out, residual_mm_out,
                                           inlier_out, rms_px_out, rms_mm_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The three batch maps: points (N, 2) in, points_out (N, 2) filled. */
  flt_status image_to_plane_into(unsigned laser, const double *points,
                                 size_t points_count, size_t points_dims,
                                 double *points_out, size_t points_out_count,
                                 size_t points_out_dims) {
    const char *fn = "flt_calib_image_to_plane";
    flt_status status;
    if ((status = flt_py_check_points(fn, "image_px", points_dims, points_count,
                                      points_count)) != FLT_OK ||
        (status = flt_py_check_points(fn, "plane_out", points_out_dims,
                                      points_out_count, points_count)) != FLT_OK)
        return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_calib_image_to_plane($self, laser, points_count, points, points_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status plane_to_image_into(unsigned laser, const double *points,
                                 size_t points_count, size_t points_dims,
                                 double *points_out, size_t points_out_count,
                                 size_t points_out_dims) {
    const char *fn = "flt_calib_plane_to_image";
    flt_status status;
    if ((status = flt_py_check_points(fn, "plane_mm", points_dims, points_count,
                                      points_count)) != FLT_OK ||
        (status = flt_py_check_points(fn, "image_out", points_out_dims,
                                      points_out_count, points_count)) != FLT_OK)
        return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_calib_plane_to_image($self, laser, points_count, points, points_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status undistort_into(const double *points, size_t points_count,
                            size_t points_dims, double *points_out,
                            size_t points_out_count, size_t points_out_dims) {
    const char *fn = "flt_calib_undistort";
    flt_status status;
    if ((status = flt_py_check_points(fn, "image_px", points_dims, points_count,
                                      points_count)) != FLT_OK ||
        (status = flt_py_check_points(fn, "undistorted_out", points_out_dims,
                                      points_out_count, points_count)) != FLT_OK)
        return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_calib_undistort($self, points_count, points, points_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The saved text as bytes (UTF-8 JSON), sized by a first call. */
  flt_status save_text_bytes(PyObject **text_out) {
    size_t length = 0;
    PyObject *text;
    flt_status status = flt_calib_save_text($self, NULL, 0, &length);
    if (status != FLT_ERR_BUFFER_FULL) return status;  /* e.g. not finished */
    /* A bytes object has room for a terminating NUL beyond its length. */
    text = PyBytes_FromStringAndSize(NULL, (Py_ssize_t)length);
    if (text == NULL) return FLT_ERR_OUT_OF_MEMORY;  /* MemoryError is set */
    status = flt_calib_save_text($self, PyBytes_AS_STRING(text), length + 1, &length);
    if (status != FLT_OK) {
        Py_DECREF(text);
        return status;
    }
    *text_out = text;
    return FLT_OK;
  }
}

%include "flatline/calib.h"
