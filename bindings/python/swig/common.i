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

/* Scalar arguments. SWIG's own conversions raise OverflowError for an int
 * outside the C type (flatline.Reconstructor(2**64)) and for an int beyond
 * a double's range, where the library raises InvalidArgumentError (a
 * ValueError) for every other value out of range. These typemaps convert
 * every integer and double argument through one helper each: anything with
 * __index__ (int, bool, numpy integers) for an integer, anything float()
 * takes for a double; TypeError for another type, InvalidArgumentError
 * naming the function, the argument and the value when it does not fit. */
%{
#include <limits.h>
#include <stdint.h>

static void flt_py_out_of_range(const char *function, const char *name, PyObject *value,
                                const char *range) {
    char message[512];
    PyObject *text = PyObject_Str(value);
    const char *digits = text ? PyUnicode_AsUTF8(text) : NULL;
    if (digits == NULL) {
        PyErr_Clear();
        digits = "?";
    }
    /* A 2**4000 has 1200 digits: the message keeps the first 60. */
    PyOS_snprintf(message, sizeof message, "%s: argument '%s' = %.60s%s is outside %s", function,
                  name, digits, strlen(digits) > 60 ? "..." : "", range);
    Py_XDECREF(text);
    flt_py_raise((int)FLT_ERR_INVALID_ARGUMENT, message);
}

/* An integer argument in [min, max] (signed types) or [0, umax] (unsigned),
 * as the bits of an unsigned long long; 0 with an exception set if not. */
static int flt_py_integer(PyObject *obj, const char *function, const char *name, int is_signed,
                          long long min, unsigned long long umax, unsigned long long *bits) {
    PyObject *index;
    long long v;
    unsigned long long u = 0;
    int overflow = 0, ok;
    char range[96];
    index = PyNumber_Index(obj);
    if (index == NULL) {
        if (PyErr_ExceptionMatches(PyExc_TypeError)) {
            PyErr_Clear();
            PyErr_Format(PyExc_TypeError, "%s() argument '%s' must be an integer, not %.100s",
                         function, name, Py_TYPE(obj)->tp_name);
        }
        return 0;
    }
    v = PyLong_AsLongLongAndOverflow(index, &overflow);
    if (v == -1 && PyErr_Occurred()) {
        Py_DECREF(index);
        return 0;
    }
    if (overflow > 0) { /* above LLONG_MAX: an unsigned long long at most */
        u = PyLong_AsUnsignedLongLong(index);
        if (PyErr_Occurred()) {
            PyErr_Clear();
            ok = 0;
        } else {
            ok = !is_signed && u <= umax;
        }
    } else if (overflow < 0) {
        ok = 0;
    } else if (v < 0) {
        ok = is_signed && v >= min;
        u = (unsigned long long)v;
    } else {
        ok = (unsigned long long)v <= umax;
        u = (unsigned long long)v;
    }
    if (!ok) {
        if (is_signed)
            PyOS_snprintf(range, sizeof range, "[%lld, %llu]", min, umax);
        else
            PyOS_snprintf(range, sizeof range, "[0, %llu]", umax);
        flt_py_out_of_range(function, name, index, range);
        Py_DECREF(index);
        return 0;
    }
    Py_DECREF(index);
    *bits = u;
    return 1;
}

/* A double argument; 0 with an exception set if not. */
static int flt_py_double(PyObject *obj, const char *function, const char *name, double *out) {
    double v = PyFloat_AsDouble(obj); /* float, int, __float__, __index__ */
    if (v == -1.0 && PyErr_Occurred()) {
        if (PyErr_ExceptionMatches(PyExc_OverflowError)) { /* an int like 10**400 */
            PyErr_Clear();
            flt_py_out_of_range(function, name, obj, "the range of a double");
        } else if (PyErr_ExceptionMatches(PyExc_TypeError)) {
            PyErr_Clear();
            PyErr_Format(PyExc_TypeError, "%s() argument '%s' must be a real number, not %.100s",
                         function, name, Py_TYPE(obj)->tp_name);
        }
        return 0;
    }
    *out = v;
    return 1;
}
%}

%define FLT_PY_UNSIGNED(TYPE, UMAX)
%typemap(in) TYPE {
  unsigned long long flt_bits = 0;
  if (!flt_py_integer($input, "$symname", "$1_name", 0, 0, UMAX, &flt_bits)) SWIG_fail;
  $1 = ($1_ltype)flt_bits;
}
%enddef
%define FLT_PY_SIGNED(TYPE, MIN, MAX)
%typemap(in) TYPE {
  unsigned long long flt_bits = 0;
  if (!flt_py_integer($input, "$symname", "$1_name", 1, MIN, MAX, &flt_bits)) SWIG_fail;
  $1 = ($1_ltype)(long long)flt_bits;
}
%enddef
FLT_PY_UNSIGNED(size_t, SIZE_MAX)
FLT_PY_UNSIGNED(unsigned int, UINT_MAX)
FLT_PY_UNSIGNED(uint32_t, UINT32_MAX)
FLT_PY_UNSIGNED(unsigned long long, ULLONG_MAX)
FLT_PY_UNSIGNED(uint64_t, UINT64_MAX)
FLT_PY_SIGNED(int, INT_MIN, INT_MAX)
FLT_PY_SIGNED(long long, LLONG_MIN, LLONG_MAX)
FLT_PY_SIGNED(int64_t, INT64_MIN, INT64_MAX)
/* Enums are int-sized (common.h): any int is passed on, and the library
 * refuses the ones it does not know with a message. */
FLT_PY_SIGNED(enum SWIGTYPE, INT_MIN, INT_MAX)

%typemap(in) double {
  if (!flt_py_double($input, "$symname", "$1_name", &$1)) SWIG_fail;
}

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
                          double *min_out (double temp = 0.0),
                          double *max_out (double temp = 0.0),
                          double *default_out (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *out, double *min_out, double *max_out,
                 double *default_out { %append_output(PyFloat_FromDouble(*$1)); }

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

%typemap(in, numinputs=0) int *is_integer_out (int temp = 0) { $1 = &temp; }
%typemap(argout) int *is_integer_out { %append_output(PyBool_FromLong(*$1)); }

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

/* flt_py_release(proxy): frees the C object behind a SWIG proxy now, however
 * many references to the proxy are still alive (a traceback's frame keeps
 * the locals of the call that raised, and a test framework may keep the
 * traceback for a long time): the flatline classes' close() promises the C
 * memory back at once, not when the last reference happens to go. Calls the
 * proxy's __swig_destroy__ when the proxy owns the object, then clears the
 * pointer, so a call through a stale proxy passes NULL, which every
 * function of the library refuses (FLT_ERR_INVALID_ARGUMENT), and the
 * proxy's own destructor later does nothing. None and a released proxy are
 * ignored. */
%{
static PyObject *flt_py_release(PyObject *self, PyObject *args) {
    SwigPyObject *sobj;
    PyObject *proxy = NULL;
    (void)self;
    if (!PyArg_UnpackTuple(args, "flt_py_release", 1, 1, &proxy)) return NULL;
    if (proxy == Py_None) Py_RETURN_NONE;
    sobj = SWIG_Python_GetSwigThis(proxy);
    if (sobj == NULL) {
        PyErr_SetString(PyExc_TypeError, "flt_py_release: not a SWIG proxy");
        return NULL;
    }
    if (sobj->ptr != NULL && sobj->own) {
        PyObject *destroy = PyObject_GetAttrString((PyObject *)Py_TYPE(proxy), "__swig_destroy__");
        PyObject *done;
        if (destroy == NULL) return NULL;
        done = PyObject_CallFunctionObjArgs(destroy, proxy, NULL);
        Py_DECREF(destroy);
        if (done == NULL) return NULL;
        Py_DECREF(done);
    }
    sobj->ptr = NULL;
    sobj->own = 0;
    Py_RETURN_NONE;
}
%}
%native(flt_py_release) flt_py_release;

/* The version the extension was compiled against (the library's own is
 * flt_version_string()). */
%constant const char *FLT_HEADER_VERSION = FLT_VERSION_STRING;
%constant int FLT_HEADER_VERSION_NUMBER = FLT_VERSION_NUMBER;

/* SWIG sees neither __GNUC__ nor _WIN32, so FLT_API, FLT_CALL and
 * FLT_NODISCARD expand to nothing. */
%include "flatline/version.h"
%include "flatline/common.h"
