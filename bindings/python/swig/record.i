// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/coil.h and flatline/record.h: coil identities, recordings
 * (writing, reading) and the archive.
 *
 * Wrapped as they are: the coil identity's calls, flt_recorder_create,
 * _cut, _set_coil, _save_frames, _count, flt_recording_open, _info,
 * _calib, _options, flt_archive_open, _prune, _count, _backend. Replaced:
 * the calls that wait (sync, verify, flush: the GIL is released) and the
 * array calls (push_row, read_rows: numpy arrays).
 */

%ignore flt_coil_info_destroy;
%ignore flt_recorder_destroy;
%ignore flt_recorder_push_row;
%ignore flt_recorder_sync;
%ignore flt_recording_destroy;
%ignore flt_recording_verify;
%ignore flt_recording_read_rows;
%ignore flt_archive_destroy;
%ignore flt_archive_flush;

%typemap(in, numinputs=0) flt_coil_info **out (flt_coil_info *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_coil_info **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_coil_info *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_recorder **out (flt_recorder *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_recorder **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_recorder *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_recording **out (flt_recording *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_recording **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_recording *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_archive **out (flt_archive *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_archive **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_archive *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_calib **out (flt_calib *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_calib **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_calib *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) double *thickness_mm_out (double temp = 0.0),
                          double *width_mm_out (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *thickness_mm_out, double *width_mm_out {
  %append_output(PyFloat_FromDouble(*$1));
}
%typemap(in, numinputs=0) const char **key_out (const char *temp = NULL),
                          const char **value_out (const char *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const char **key_out, const char **value_out {
  %append_output(PyUnicode_DecodeUTF8(*$1 ? *$1 : "", (Py_ssize_t)strlen(*$1 ? *$1 : ""),
                                      "replace"));
}
%typemap(in, numinputs=0) uint64_t *removed_out (uint64_t temp = 0) { $1 = &temp; }
%typemap(argout) uint64_t *removed_out {
  %append_output(PyLong_FromUnsignedLongLong((unsigned long long)*$1));
}

%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *rec_height, size_t rec_height_n),
  (const double *rec_slope, size_t rec_slope_n)
};
%apply (unsigned char *IN_ARRAY1, size_t DIM1) {
  (const unsigned char *rec_valid, size_t rec_valid_n)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *rec_e_out, size_t rec_e_out_n),
  (double *rec_t_out, size_t rec_t_out_n)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *rec_h_out, size_t rec_h_out_rows, size_t rec_h_out_fibers),
  (double *rec_s_out, size_t rec_s_out_rows, size_t rec_s_out_fibers)
};
%apply (unsigned char *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (unsigned char *rec_f_out, size_t rec_f_out_rows, size_t rec_f_out_fibers)
};

%nodefaultctor flt_coil_info;
struct flt_coil_info {};
%extend flt_coil_info {
  ~flt_coil_info() { flt_coil_info_destroy($self); }
}

%nodefaultctor flt_recorder;
struct flt_recorder {};
%extend flt_recorder {
  ~flt_recorder() {
    Py_BEGIN_ALLOW_THREADS
    flt_recorder_destroy($self);
    Py_END_ALLOW_THREADS
  }

  flt_status push_row_arrays(double encoder_mm, const double *rec_height, size_t rec_height_n,
                             const double *rec_slope, size_t rec_slope_n,
                             const unsigned char *rec_valid, size_t rec_valid_n, int flagged) {
    flt_status status;
    if (rec_slope_n != rec_height_n)
        return flt_py_shape_error("flt_recorder_push_row", "slope.shape[0]", rec_slope_n,
                                  rec_height_n);
    if (flagged && rec_valid_n != rec_height_n)
        return flt_py_shape_error("flt_recorder_push_row", "valid.shape[0]", rec_valid_n,
                                  rec_height_n);
    Py_BEGIN_ALLOW_THREADS
    status = flt_recorder_push_row($self, encoder_mm, rec_height_n, rec_height, rec_slope,
                                   flagged ? rec_valid : NULL);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status sync_waiting(uint32_t timeout_ms) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_recorder_sync($self, timeout_ms);
    Py_END_ALLOW_THREADS
    return status;
  }
}

%nodefaultctor flt_recording;
struct flt_recording {};
%extend flt_recording {
  ~flt_recording() { flt_recording_destroy($self); }

  flt_status verify_waiting(uint64_t *out) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_recording_verify($self, out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* Rows [first, first + n) into (n,) and (n, fibers) arrays; the rows
   * read (fewer at the end). */
  flt_status read_rows_into(uint64_t first, double *rec_e_out, size_t rec_e_out_n,
                            double *rec_t_out, size_t rec_t_out_n, double *rec_h_out,
                            size_t rec_h_out_rows, size_t rec_h_out_fibers, double *rec_s_out,
                            size_t rec_s_out_rows, size_t rec_s_out_fibers,
                            unsigned char *rec_f_out, size_t rec_f_out_rows,
                            size_t rec_f_out_fibers, size_t *out) {
    const char *fn = "flt_recording_read_rows";
    flt_status status;
    if (rec_t_out_n != rec_e_out_n)
        return flt_py_shape_error(fn, "time.shape[0]", rec_t_out_n, rec_e_out_n);
    if (rec_h_out_rows != rec_e_out_n || rec_s_out_rows != rec_e_out_n ||
        rec_f_out_rows != rec_e_out_n)
        return flt_py_shape_error(fn, "rows", rec_h_out_rows, rec_e_out_n);
    if (rec_s_out_fibers != rec_h_out_fibers || rec_f_out_fibers != rec_h_out_fibers)
        return flt_py_shape_error(fn, "fibers", rec_s_out_fibers, rec_h_out_fibers);
    Py_BEGIN_ALLOW_THREADS
    status = flt_recording_read_rows($self, first, rec_e_out_n, rec_h_out_fibers, rec_e_out,
                                     rec_t_out, rec_h_out, rec_s_out, rec_f_out, out);
    Py_END_ALLOW_THREADS
    return status;
  }
}

%nodefaultctor flt_archive;
struct flt_archive {};
%extend flt_archive {
  ~flt_archive() {
    Py_BEGIN_ALLOW_THREADS
    flt_archive_destroy($self);
    Py_END_ALLOW_THREADS
  }

  flt_status flush_waiting(uint32_t timeout_ms) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_archive_flush($self, timeout_ms);
    Py_END_ALLOW_THREADS
    return status;
  }
}

%include "flatline/coil.h"
%include "flatline/record.h"
