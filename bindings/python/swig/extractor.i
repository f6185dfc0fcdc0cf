// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/extractor.h: camera frame -> one profile row (and the pixel
 * formats, which the simulator shares).
 *
 * Wrapped as they are: create, fibers and band. process, peaks and
 * laser_profiles are replaced by methods. Frames are passed as the numpy
 * array itself, not through numpy.i (whose IN_ARRAY typemaps would copy any
 * array that is not C-contiguous): any 2-D uint8 / uint16 array whose rows
 * are contiguous and in native byte order goes to C without a copy, with its
 * row stride, so a view of a wider buffer (an ROI, a padded camera buffer)
 * works too. process releases the GIL.
 */

%ignore flt_extractor_destroy;
%ignore flt_extractor_process;
%ignore flt_extractor_peaks;
%ignore flt_extractor_laser_profiles;
%ignore flt_extractor_fiber_flags;
%ignore flt_extractor_strip;
%ignore flt_extractor_saturation;

%typemap(in, numinputs=0) flt_extractor **out (flt_extractor *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_extractor **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_extractor *), SWIG_POINTER_OWN));
}

%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *row_height_out, size_t row_height_out_fibers),
  (double *row_slope_out, size_t row_slope_out_fibers)
};
%apply (unsigned char *INPLACE_ARRAY1, size_t DIM1) {
  (unsigned char *row_valid_out, size_t row_valid_out_fibers),
  (unsigned char *fiber_flags_out, size_t fiber_flags_out_fibers)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *strip_out, size_t strip_out_n),
  (double *saturation_out, size_t saturation_out_n)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *peak_rows_out, size_t peak_rows_out_lasers, size_t peak_rows_out_width),
  (double *laser_z_out, size_t laser_z_out_lasers, size_t laser_z_out_fibers)
};

%{
/* The pixels of a frame: a 2-D uint8 (Mono8) or uint16 (Mono10/12/16)
 * ndarray, aligned, native byte order, each row contiguous (stride of one
 * pixel along a row) and rows a positive stride apart. Sets TypeError or
 * ValueError naming 'frame' and returns a failure otherwise. */
static flt_status flt_py_frame(const char *function, PyObject *object, int format,
                               const void **pixels, uint32_t *width,
                               uint32_t *height, size_t *stride_bytes) {
    PyArrayObject *array;
    npy_intp item;
    const int wide = format != FLT_PIXEL_MONO8;
    if (!PyArray_Check(object)) {
        PyErr_Format(PyExc_TypeError, "%s: argument 'frame' must be a numpy array",
                     function);
        return FLT_ERR_INVALID_ARGUMENT;
    }
    array = (PyArrayObject *)object;
    if (PyArray_TYPE(array) != (wide ? NPY_USHORT : NPY_UBYTE) ||
        !PyArray_ISNOTSWAPPED(array)) {
        PyErr_Format(PyExc_TypeError,
                     "%s: argument 'frame' must be a native %s array for %d-bit "
                     "pixels", function, wide ? "uint16" : "uint8", format);
        return FLT_ERR_INVALID_ARGUMENT;
    }
    item = PyArray_ITEMSIZE(array);
    if (PyArray_NDIM(array) != 2 || PyArray_DIM(array, 0) < 1 ||
        PyArray_DIM(array, 1) < 1 || PyArray_DIM(array, 0) > 0xFFFFFFFFL ||
        PyArray_DIM(array, 1) > 0xFFFFFFFFL) {
        PyErr_Format(PyExc_ValueError, "%s: argument 'frame' must be a non-empty 2-D "
                     "array (height, width)", function);
        return FLT_ERR_INVALID_ARGUMENT;
    }
    if (!PyArray_ISALIGNED(array) || PyArray_STRIDE(array, 1) != item ||
        PyArray_STRIDE(array, 0) < PyArray_DIM(array, 1) * item) {
        PyErr_Format(PyExc_ValueError, "%s: argument 'frame' must be aligned with "
                     "contiguous rows (numpy.ascontiguousarray)", function);
        return FLT_ERR_INVALID_ARGUMENT;
    }
    *pixels = PyArray_DATA(array);
    *height = (uint32_t)PyArray_DIM(array, 0);
    *width = (uint32_t)PyArray_DIM(array, 1);
    *stride_bytes = (size_t)PyArray_STRIDE(array, 0);
    return FLT_OK;
}
%}

%nodefaultctor flt_extractor;
struct flt_extractor {};
%extend flt_extractor {
  ~flt_extractor() { flt_extractor_destroy($self); }

  /* One frame -> one row: height, slope (K,) and valid (K,) filled; returns
   * the row's material position s, mm. `frame` stays referenced by the
   * caller for the whole call, so releasing the GIL is safe. */
  flt_status process_frame(PyObject *frame, int format, double encoder_mm,
                           double *row_height_out, size_t row_height_out_fibers,
                           double *row_slope_out, size_t row_slope_out_fibers,
                           unsigned char *row_valid_out, size_t row_valid_out_fibers,
                           double *s_mm_out) {
    const char *fn = "flt_extractor_process";
    const void *pixels = NULL;
    uint32_t width = 0, height = 0;
    size_t stride = 0;
    flt_status status;
    if (row_slope_out_fibers != row_height_out_fibers)
        return flt_py_shape_error(fn, "slope_out.shape[0]", row_slope_out_fibers,
                                  row_height_out_fibers);
    if (row_valid_out_fibers != row_height_out_fibers)
        return flt_py_shape_error(fn, "valid_out.shape[0]", row_valid_out_fibers,
                                  row_height_out_fibers);
    if (format != FLT_PIXEL_MONO8 && format != FLT_PIXEL_MONO10 &&
        format != FLT_PIXEL_MONO12 && format != FLT_PIXEL_MONO16)
        /* The library names the bad format. */
        return flt_extractor_process($self, frame, (flt_pixel_format)format, 0, 0, 0,
                                     encoder_mm, row_height_out_fibers, s_mm_out,
                                     row_height_out, row_slope_out, row_valid_out);
    status = flt_py_frame(fn, frame, format, &pixels, &width, &height, &stride);
    if (status != FLT_OK) return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_extractor_process($self, pixels, (flt_pixel_format)format, width,
                                   height, stride, encoder_mm, row_height_out_fibers,
                                   s_mm_out, row_height_out, row_slope_out,
                                   row_valid_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The last frame's peak rows (2, width), px; NaN where none. */
  flt_status peaks_into(double *peak_rows_out, size_t peak_rows_out_lasers,
                        size_t peak_rows_out_width) {
    if (peak_rows_out_lasers != 2)
        return flt_py_shape_error("flt_extractor_peaks", "rows_out.shape[0]",
                                  peak_rows_out_lasers, 2);
    return flt_extractor_peaks($self, peak_rows_out_width, peak_rows_out);
  }

  /* The last frame's z per laser on the fiber grid (2, K), mm; NaN where
   * invalid. */
  flt_status laser_profiles_into(double *laser_z_out, size_t laser_z_out_lasers,
                                 size_t laser_z_out_fibers) {
    if (laser_z_out_lasers != 2)
        return flt_py_shape_error("flt_extractor_laser_profiles", "z_out.shape[0]",
                                  laser_z_out_lasers, 2);
    return flt_extractor_laser_profiles($self, laser_z_out_fibers, laser_z_out);
  }

  /* The last frame's flags per fiber (K,): what push_flagged takes. */
  flt_status fiber_flags_into(unsigned char *fiber_flags_out, size_t fiber_flags_out_fibers) {
    return flt_extractor_fiber_flags($self, fiber_flags_out_fibers, fiber_flags_out);
  }

  /* The strip under laser 0, 1 or 2 (the row): (left, right, width,
   * centre, flags) as 5 doubles, mm. */
  flt_status strip_into(unsigned laser, double *strip_out, size_t strip_out_n) {
    unsigned flags = 0;
    flt_status status;
    if (strip_out_n != 5)
      return flt_py_shape_error("flt_extractor_strip", "out.shape[0]", strip_out_n, 5);
    status = flt_extractor_strip($self, laser, &strip_out[0], &strip_out[1], &strip_out[2],
                                 &strip_out[3], &flags);
    strip_out[4] = (double)flags;
    return status;
  }

  /* (peaks, saturated, fraction) as 3 doubles (the counts exact below
   * 2^53). */
  flt_status saturation_into(unsigned laser, double *saturation_out, size_t saturation_out_n) {
    size_t peaks = 0, saturated = 0;
    flt_status status;
    if (saturation_out_n != 3)
      return flt_py_shape_error("flt_extractor_saturation", "out.shape[0]", saturation_out_n, 3);
    status = flt_extractor_saturation($self, laser, &peaks, &saturated, &saturation_out[2]);
    saturation_out[0] = (double)peaks;
    saturation_out[1] = (double)saturated;
    return status;
  }
}

%include "flatline/extractor.h"
