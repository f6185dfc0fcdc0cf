// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/source.h: frame sources (simulator, image sequences, USB3 Vision
 * cameras) and the camera list. (The simulated USB3 Vision bus of
 * flatline/testing.h is the module flatline.testing_capi, testing.i.)
 *
 * Wrapped as they are: the create/open calls, start, stop, set_encoder,
 * count, stream_error, camera strings and values, feature access by name,
 * map_feature and the camera list. Replaced:
 * flt_source_create_images (a list of str), flt_source_next +
 * flt_frame_info (next_frame copies the borrowed frame into a numpy array,
 * with the GIL released while waiting) and the raw memory access (numpy
 * byte arrays). flt_frame is never exposed: the borrowed frame cannot
 * outlive the call that copies it.
 */

%ignore flt_source_destroy;
%ignore flt_camera_list_destroy;
%ignore flt_source_create_images;
%ignore flt_source_next;
%ignore flt_frame_info;
%ignore flt_frame_row;          /* a recording source's rows: flatline.Recording reads them */
%ignore flt_frame_event_count;
%ignore flt_frame_event;
%ignore flt_frame_event_note;
%ignore flt_source_read_memory;
%ignore flt_source_write_memory;

%typemap(in, numinputs=0) flt_source **out (flt_source *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_source **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_source *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_camera_list **out (flt_camera_list *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_camera_list **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_camera_list *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_source_kind *out (flt_source_kind temp) { $1 = &temp; }
%typemap(argout) flt_source_kind *out { %append_output(PyLong_FromLong((long)*$1)); }
%typemap(in, numinputs=0) uint64_t *out (uint64_t temp = 0) { $1 = &temp; }
%typemap(argout) uint64_t *out {
  %append_output(PyLong_FromUnsignedLongLong((unsigned long long)*$1));
}
%typemap(in, numinputs=0) int64_t *out (int64_t temp = 0) { $1 = &temp; }
%typemap(argout) int64_t *out { %append_output(PyLong_FromLongLong((long long)*$1)); }
%typemap(in, numinputs=0) uint32_t *out (uint32_t temp = 0),
                          uint32_t *speed_mbps_out (uint32_t temp = 0) { $1 = &temp; }
%typemap(argout) uint32_t *out, uint32_t *speed_mbps_out {
  %append_output(PyLong_FromUnsignedLong((unsigned long)*$1));
}
%typemap(in, numinputs=0) const char **out (const char *temp = NULL),
                          const char **vendor_out (const char *temp = NULL),
                          const char **model_out (const char *temp = NULL),
                          const char **serial_out (const char *temp = NULL) {
  $1 = ($1_ltype)&temp;
}
%typemap(argout) const char **out, const char **vendor_out, const char **model_out,
                 const char **serial_out {
  %append_output(PyUnicode_DecodeUTF8(*$1 ? *$1 : "", (Py_ssize_t)strlen(*$1 ? *$1 : ""),
                                      "replace"));
}

%apply (unsigned char *INPLACE_ARRAY1, size_t DIM1) {
  (unsigned char *memory_out, size_t memory_out_bytes)
};
%apply (unsigned char *IN_ARRAY1, size_t DIM1) {
  (const unsigned char *memory_in, size_t memory_in_bytes)
};

%inline %{
/* flt_source_create_images with a sequence of str paths. */
static flt_status flt_py_source_create_images(PyObject *paths, const char *encoder_csv,
                                              const flt_options *options,
                                              flt_source **out) {
    const char *fn = "flt_source_create_images";
    PyObject *seq, *encoded = NULL;
    const char **names = NULL;
    Py_ssize_t count, i;
    flt_status status;
    seq = PySequence_Fast(paths, "flt_source_create_images: argument 'paths' must be a "
                                 "sequence of str");
    if (seq == NULL) return FLT_ERR_INVALID_ARGUMENT;
    count = PySequence_Fast_GET_SIZE(seq);
    encoded = PyList_New(count);
    names = (const char **)PyMem_Malloc((size_t)(count ? count : 1) * sizeof *names);
    if (encoded == NULL || names == NULL) {
        if (names == NULL) PyErr_NoMemory();
        status = FLT_ERR_OUT_OF_MEMORY;
        goto done;
    }
    for (i = 0; i < count; ++i) {
        PyObject *item = PySequence_Fast_GET_ITEM(seq, i), *bytes = NULL;
        if (!PyUnicode_FSConverter(item, &bytes)) {
            PyErr_Format(PyExc_TypeError, "%s: paths[%zd] must be a str or path", fn, i);
            status = FLT_ERR_INVALID_ARGUMENT;
            goto done;
        }
        PyList_SET_ITEM(encoded, i, bytes);  /* steals */
        names[i] = PyBytes_AS_STRING(bytes);
    }
    status = flt_source_create_images(count ? names : NULL, (size_t)count, encoder_csv,
                                      options, out);
done:
    PyMem_Free(names);
    Py_XDECREF(encoded);
    Py_DECREF(seq);
    return status;
}
%}

%{
/* The next frame copied into `out` (a C-contiguous 2-D array of the frame's
 * size and dtype) or a new array: returns None at the end of an image
 * sequence, else (pixels, format, block_id, timestamp_ns, encoder_mm). NULL
 * with an exception set on failure. */
static PyObject *flt_py_source_next(flt_source *source, uint32_t timeout_ms,
                                    PyObject *out) {
    const char *fn = "flt_source_next";
    const flt_frame *frame = NULL;
    const void *pixels = NULL;
    uint32_t width = 0, height = 0, r;
    size_t stride = 0, row_bytes;
    flt_pixel_format format = FLT_PIXEL_MONO8;
    uint64_t block_id = 0, timestamp = 0;
    double encoder_mm = 0.0;
    PyArrayObject *array;
    int type;
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_source_next(source, timeout_ms, &frame);
    Py_END_ALLOW_THREADS
    if (status != FLT_OK) { flt_py_raise_last(status); return NULL; }
    if (frame == NULL) Py_RETURN_NONE;
    status = flt_frame_info(frame, &pixels, &width, &height, &stride, &format, &block_id,
                            &timestamp, &encoder_mm);
    if (status != FLT_OK) { flt_py_raise_last(status); return NULL; }
    type = format == FLT_PIXEL_MONO8 ? NPY_UBYTE : NPY_USHORT;
    row_bytes = (size_t)width * (format == FLT_PIXEL_MONO8 ? 1 : 2);
    if (out == NULL || out == Py_None) {
        npy_intp dims[2];
        dims[0] = (npy_intp)height;
        dims[1] = (npy_intp)width;
        array = (PyArrayObject *)PyArray_SimpleNew(2, dims, type);
        if (array == NULL) return NULL;
    } else {
        if (!PyArray_Check(out) || PyArray_TYPE((PyArrayObject *)out) != type ||
            !PyArray_ISNOTSWAPPED((PyArrayObject *)out)) {
            PyErr_Format(PyExc_TypeError, "%s: argument 'out' must be a native %s array "
                         "for this %d-bit frame", fn,
                         type == NPY_UBYTE ? "uint8" : "uint16", (int)format);
            return NULL;
        }
        array = (PyArrayObject *)out;
        if (PyArray_NDIM(array) != 2 || PyArray_DIM(array, 0) != (npy_intp)height ||
            PyArray_DIM(array, 1) != (npy_intp)width) {
            PyErr_Format(PyExc_ValueError, "%s: argument 'out' must have shape (%u, %u) "
                         "(height, width)", fn, (unsigned)height, (unsigned)width);
            return NULL;
        }
        if (!PyArray_IS_C_CONTIGUOUS(array) || !PyArray_ISWRITEABLE(array) ||
            !PyArray_ISALIGNED(array)) {
            PyErr_Format(PyExc_ValueError, "%s: argument 'out' must be C-contiguous, "
                         "aligned and writeable", fn);
            return NULL;
        }
        Py_INCREF(array);
    }
    for (r = 0; r < height; ++r)
        memcpy((char *)PyArray_DATA(array) + (size_t)r * row_bytes,
               (const char *)pixels + (size_t)r * stride, row_bytes);
    return Py_BuildValue("(NiKKd)", (PyObject *)array, (int)format,
                         (unsigned long long)block_id, (unsigned long long)timestamp,
                         encoder_mm);
}
%}

%nodefaultctor flt_source;
struct flt_source {};
%extend flt_source {
  ~flt_source() { flt_source_destroy($self); }

  PyObject *next_frame(uint32_t timeout_ms, PyObject *out) {
    return flt_py_source_next($self, timeout_ms, out);
  }

  flt_status read_memory_into(uint64_t address, unsigned char *memory_out,
                              size_t memory_out_bytes) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_source_read_memory($self, address, memory_out, memory_out_bytes);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status write_memory_array(uint64_t address, const unsigned char *memory_in,
                                size_t memory_in_bytes) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_source_write_memory($self, address, memory_in, memory_in_bytes);
    Py_END_ALLOW_THREADS
    return status;
  }
}

%nodefaultctor flt_camera_list;
struct flt_camera_list {};
%extend flt_camera_list {
  ~flt_camera_list() { flt_camera_list_destroy($self); }
}

/* flt_frame stays opaque and unused from Python. */
%ignore flt_frame;

%include "flatline/source.h"
