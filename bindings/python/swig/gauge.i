// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/gauge.h: the gauge (frames and cuts in, sheets out) and its
 * sheets.
 *
 * Wrapped as they are: create, get_option, cut, attach_source, start,
 * count, set_rules, flt_sheet_get and flt_sheet_verdict (its rules and
 * verdict come back as borrowed handles, read at once by flatline.Sheet).
 * Replaced: coil_stats (into a numpy array). Replaced: push_frame and push_row (numpy
 * arrays), flush, stop and next_sheet (they wait: the GIL is released),
 * the sheet's arrays and maps (into numpy arrays). set_callback is not
 * wrapped: a C callback on a gauge thread cannot call Python safely, and
 * flatline.Gauge's iterators poll instead.
 */

%ignore flt_gauge_destroy;
%ignore flt_gauge_push_frame;
%ignore flt_gauge_push_row;
%ignore flt_gauge_flush;
%ignore flt_gauge_stop;
%ignore flt_gauge_wait;
%ignore flt_gauge_next_sheet;
%ignore flt_gauge_set_callback;
%ignore flt_sheet_destroy;
%ignore flt_sheet_get_array;
%ignore flt_sheet_height_map;
%ignore flt_sheet_measured_map;
%ignore flt_gauge_coil_stats;

/* The sheet's own rules and verdict: borrowed (not freed by Python; valid
 * while the sheet lives). */
%typemap(in, numinputs=0) const flt_rules **rules_out (const flt_rules *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const flt_rules **rules_out {
  %append_output(SWIG_NewPointerObj((void *)*$1, $descriptor(flt_rules *), 0));
}
%typemap(in, numinputs=0) const flt_verdict **verdict_out (const flt_verdict *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const flt_verdict **verdict_out {
  %append_output(SWIG_NewPointerObj((void *)*$1, $descriptor(flt_verdict *), 0));
}

%typemap(in, numinputs=0) flt_gauge **out (flt_gauge *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_gauge **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_gauge *), SWIG_POINTER_OWN));
}

%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *gauge_height, size_t gauge_height_n),
  (const double *gauge_slope, size_t gauge_slope_n)
};
%apply (unsigned char *IN_ARRAY1, size_t DIM1) {
  (const unsigned char *gauge_valid, size_t gauge_valid_n)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *sheet_array_out, size_t sheet_array_out_n),
  (double *sheet_s_out, size_t sheet_s_out_n),
  (double *coil_out, size_t coil_out_n)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *sheet_z_out, size_t sheet_z_out_rows, size_t sheet_z_out_fibers),
  (double *sheet_h_out, size_t sheet_h_out_rows, size_t sheet_h_out_fibers)
};
%apply (unsigned char *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (unsigned char *sheet_flags_out, size_t sheet_flags_out_rows, size_t sheet_flags_out_fibers)
};

/* The waiting calls release the GIL; the handle is the Python object's. */
%nodefaultctor flt_gauge;
struct flt_gauge {};
%extend flt_gauge {
  ~flt_gauge() { flt_gauge_destroy($self); }

  /* One frame: a (height, width) uint8 or uint16 array (its rows may be
   * strided), copied by the gauge. May wait for room (gauge_overflow = 1). */
  flt_status push_frame_array(PyObject *frame, int format, double encoder_mm) {
    const char *fn = "flt_gauge_push_frame";
    const void *pixels = NULL;
    uint32_t width = 0, height = 0;
    size_t stride = 0;
    flt_status status;
    if (format != FLT_PIXEL_MONO8 && format != FLT_PIXEL_MONO10 &&
        format != FLT_PIXEL_MONO12 && format != FLT_PIXEL_MONO16)
        /* The library names the bad format. */
        return flt_gauge_push_frame($self, frame, (flt_pixel_format)format, 0, 0, 0,
                                    encoder_mm);
    status = flt_py_frame(fn, frame, format, &pixels, &width, &height, &stride);
    if (status != FLT_OK) return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_gauge_push_frame($self, pixels, (flt_pixel_format)format, width, height,
                                  stride, encoder_mm);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* One profile row: height, slope (K,) and valid (K,) (ignored unless
   * flagged). */
  flt_status push_row_arrays(double encoder_mm, const double *gauge_height,
                             size_t gauge_height_n, const double *gauge_slope,
                             size_t gauge_slope_n, const unsigned char *gauge_valid,
                             size_t gauge_valid_n, int flagged) {
    flt_status status;
    if (gauge_slope_n != gauge_height_n)
        return flt_py_shape_error("flt_gauge_push_row", "slope.shape[0]", gauge_slope_n,
                                  gauge_height_n);
    if (flagged && gauge_valid_n != gauge_height_n)
        return flt_py_shape_error("flt_gauge_push_row", "valid.shape[0]", gauge_valid_n,
                                  gauge_height_n);
    Py_BEGIN_ALLOW_THREADS
    status = flt_gauge_push_row($self, encoder_mm, gauge_height_n, gauge_height, gauge_slope,
                                flagged ? gauge_valid : NULL);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status flush_waiting() {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_gauge_flush($self);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* flt_gauge_wait with the GIL released. */
  flt_status wait_waiting(unsigned int timeout_ms) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_gauge_wait($self, timeout_ms);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status stop_waiting() {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_gauge_stop($self);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* One rule's coil statistics into out (FLT_COIL_VALUES,). */
  flt_status coil_stats_into(int which, size_t rule, double *coil_out, size_t coil_out_n) {
    return flt_gauge_coil_stats($self, (flt_coil)which, rule, coil_out_n, coil_out);
  }

  /* The next sheet, or None after timeout_ms. */
  PyObject *next_sheet_waiting(unsigned int timeout_ms) {
    flt_sheet *sheet = NULL;
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_gauge_next_sheet($self, timeout_ms, &sheet);
    Py_END_ALLOW_THREADS
    if (status != FLT_OK) {
        flt_py_raise_last(status);
        return NULL;
    }
    if (sheet == NULL) Py_RETURN_NONE;
    return SWIG_NewPointerObj(sheet, SWIGTYPE_p_flt_sheet, SWIG_POINTER_OWN);
  }
}

%nodefaultctor flt_sheet;
struct flt_sheet {};
%extend flt_sheet {
  ~flt_sheet() { flt_sheet_destroy($self); }

  flt_status array_into(int key, double *sheet_array_out, size_t sheet_array_out_n) {
    return flt_sheet_get_array($self, (flt_sheet_array)key, sheet_array_out_n,
                               sheet_array_out);
  }

  /* s (rows,), z (rows, K) and flags (rows, K). */
  flt_status height_map_into(double *sheet_s_out, size_t sheet_s_out_n, double *sheet_z_out,
                             size_t sheet_z_out_rows, size_t sheet_z_out_fibers,
                             unsigned char *sheet_flags_out, size_t sheet_flags_out_rows,
                             size_t sheet_flags_out_fibers) {
    if (sheet_s_out_n != sheet_z_out_rows)
        return flt_py_shape_error("flt_sheet_height_map", "s.shape[0]", sheet_s_out_n,
                                  sheet_z_out_rows);
    if (sheet_flags_out_rows != sheet_z_out_rows || sheet_flags_out_fibers != sheet_z_out_fibers)
        return flt_py_shape_error("flt_sheet_height_map", "flags.shape[0]",
                                  sheet_flags_out_rows, sheet_z_out_rows);
    return flt_sheet_height_map($self, sheet_z_out_rows, sheet_z_out_fibers, sheet_s_out,
                                sheet_z_out, sheet_flags_out);
  }

  flt_status measured_map_into(double *sheet_h_out, size_t sheet_h_out_rows,
                               size_t sheet_h_out_fibers) {
    return flt_sheet_measured_map($self, sheet_h_out_rows, sheet_h_out_fibers, sheet_h_out);
  }
}

/* The sheet's coil (borrowed, read-only) and its notes. */
%typemap(in, numinputs=0) const flt_coil_info **out (const flt_coil_info *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const flt_coil_info **out {
  %append_output(SWIG_NewPointerObj((void *)*$1, $descriptor(flt_coil_info *), 0));
}
%typemap(in, numinputs=0) const char **kind_out (const char *temp = NULL),
                          const char **text_out (const char *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const char **kind_out, const char **text_out {
  %append_output(PyUnicode_DecodeUTF8(*$1 ? *$1 : "", (Py_ssize_t)strlen(*$1 ? *$1 : ""),
                                      "replace"));
}
%typemap(in, numinputs=0) double *s_mm_out (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *s_mm_out { %append_output(PyFloat_FromDouble(*$1)); }

%include "flatline/gauge.h"
