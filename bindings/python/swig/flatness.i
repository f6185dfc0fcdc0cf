// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/flatness.h: I-Units per fiber and zone, waves, shape class, bow
 * and crossbow.
 *
 * Wrapped as they are: create_from_calib, fibers, zones, finish, reset and
 * flt_shape_string. create, evaluate, push and the result getters (arrays
 * and many outputs) are replaced by helpers with numpy.i's argument
 * patterns. evaluate and push release the GIL.
 */

%ignore flt_flatness_destroy;
%ignore flt_flatness_create;
%ignore flt_flatness_evaluate;
%ignore flt_flatness_push;
%ignore flt_flatness_zone_layout;
%ignore flt_flatness_window;
%ignore flt_flatness_fiber_results;
%ignore flt_flatness_zone_results;
%ignore flt_flatness_shape;
%ignore flt_flatness_evaluate_strip;
%ignore flt_flatness_push_strip;
%ignore flt_flatness_strip;
%ignore flt_flatness_zone_positions;
%ignore flt_flatness_fiber_positions;

%typemap(in, numinputs=0) flt_flatness **out (flt_flatness *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_flatness **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_flatness *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) int *evaluated_out (int temp = 0) { $1 = &temp; }
%typemap(argout) int *evaluated_out { %append_output(PyBool_FromLong(*$1)); }
%typemap(in, numinputs=0) size_t *consumed_out (size_t temp = 0) { $1 = &temp; }
%typemap(argout) size_t *consumed_out { %append_output(PyLong_FromSize_t(*$1)); }

%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *fiber_x, size_t fiber_x_count),
  (const double *flat_s, size_t flat_s_rows),
  (const double *edge_left, size_t edge_left_rows),
  (const double *edge_right, size_t edge_right_rows)
};
%apply (double *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const double *flat_z, size_t flat_z_rows, size_t flat_z_fibers)
};
%apply (unsigned char *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const unsigned char *flat_flags, size_t flat_flags_rows, size_t flat_flags_fibers)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *arc_out, size_t arc_out_n), (double *iu_out, size_t iu_out_n),
  (double *wave_height_out, size_t wave_height_out_n),
  (double *wave_period_out, size_t wave_period_out_n),
  (double *steepness_out, size_t steepness_out_n),
  (double *zone_iu_out, size_t zone_iu_out_n),
  (double *left_x_out, size_t left_x_out_n),
  (double *centre_x_out, size_t centre_x_out_n),
  (double *fiber_count_out, size_t fiber_count_out_n),
  (double *window_out, size_t window_out_n),
  (double *shape_out, size_t shape_out_n),
  (double *strip_out, size_t strip_out_n),
  (double *zone_strip_out, size_t zone_strip_out_n),
  (double *zone_sensor_out, size_t zone_sensor_out_n),
  (double *zone_width_out, size_t zone_width_out_n),
  (double *zone_fibers_out, size_t zone_fibers_out_n),
  (double *fiber_strip_out, size_t fiber_strip_out_n),
  (double *fiber_sensor_out, size_t fiber_sensor_out_n)
};
%apply (unsigned char *INPLACE_ARRAY1, size_t DIM1) {
  (unsigned char *fiber_flags_out, size_t fiber_flags_out_n),
  (unsigned char *zone_flags_out, size_t zone_flags_out_n)
};

%inline %{
/* flt_flatness_create with fiber_x (K,) mm. */
static flt_status flt_py_flatness_create(const double *fiber_x, size_t fiber_x_count,
                                         const flt_options *options,
                                         flt_flatness **out) {
    return flt_flatness_create(fiber_x_count, fiber_x, options, out);
}
%}

%{
/* Checks s (n,), z (n, K) and flags (n, K) (when flagged) against the
 * handle's K. */
static flt_status flt_py_flat_rows(const char *fn, const flt_flatness *flat,
                                   size_t s_rows, size_t z_rows, size_t z_fibers,
                                   size_t f_rows, size_t f_fibers, int flagged) {
    size_t fibers = 0;
    flt_status status = flt_flatness_fibers(flat, &fibers);
    if (status != FLT_OK) return status;
    if (z_fibers != fibers) return flt_py_shape_error(fn, "z.shape[1]", z_fibers, fibers);
    if (s_rows != z_rows) return flt_py_shape_error(fn, "s.shape[0]", s_rows, z_rows);
    if (flagged && f_rows != z_rows)
        return flt_py_shape_error(fn, "flags.shape[0]", f_rows, z_rows);
    if (flagged && f_fibers != fibers)
        return flt_py_shape_error(fn, "flags.shape[1]", f_fibers, fibers);
    return FLT_OK;
}
%}

%nodefaultctor flt_flatness;
struct flt_flatness {};
%extend flt_flatness {
  ~flt_flatness() { flt_flatness_destroy($self); }

  /* One window from s (n,), z (n, K) and flags (n, K) (ignored unless
   * flagged). */
  flt_status evaluate_rows(const double *flat_s, size_t flat_s_rows,
                           const double *flat_z, size_t flat_z_rows, size_t flat_z_fibers,
                           const unsigned char *flat_flags, size_t flat_flags_rows,
                           size_t flat_flags_fibers, int flagged) {
    flt_status status = flt_py_flat_rows("flt_flatness_evaluate", $self, flat_s_rows,
                                         flat_z_rows, flat_z_fibers, flat_flags_rows,
                                         flat_flags_fibers, flagged);
    if (status != FLT_OK) return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_flatness_evaluate($self, flat_z_rows, flat_z_fibers, flat_s, flat_z,
                                   flagged ? flat_flags : NULL);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* Streaming push; returns (consumed, evaluated). */
  flt_status push_rows(const double *flat_s, size_t flat_s_rows,
                       const double *flat_z, size_t flat_z_rows, size_t flat_z_fibers,
                       const unsigned char *flat_flags, size_t flat_flags_rows,
                       size_t flat_flags_fibers, int flagged, size_t *consumed_out,
                       int *evaluated_out) {
    flt_status status = flt_py_flat_rows("flt_flatness_push", $self, flat_s_rows,
                                         flat_z_rows, flat_z_fibers, flat_flags_rows,
                                         flat_flags_fibers, flagged);
    if (status != FLT_OK) return status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_flatness_push($self, flat_z_rows, flat_z_fibers, flat_s, flat_z,
                               flagged ? flat_flags : NULL, consumed_out, evaluated_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* Zone layout into (zones,) arrays; the fiber counts as doubles. */
  flt_status zone_layout_into(double *left_x_out, size_t left_x_out_n,
                              double *centre_x_out, size_t centre_x_out_n,
                              double *fiber_count_out, size_t fiber_count_out_n) {
    size_t zones = left_x_out_n, j;
    size_t *counts;
    flt_status status;
    if (centre_x_out_n != zones)
        return flt_py_shape_error("flt_flatness_zone_layout", "centre_x.shape[0]",
                                  centre_x_out_n, zones);
    if (fiber_count_out_n != zones)
        return flt_py_shape_error("flt_flatness_zone_layout", "fiber_count.shape[0]",
                                  fiber_count_out_n, zones);
    counts = (size_t *)PyMem_Malloc((zones ? zones : 1) * sizeof(size_t));
    if (counts == NULL) { PyErr_NoMemory(); return FLT_ERR_OUT_OF_MEMORY; }
    status = flt_flatness_zone_layout($self, zones, left_x_out, centre_x_out, counts);
    if (status == FLT_OK)
      for (j = 0; j < zones; ++j) fiber_count_out[j] = (double)counts[j];
    PyMem_Free(counts);
    return status;
  }

  /* (s_first, s_last, rows, window flags, index) as 5 doubles (exact below
   * 2^53). */
  flt_status window_into(double *window_out, size_t window_out_n) {
    size_t rows = 0, index = 0;
    unsigned flags = 0;
    flt_status status;
    if (window_out_n != 5)
        return flt_py_shape_error("flt_flatness_window", "out.shape[0]", window_out_n, 5);
    status = flt_flatness_window($self, &window_out[0], &window_out[1], &rows, &flags,
                                 &index);
    window_out[2] = (double)rows;
    window_out[3] = (double)flags;
    window_out[4] = (double)index;
    return status;
  }

  /* Per-fiber results into (K,) arrays. */
  flt_status fiber_results_into(double *arc_out, size_t arc_out_n, double *iu_out,
                                size_t iu_out_n, double *wave_height_out,
                                size_t wave_height_out_n, double *wave_period_out,
                                size_t wave_period_out_n, double *steepness_out,
                                size_t steepness_out_n, unsigned char *fiber_flags_out,
                                size_t fiber_flags_out_n) {
    const size_t k = arc_out_n;
    if (iu_out_n != k || wave_height_out_n != k || wave_period_out_n != k ||
        steepness_out_n != k || fiber_flags_out_n != k)
        return flt_py_shape_error("flt_flatness_fiber_results", "an output's length",
                                  iu_out_n, k);
    return flt_flatness_fiber_results($self, k, arc_out, iu_out, wave_height_out,
                                      wave_period_out, steepness_out, fiber_flags_out);
  }

  /* Zone I-Units and flags into (zones,) arrays. */
  flt_status zone_results_into(double *zone_iu_out, size_t zone_iu_out_n,
                               unsigned char *zone_flags_out, size_t zone_flags_out_n) {
    if (zone_flags_out_n != zone_iu_out_n)
        return flt_py_shape_error("flt_flatness_zone_results", "flags.shape[0]",
                                  zone_flags_out_n, zone_iu_out_n);
    return flt_flatness_zone_results($self, zone_iu_out_n, zone_iu_out, zone_flags_out);
  }

  /* (shape, confidence, components, bow_mm, crossbow_mm) as 5 doubles. */
  flt_status shape_into(double *shape_out, size_t shape_out_n) {
    flt_shape shape = FLT_SHAPE_UNDETERMINED;
    unsigned components = 0;
    flt_status status;
    if (shape_out_n != 5)
        return flt_py_shape_error("flt_flatness_shape", "out.shape[0]", shape_out_n, 5);
    status = flt_flatness_shape($self, &shape, &shape_out[1], &components, &shape_out[3],
                                &shape_out[4]);
    shape_out[0] = (double)shape;
    shape_out[2] = (double)components;
    return status;
  }

  /* One window with the strip's edges per row, left and right (n,) mm
   * (NaN: unknown). */
  flt_status evaluate_strip_rows(const double *flat_s, size_t flat_s_rows,
                                 const double *flat_z, size_t flat_z_rows, size_t flat_z_fibers,
                                 const unsigned char *flat_flags, size_t flat_flags_rows,
                                 size_t flat_flags_fibers, int flagged,
                                 const double *edge_left, size_t edge_left_rows,
                                 const double *edge_right, size_t edge_right_rows) {
    const char *fn = "flt_flatness_evaluate_strip";
    flt_status status = flt_py_flat_rows(fn, $self, flat_s_rows, flat_z_rows, flat_z_fibers,
                                         flat_flags_rows, flat_flags_fibers, flagged);
    if (status != FLT_OK) return status;
    if (edge_left_rows != flat_z_rows)
      return flt_py_shape_error(fn, "left_mm.shape[0]", edge_left_rows, flat_z_rows);
    if (edge_right_rows != flat_z_rows)
      return flt_py_shape_error(fn, "right_mm.shape[0]", edge_right_rows, flat_z_rows);
    Py_BEGIN_ALLOW_THREADS
    status = flt_flatness_evaluate_strip($self, flat_z_rows, flat_z_fibers, flat_s, flat_z,
                                         flagged ? flat_flags : NULL, edge_left, edge_right);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* Streaming push with the strip's edges; returns (consumed, evaluated). */
  flt_status push_strip_rows(const double *flat_s, size_t flat_s_rows,
                             const double *flat_z, size_t flat_z_rows, size_t flat_z_fibers,
                             const unsigned char *flat_flags, size_t flat_flags_rows,
                             size_t flat_flags_fibers, int flagged,
                             const double *edge_left, size_t edge_left_rows,
                             const double *edge_right, size_t edge_right_rows,
                             size_t *consumed_out, int *evaluated_out) {
    const char *fn = "flt_flatness_push_strip";
    flt_status status = flt_py_flat_rows(fn, $self, flat_s_rows, flat_z_rows, flat_z_fibers,
                                         flat_flags_rows, flat_flags_fibers, flagged);
    if (status != FLT_OK) return status;
    if (edge_left_rows != flat_z_rows)
      return flt_py_shape_error(fn, "left_mm.shape[0]", edge_left_rows, flat_z_rows);
    if (edge_right_rows != flat_z_rows)
      return flt_py_shape_error(fn, "right_mm.shape[0]", edge_right_rows, flat_z_rows);
    Py_BEGIN_ALLOW_THREADS
    status = flt_flatness_push_strip($self, flat_z_rows, flat_z_fibers, flat_s, flat_z,
                                     flagged ? flat_flags : NULL, edge_left, edge_right,
                                     consumed_out, evaluated_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The strip over the last window: width {mean, min, max} then centre
   * {mean, min, max}, mm (6 doubles). */
  flt_status strip_into(double *strip_out, size_t strip_out_n) {
    if (strip_out_n != 6)
      return flt_py_shape_error("flt_flatness_strip", "out.shape[0]", strip_out_n, 6);
    return flt_flatness_strip($self, strip_out, strip_out + 3);
  }

  /* Zone positions into (zones,) arrays; the fiber counts as doubles. */
  flt_status zone_positions_into(double *zone_strip_out, size_t zone_strip_out_n,
                                 double *zone_sensor_out, size_t zone_sensor_out_n,
                                 double *zone_width_out, size_t zone_width_out_n,
                                 double *zone_fibers_out, size_t zone_fibers_out_n) {
    const char *fn = "flt_flatness_zone_positions";
    size_t zones = zone_strip_out_n, j, *counts;
    flt_status status;
    if (zone_sensor_out_n != zones || zone_width_out_n != zones || zone_fibers_out_n != zones)
      return flt_py_shape_error(fn, "an output's length", zone_sensor_out_n, zones);
    counts = (size_t *)PyMem_Malloc((zones ? zones : 1) * sizeof(size_t));
    if (counts == NULL) { PyErr_NoMemory(); return FLT_ERR_OUT_OF_MEMORY; }
    status = flt_flatness_zone_positions($self, zones, zone_strip_out, zone_sensor_out,
                                         zone_width_out, counts);
    if (status == FLT_OK)
      for (j = 0; j < zones; ++j) zone_fibers_out[j] = (double)counts[j];
    PyMem_Free(counts);
    return status;
  }

  /* Result fiber positions into (K,) arrays. */
  flt_status fiber_positions_into(double *fiber_strip_out, size_t fiber_strip_out_n,
                                  double *fiber_sensor_out, size_t fiber_sensor_out_n) {
    if (fiber_sensor_out_n != fiber_strip_out_n)
      return flt_py_shape_error("flt_flatness_fiber_positions", "sensor_x.shape[0]",
                                fiber_sensor_out_n, fiber_strip_out_n);
    return flt_flatness_fiber_positions($self, fiber_strip_out_n, fiber_strip_out,
                                        fiber_sensor_out);
  }
}

%include "flatline/flatness.h"
