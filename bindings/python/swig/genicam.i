// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/genicam.h: the offline view of a camera description.
 *
 * Wrapped as they are, with their `out` pointers returned: everything but
 * flt_genicam_load_memory / flt_genicam_set_memory / flt_genicam_get_memory
 * (replaced: any buffer-protocol object in, bytes out) and
 * flt_genicam_set_registers (C callbacks; Python gives register contents
 * as a memory image).
 */

%ignore flt_genicam_destroy;
%ignore flt_genicam_load_memory;
%ignore flt_genicam_set_memory;
%ignore flt_genicam_get_memory;
%ignore flt_genicam_set_registers;
%ignore flt_genicam_read_fn;
%ignore flt_genicam_write_fn;

%typemap(in, numinputs=0) flt_genicam **out (flt_genicam *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_genicam **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_genicam *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_genicam_type *type_out (flt_genicam_type temp = FLT_GENICAM_INTEGER) {
  $1 = &temp;
}
%typemap(argout) flt_genicam_type *type_out { %append_output(PyLong_FromLong((long)*$1)); }
%typemap(in, numinputs=0) flt_genicam_access *out (flt_genicam_access temp) { $1 = &temp; }
%typemap(argout) flt_genicam_access *out { %append_output(PyLong_FromLong((long)*$1)); }
%typemap(in, numinputs=0) const char **kind_out (const char *temp = NULL),
                          const char **unit_out (const char *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const char **kind_out, const char **unit_out {
  %append_output(PyUnicode_DecodeUTF8(*$1 ? *$1 : "", (Py_ssize_t)strlen(*$1 ? *$1 : ""),
                                      "replace"));
}
%typemap(in, numinputs=0) int *implemented_out (int temp = 0), int *available_out (int temp = 0),
                          int *locked_out (int temp = 0), int *big_endian_out (int temp = 0) {
  $1 = &temp;
}
%typemap(argout) int *implemented_out, int *available_out, int *locked_out, int *big_endian_out {
  %append_output(PyBool_FromLong(*$1));
}
%typemap(in, numinputs=0) uint64_t *address_out (uint64_t temp = 0) { $1 = &temp; }
%typemap(argout) uint64_t *address_out {
  %append_output(PyLong_FromUnsignedLongLong((unsigned long long)*$1));
}
%typemap(in, numinputs=0) uint32_t *length_out (uint32_t temp = 0), uint32_t *lsb_out (uint32_t temp = 0),
                          uint32_t *msb_out (uint32_t temp = 0) { $1 = &temp; }
%typemap(argout) uint32_t *length_out, uint32_t *lsb_out, uint32_t *msb_out {
  %append_output(PyLong_FromUnsignedLong((unsigned long)*$1));
}
%typemap(in, numinputs=0) int64_t *min_out (int64_t temp = 0), int64_t *max_out (int64_t temp = 0),
                          int64_t *inc_out (int64_t temp = 0), int64_t *value_out (int64_t temp = 0) {
  $1 = &temp;
}
%typemap(argout) int64_t *min_out, int64_t *max_out, int64_t *inc_out, int64_t *value_out {
  %append_output(PyLong_FromLongLong((long long)*$1));
}
%typemap(in, numinputs=0) double *min_out (double temp = 0.0), double *max_out (double temp = 0.0) {
  $1 = &temp;
}
%typemap(argout) double *min_out, double *max_out { %append_output(PyFloat_FromDouble(*$1)); }

%{
/* A read-only view of any buffer-protocol object (bytes, bytearray,
 * memoryview, a C-contiguous numpy array), for the calls taking bytes. */
static int flt_py_bytes_view(PyObject *obj, Py_buffer *view, const char *fn,
                             const char *argument) {
    if (PyObject_GetBuffer(obj, view, PyBUF_SIMPLE) != 0) {
        PyErr_Clear();
        PyErr_Format(PyExc_TypeError, "%s: argument '%s' must be bytes-like (bytes, "
                     "bytearray, a contiguous numpy array), not %s", fn, argument,
                     Py_TYPE(obj)->tp_name);
        return 0;
    }
    return 1;
}
%}

%inline %{
/* flt_genicam_load_memory over a bytes-like object. */
static PyObject *flt_py_genicam_load_memory(PyObject *data) {
    Py_buffer view;
    flt_genicam *g = NULL;
    flt_status status;
    if (!flt_py_bytes_view(data, &view, "flt_genicam_load_memory", "data"))
        return NULL;
    Py_BEGIN_ALLOW_THREADS
    status = flt_genicam_load_memory(view.buf, (size_t)view.len, &g);
    Py_END_ALLOW_THREADS
    PyBuffer_Release(&view);
    if (status != FLT_OK) { flt_py_raise_last(status); return NULL; }
    return SWIG_NewPointerObj(g, SWIGTYPE_p_flt_genicam, SWIG_POINTER_OWN);
}
%}

%nodefaultctor flt_genicam;
struct flt_genicam {};
%extend flt_genicam {
  ~flt_genicam() { flt_genicam_destroy($self); }

  /* flt_genicam_set_memory with a bytes-like object. */
  PyObject *put_memory(uint64_t address, PyObject *data) {
    Py_buffer view;
    flt_status status;
    if (!flt_py_bytes_view(data, &view, "flt_genicam_set_memory", "data"))
      return NULL;
    status = flt_genicam_set_memory($self, address, view.buf, (size_t)view.len);
    PyBuffer_Release(&view);
    if (status != FLT_OK) { flt_py_raise_last(status); return NULL; }
    Py_RETURN_NONE;
  }

  /* flt_genicam_get_memory as bytes. */
  PyObject *fetch_memory(uint64_t address, size_t count) {
    PyObject *out;
    flt_status status;
    unsigned char dummy = 0;
    if (count == 0 || count > ((size_t)64 << 20)) {
      /* the library refuses the count and names it; nothing allocated */
      status = flt_genicam_get_memory($self, address, &dummy, count);
      flt_py_raise_last(status == FLT_OK ? FLT_ERR_INTERNAL : status);
      return NULL;
    }
    out = PyBytes_FromStringAndSize(NULL, (Py_ssize_t)count);
    if (out == NULL) return NULL;
    status = flt_genicam_get_memory($self, address, PyBytes_AS_STRING(out), count);
    if (status != FLT_OK) { Py_DECREF(out); flt_py_raise_last(status); return NULL; }
    return out;
  }
}

%include "flatline/genicam.h"
