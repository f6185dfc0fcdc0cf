// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/common.h: status codes, errors, version, options.
 *
 * Errors: every wrapped function that returns flt_status goes through the
 * one `out` typemap below. On failure it reads the thread's last error
 * (flt_last_error_message(); the status is the returned code, which is
 * also flt_last_error_status()) and raises the matching subclass of
 * flatline.FlatlineError, built by flatline._errors._from_status(). No
 * status code ever reaches Python: a successful call returns None, or its
 * `out` values.
 */

%{
/* Raises the FlatlineError subclass for `status`, with `message`. Needs the
 * GIL. Never fails silently: if the error classes cannot be loaded, that
 * import error is what propagates. */
static void flt_py_raise(int status, const char *message) {
    PyObject *module, *text, *exc;
    if (message == NULL) message = "";
    text = PyUnicode_DecodeUTF8(message, (Py_ssize_t)strlen(message), "replace");
    if (text == NULL) return;
    module = PyImport_ImportModule("flatline._errors");
    if (module == NULL) { Py_DECREF(text); return; }
    exc = PyObject_CallMethod(module, "_from_status", "iO", status, text);
    Py_DECREF(module);
    Py_DECREF(text);
    if (exc == NULL) return;
    PyErr_SetObject((PyObject *)Py_TYPE(exc), exc);
    Py_DECREF(exc);
}

/* Raises InvalidArgumentError for inconsistent array shapes and returns the
 * status, so the flt_status typemap fails the call (the helpers of every
 * component use it as their last line of defence). */
static flt_status flt_py_shape_error(const char *function, const char *what,
                                     size_t got, size_t expected) {
    char message[256];
    PyOS_snprintf(message, sizeof message,
                  "%s: %s is %zu but should be %zu", function, what, got,
                  expected);
    flt_py_raise((int)FLT_ERR_INVALID_ARGUMENT, message);
    return FLT_ERR_INVALID_ARGUMENT;
}

/* Raises the last error of this thread (after a call returned a failure). */
static void flt_py_raise_last(flt_status status) {
    /* Copy before anything else can call into the library. */
    flt_py_raise((int)status, flt_last_error_message());
}
%}

/* The one error path for every flt_status-returning call. A helper that has
 * already set a Python exception (e.g. a shape check) returns a failure
 * status too; its exception is kept. */
%typemap(out) flt_status {
  if ($1 != FLT_OK) {
    if (!PyErr_Occurred()) flt_py_raise_last($1);
    SWIG_fail;
  }
  $result = SWIG_Py_Void();
}

/* ...except the accessor of the thread's last status, which reports one. */
%typemap(out) flt_status flt_last_error_status { $result = PyLong_FromLong((long)$1); }

/* Scalar `out` parameters become return values. */
%typemap(in, numinputs=0) size_t *out (size_t temp = 0) { $1 = &temp; }
%typemap(argout) size_t *out { %append_output(PyLong_FromSize_t(*$1)); }

%typemap(in, numinputs=0) double *out (double temp = 0.0),
                          double *min_value (double temp = 0.0),
                          double *max_value (double temp = 0.0),
                          double *default_value (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *out, double *min_value, double *max_value,
                 double *default_value { %append_output(PyFloat_FromDouble(*$1)); }

/* ...and the named scalar outputs of the calibration and the simulator. */
%typemap(in, numinputs=0) size_t *count_out (size_t temp = 0) { $1 = &temp; }
%typemap(argout) size_t *count_out { %append_output(PyLong_FromSize_t(*$1)); }
%typemap(in, numinputs=0) double *first_x_mm_out (double temp = 0.0),
                          double *pitch_mm_out (double temp = 0.0),
                          double *rms_px_out (double temp = 0.0),
                          double *rms_mm_out (double temp = 0.0),
                          double *encoder_mm_out (double temp = 0.0),
                          double *s_mm_out (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *first_x_mm_out, double *pitch_mm_out, double *rms_px_out,
                 double *rms_mm_out, double *encoder_mm_out, double *s_mm_out {
  %append_output(PyFloat_FromDouble(*$1));
}
%typemap(in, numinputs=0) uint32_t *width_out (uint32_t temp = 0),
                          uint32_t *height_out (uint32_t temp = 0),
                          uint32_t *first_row_out (uint32_t temp = 0),
                          uint32_t *rows_out (uint32_t temp = 0) { $1 = &temp; }
%typemap(argout) uint32_t *width_out, uint32_t *height_out, uint32_t *first_row_out,
                 uint32_t *rows_out { %append_output(PyLong_FromUnsignedLong(*$1)); }
%typemap(in, numinputs=0) int *out (int temp = 0) { $1 = &temp; }
%typemap(argout) int *out { %append_output(PyLong_FromLong((long)*$1)); }

%typemap(in, numinputs=0) int *is_integer (int temp = 0) { $1 = &temp; }
%typemap(argout) int *is_integer { %append_output(PyBool_FromLong(*$1)); }

%typemap(in, numinputs=0) flt_option *out (flt_option temp) { $1 = &temp; }
%typemap(argout) flt_option *out { %append_output(PyLong_FromLong((long)*$1)); }

%typemap(in, numinputs=0) const char **name (const char *temp = NULL),
                          const char **name_out (const char *temp = NULL) { $1 = ($1_ltype)&temp; }
%typemap(argout) const char **name, const char **name_out {
  %append_output(PyUnicode_FromString(*$1 ? *$1 : ""));
}
%typemap(in, numinputs=0) int *value_out (int temp = 0) { $1 = &temp; }
%typemap(argout) int *value_out { %append_output(PyLong_FromLong((long)*$1)); }

/* The option bag: a Python-owned handle, freed by its destructor. */
%nodefaultctor flt_options;
struct flt_options {};
%extend flt_options {
  ~flt_options() { flt_options_destroy($self); }
}
%ignore flt_options_destroy;
%typemap(in, numinputs=0) flt_options **out (flt_options *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_options **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_options *), SWIG_POINTER_OWN));
}

/* The version the extension was compiled against (the library's own is
 * flt_version_string()). */
%constant const char *FLT_HEADER_VERSION = FLT_VERSION_STRING;
%constant int FLT_HEADER_VERSION_NUMBER = FLT_VERSION_NUMBER;

/* SWIG sees neither __GNUC__ nor _WIN32, so FLT_API, FLT_CALL and
 * FLT_NODISCARD expand to nothing. */
%include "flatline/version.h"
%include "flatline/common.h"
