// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/verdict.h: rule sets of flatness tolerances, the straightedge
 * deviation and verdicts.
 *
 * Wrapped as they are: flt_rules_load, _load_text, _count, _rule,
 * flt_verdict_create, _set_measure, _get, _failed. Replaced: the array
 * calls (flt_straightedge_profile, flt_verdict_evaluate) by helpers over
 * numpy arrays that release the GIL.
 */

%ignore flt_rules_destroy;
%ignore flt_verdict_destroy;
%ignore flt_straightedge_profile;
%ignore flt_verdict_evaluate;

%typemap(in, numinputs=0) flt_rules **out (flt_rules *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_rules **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_rules *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_verdict **out (flt_verdict *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_verdict **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_verdict *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_measure *measure_out (flt_measure temp = FLT_MEASURE_BOW) { $1 = &temp; }
%typemap(argout) flt_measure *measure_out { %append_output(PyLong_FromLong((long)*$1)); }
%typemap(in, numinputs=0) double *length_mm_out (double temp = 0.0),
                          double *at_out (double temp = 0.0) { $1 = &temp; }
%typemap(argout) double *length_mm_out, double *at_out { %append_output(PyFloat_FromDouble(*$1)); }

%apply (char *STRING, size_t LENGTH) { (const char *text, size_t length) };
%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *se_position, size_t se_position_n),
  (const double *se_height, size_t se_height_n),
  (const double *verdict_s, size_t verdict_s_n),
  (const double *verdict_x, size_t verdict_x_n)
};
%apply (double *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const double *verdict_z, size_t verdict_z_rows, size_t verdict_z_fibers)
};
%apply (unsigned char *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const unsigned char *verdict_flags, size_t verdict_flags_rows, size_t verdict_flags_fibers)
};

%inline %{
/* The straightedge deviation of one profile: (deviation, at). */
flt_status flt_py_straightedge_profile(const double *se_position, size_t se_position_n,
                                       const double *se_height, size_t se_height_n,
                                       double length_mm, double *out, double *at_out) {
    flt_status status;
    if (se_height_n != se_position_n)
        return flt_py_shape_error("flt_straightedge_profile", "heights.shape[0]", se_height_n,
                                  se_position_n);
    Py_BEGIN_ALLOW_THREADS
    status = flt_straightedge_profile(se_position, se_height, se_position_n, length_mm, out,
                                      at_out);
    Py_END_ALLOW_THREADS
    return status;
}
%}

%nodefaultctor flt_rules;
struct flt_rules {};
%extend flt_rules {
  ~flt_rules() { flt_rules_destroy($self); }
}

%nodefaultctor flt_verdict;
struct flt_verdict {};
%extend flt_verdict {
  ~flt_verdict() { flt_verdict_destroy($self); }

  /* One sheet: s (rows,), x (fibers,), z (rows, fibers) and flags (rows,
   * fibers) used when `flagged`; `has_map` 0 judges without a map. */
  flt_status evaluate_arrays(double thickness_mm, double width_mm, int has_map,
                             const double *verdict_s, size_t verdict_s_n,
                             const double *verdict_x, size_t verdict_x_n,
                             const double *verdict_z, size_t verdict_z_rows,
                             size_t verdict_z_fibers, int flagged,
                             const unsigned char *verdict_flags, size_t verdict_flags_rows,
                             size_t verdict_flags_fibers) {
    const char *fn = "flt_verdict_evaluate";
    flt_status status;
    if (!has_map) {
        Py_BEGIN_ALLOW_THREADS
        status = flt_verdict_evaluate($self, thickness_mm, width_mm, 0, 0, NULL, NULL, NULL,
                                      NULL);
        Py_END_ALLOW_THREADS
        return status;
    }
    if (verdict_s_n != verdict_z_rows)
        return flt_py_shape_error(fn, "s.shape[0]", verdict_s_n, verdict_z_rows);
    if (verdict_x_n != verdict_z_fibers)
        return flt_py_shape_error(fn, "x.shape[0]", verdict_x_n, verdict_z_fibers);
    if (flagged && verdict_flags_rows != verdict_z_rows)
        return flt_py_shape_error(fn, "flags.shape[0]", verdict_flags_rows, verdict_z_rows);
    if (flagged && verdict_flags_fibers != verdict_z_fibers)
        return flt_py_shape_error(fn, "flags.shape[1]", verdict_flags_fibers, verdict_z_fibers);
    Py_BEGIN_ALLOW_THREADS
    status = flt_verdict_evaluate($self, thickness_mm, width_mm, verdict_z_rows,
                                  verdict_z_fibers, verdict_s, verdict_x, verdict_z,
                                  flagged ? verdict_flags : NULL);
    Py_END_ALLOW_THREADS
    return status;
  }
}

%include "flatline/verdict.h"
