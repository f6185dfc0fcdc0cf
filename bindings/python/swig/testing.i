// SPDX-License-Identifier: Apache-2.0
/*
 * The module flatline.testing_capi (extension _testing_capi.so): the
 * testing tier, flatline/testing.h, over libflatline_testing. A module of
 * its own, so that `import flatline` never loads the testing library; the
 * Python classes over it are in flatline/testing.py.
 *
 * It shares SWIG's type table with flatline.capi (same SWIG runtime): the
 * flt_usb_transport pointer it returns is what capi's flt_source_open_u3v
 * and flt_camera_list_create take, and capi's flt_sim objects are what
 * flt_u3v_sim_set_frames takes.
 */
%module(package="flatline") testing_capi

%{
#include "flatline/flatline.h"
#include "flatline/testing.h"
%}

%include "stdint.i"

%{
/* The error path of flatline.capi (common.i), for this module's calls:
 * the thread's last error raised as the matching FlatlineError. */
static void flt_py_testing_raise(flt_status status) {
    PyObject *module, *text, *exc;
    const char *message = flt_last_error_message();
    text = PyUnicode_DecodeUTF8(message, (Py_ssize_t)strlen(message), "replace");
    if (text == NULL) return;
    module = PyImport_ImportModule("flatline._errors");
    if (module == NULL) { Py_DECREF(text); return; }
    exc = PyObject_CallMethod(module, "_from_status", "iO", (int)status, text);
    Py_DECREF(module);
    Py_DECREF(text);
    if (exc == NULL) return;
    PyErr_SetObject((PyObject *)Py_TYPE(exc), exc);
    Py_DECREF(exc);
}
%}

%typemap(out) flt_status {
  if ($1 != FLT_OK) {
    if (!PyErr_Occurred()) flt_py_testing_raise($1);
    SWIG_fail;
  }
  $result = SWIG_Py_Void();
}

/* The types of libflatline's headers, known but not wrapped here. */
%import "flatline/common.h"
%apply int { flt_pixel_format };

%ignore flt_u3v_sim_destroy;
%typemap(in, numinputs=0) flt_u3v_sim **out (flt_u3v_sim *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_u3v_sim **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_u3v_sim *), SWIG_POINTER_OWN));
}
/* The transport belongs to its bus: not owned by the Python object (the
 * Python bus keeps the C bus alive while a source uses the transport). */
%typemap(in, numinputs=0) flt_usb_transport **out (flt_usb_transport *temp = NULL) {
  $1 = &temp;
}
%typemap(argout) flt_usb_transport **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_usb_transport *), 0));
}
%typemap(in, numinputs=0) uint64_t *out (uint64_t temp = 0) { $1 = &temp; }
%typemap(argout) uint64_t *out {
  %append_output(PyLong_FromUnsignedLongLong((unsigned long long)*$1));
}
%typemap(in, numinputs=0) uint32_t *out (uint32_t temp = 0) { $1 = &temp; }
%typemap(argout) uint32_t *out { %append_output(PyLong_FromUnsignedLong((unsigned long)*$1)); }
%typemap(in, numinputs=0) size_t *index_out (size_t temp = 0) { $1 = &temp; }
%typemap(argout) size_t *index_out { %append_output(PyLong_FromSize_t(*$1)); }

%nodefaultctor flt_u3v_sim;
struct flt_u3v_sim {};
%extend flt_u3v_sim {
  ~flt_u3v_sim() { flt_u3v_sim_destroy($self); }
}

/* The hidden leveler (flt_leveler_sim) closes the advisor's loop in the C
 * tests and examples/advisor_loop; it is not bound. */
%ignore flt_leveler_sim;
%ignore flt_leveler_sim_create;
%ignore flt_leveler_sim_destroy;
%ignore flt_leveler_sim_set_settings;
%ignore flt_leveler_sim_set_incoming;
%ignore flt_leveler_sim_next_sheet;

%include "flatline/testing.h"
