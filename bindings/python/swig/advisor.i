// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/advisor.h: the leveler advisor.
 *
 * Wrapped as they are: flt_advisor_create, _load, _load_text, _size,
 * _set_actuator, _actuator, _fit. Replaced by methods over
 * numpy arrays (shapes checked here, the GIL released around the solve):
 * flt_advisor_set_influence, _influence, _set_target, _identify, _advise.
 */

%ignore flt_advisor_destroy;
%ignore flt_advisor_set_influence;
%ignore flt_advisor_influence;
%ignore flt_advisor_set_target;
%ignore flt_advisor_identify;
%ignore flt_advisor_advise;

%typemap(in, numinputs=0) flt_advisor **out (flt_advisor *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_advisor **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_advisor *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) size_t *zones_out (size_t temp = 0),
                          size_t *actuators_out (size_t temp = 0),
                          size_t *steps_out (size_t temp = 0) { $1 = &temp; }
%typemap(argout) size_t *zones_out, size_t *actuators_out, size_t *steps_out {
  %append_output(PyLong_FromSize_t(*$1));
}
%typemap(in, numinputs=0) const char **unit_out (const char *temp = NULL) { $1 = ($1_ltype)&temp; }
%typemap(argout) const char **unit_out { %append_output(PyUnicode_FromString(*$1 ? *$1 : "")); }
%typemap(in, numinputs=0) double *min_out (double temp = 0.0), double *max_out (double temp = 0.0),
                          double *step_out (double temp = 0.0),
                          double *r_squared_out (double temp = 0.0),
                          double *rms_out (double temp = 0.0),
                          double *confidence_out (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *min_out, double *max_out, double *step_out, double *r_squared_out,
                 double *rms_out, double *confidence_out {
  %append_output(PyFloat_FromDouble(*$1));
}

%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *adv_target, size_t adv_target_n),
  (const double *adv_profile, size_t adv_profile_n),
  (const double *adv_sheet, size_t adv_sheet_n),
  (const double *adv_now, size_t adv_now_n)
};
%apply (double *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const double *adv_g, size_t adv_g_rows, size_t adv_g_cols),
  (const double *adv_du, size_t adv_du_rows, size_t adv_du_cols),
  (const double *adv_dp, size_t adv_dp_rows, size_t adv_dp_cols)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *adv_delta_out, size_t adv_delta_n),
  (double *adv_predicted_out, size_t adv_predicted_n)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *adv_g_out, size_t adv_g_out_rows, size_t adv_g_out_cols)
};

%nodefaultctor flt_advisor;
struct flt_advisor {};
%extend flt_advisor {
  ~flt_advisor() { flt_advisor_destroy($self); }

  /* G as a (zones, actuators) array. */
  flt_status set_influence_array(const double *adv_g, size_t adv_g_rows, size_t adv_g_cols) {
    size_t zones = 0, actuators = 0;
    flt_status st = flt_advisor_size($self, &zones, &actuators);
    if (st)
      return st;
    if (adv_g_rows != zones)
      return flt_py_shape_error("flt_advisor_set_influence", "g.shape[0]", adv_g_rows, zones);
    if (adv_g_cols != actuators)
      return flt_py_shape_error("flt_advisor_set_influence", "g.shape[1]", adv_g_cols,
                                actuators);
    return flt_advisor_set_influence($self, adv_g, adv_g_rows * adv_g_cols);
  }

  /* Into a (zones, actuators) array. */
  flt_status influence_into(double *adv_g_out, size_t adv_g_out_rows, size_t adv_g_out_cols) {
    return flt_advisor_influence($self, adv_g_out, adv_g_out_rows * adv_g_out_cols);
  }

  /* has_target 0: flat. */
  flt_status set_target_array(int has_target, const double *adv_target, size_t adv_target_n) {
    return has_target ? flt_advisor_set_target($self, adv_target, adv_target_n)
                      : flt_advisor_set_target($self, NULL, 0);
  }

  /* delta_u (steps, actuators), delta_p (steps, zones). */
  flt_status identify_arrays(const double *adv_du, size_t adv_du_rows, size_t adv_du_cols,
                             const double *adv_dp, size_t adv_dp_rows, size_t adv_dp_cols,
                             double ridge) {
    flt_status status;
    if (adv_dp_rows != adv_du_rows)
      return flt_py_shape_error("flt_advisor_identify", "delta_p.shape[0]", adv_dp_rows,
                                adv_du_rows);
    Py_BEGIN_ALLOW_THREADS
    status = flt_advisor_identify($self, adv_du_rows, adv_du, adv_du_rows * adv_du_cols, adv_dp,
                                  adv_dp_rows * adv_dp_cols, ridge);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The advice into delta (actuators,) and predicted (zones,); returns the
   * confidence. */
  flt_status advise_arrays(const double *adv_profile, size_t adv_profile_n,
                           const double *adv_sheet, size_t adv_sheet_n, const double *adv_now,
                           size_t adv_now_n, double *adv_delta_out, size_t adv_delta_n,
                           double *adv_predicted_out, size_t adv_predicted_n,
                           double *confidence_out) {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_advisor_advise($self, adv_profile, adv_profile_n, adv_sheet, adv_sheet_n,
                                adv_now, adv_now_n, adv_delta_out, adv_delta_n,
                                adv_predicted_out, adv_predicted_n, confidence_out);
    Py_END_ALLOW_THREADS
    return status;
  }
}

%include "flatline/advisor.h"
