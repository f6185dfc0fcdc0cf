// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/recon.h: the streaming Hermite reconstructor.
 *
 * flt_recon_create, _fibers, _ready, _pending, _get_option and _reset are
 * wrapped as they are. The array calls (push, pull, peek, boundary,
 * flt_reconstruct) and
 * end_sheet (which may solve a whole sheet) are replaced by methods whose
 * arguments follow numpy.i's patterns; they release the GIL around the C
 * call, so threads with their own handles run in parallel.
 *
 * The Python layer (flatline/_recon.py) validates and converts its inputs
 * first, with messages naming the argument; the checks here are the last
 * line of defence for direct callers: numpy.i checks dtype and ndim, and
 * every helper checks that the arrays agree with each other.
 */

%ignore flt_recon_destroy;
%ignore flt_recon_push;
%ignore flt_recon_pull;
%ignore flt_recon_peek;
%ignore flt_recon_end_sheet;
%ignore flt_recon_boundary;
%ignore flt_reconstruct;
%ignore flt_recon_push_flagged;
%ignore flt_reconstruct_flagged;

/* flt_reconstruct_release: the bytes freed, returned. */
%apply double *out { double *bytes_out };

%typemap(in, numinputs=0) flt_recon **out (flt_recon *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_recon **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_recon *), SWIG_POINTER_OWN));
}

%apply (double *IN_ARRAY1, size_t DIM1) { (const double *s, size_t s_rows) };
%apply (double *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const double *height, size_t height_rows, size_t height_fibers),
  (const double *slope, size_t slope_rows, size_t slope_fibers)
};
%apply (unsigned char *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const unsigned char *valid, size_t valid_rows, size_t valid_fibers)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *s_out, size_t s_out_rows),
  (double *height_out, size_t height_out_fibers),
  (double *slope_out, size_t slope_out_fibers)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *z_out, size_t z_out_rows, size_t z_out_fibers)
};
%apply (unsigned char *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (unsigned char *flags_out, size_t flags_out_rows, size_t flags_out_fibers)
};

%{
/* The shapes of one block of rows: s (n,), height and slope (n, K), valid
 * (n, K) or absent. */
static flt_status flt_py_check_block(const char *function, size_t s_rows,
                                     size_t height_rows, size_t height_fibers,
                                     size_t slope_rows, size_t slope_fibers,
                                     const unsigned char *valid,
                                     size_t valid_rows, size_t valid_fibers) {
    if (height_rows != s_rows)
        return flt_py_shape_error(function, "height.shape[0]", height_rows, s_rows);
    if (slope_rows != s_rows)
        return flt_py_shape_error(function, "slope.shape[0]", slope_rows, s_rows);
    if (slope_fibers != height_fibers)
        return flt_py_shape_error(function, "slope.shape[1]", slope_fibers,
                                  height_fibers);
    if (valid != NULL && valid_rows != s_rows)
        return flt_py_shape_error(function, "valid.shape[0]", valid_rows, s_rows);
    if (valid != NULL && valid_fibers != height_fibers)
        return flt_py_shape_error(function, "valid.shape[1]", valid_fibers,
                                  height_fibers);
    return FLT_OK;
}
%}

%nodefaultctor flt_recon;
struct flt_recon {};
%extend flt_recon {
  ~flt_recon() { flt_recon_destroy($self); }

  /* Pushes a block; `masked` selects whether `valid` is used (numpy.i has
   * no optional arrays, so the unmasked call passes a 1x1 dummy): 0 no
   * mask, 1 a validity mask, 2 the extractor's FLT_FLAG_* bits
   * (flt_recon_push_flagged). */
  flt_status push_block(const double *s, size_t s_rows,
                  const double *height, size_t height_rows, size_t height_fibers,
                  const double *slope, size_t slope_rows, size_t slope_fibers,
                  const unsigned char *valid, size_t valid_rows, size_t valid_fibers,
                  int masked) {
    flt_status status;
    if (!masked) valid = NULL;
    status = flt_py_check_block(masked == 2 ? "flt_recon_push_flagged" : "flt_recon_push",
                                s_rows, height_rows, height_fibers, slope_rows, slope_fibers,
                                valid, valid_rows, valid_fibers);
    if (status != FLT_OK) return status;
    Py_BEGIN_ALLOW_THREADS
    if (masked == 2)
      status = flt_recon_push_flagged($self, s_rows, height_fibers, s, height, slope, valid);
    else
      status = flt_recon_push($self, s_rows, height_fibers, s, height, slope, valid);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* Pulls up to s_out_rows rows into the caller's arrays; returns the count. */
  flt_status pull_into(double *s_out, size_t s_out_rows,
                  double *z_out, size_t z_out_rows, size_t z_out_fibers,
                  unsigned char *flags_out, size_t flags_out_rows,
                  size_t flags_out_fibers, size_t *out) {
    flt_status status;
    if (z_out_rows != s_out_rows)
        return flt_py_shape_error("flt_recon_pull", "z_out.shape[0]", z_out_rows,
                                  s_out_rows);
    if (flags_out_rows != s_out_rows)
        return flt_py_shape_error("flt_recon_pull", "flags_out.shape[0]",
                                  flags_out_rows, s_out_rows);
    if (flags_out_fibers != z_out_fibers)
        return flt_py_shape_error("flt_recon_pull", "flags_out.shape[1]",
                                  flags_out_fibers, z_out_fibers);
    Py_BEGIN_ALLOW_THREADS
    status = flt_recon_pull($self, s_out_rows, z_out_fibers, s_out, z_out,
                            flags_out, out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The provisional rows (flt_recon_peek), up to s_out_rows of them into
   * the caller's arrays; returns the count. */
  flt_status peek_into(double *s_out, size_t s_out_rows,
                  double *z_out, size_t z_out_rows, size_t z_out_fibers,
                  unsigned char *flags_out, size_t flags_out_rows,
                  size_t flags_out_fibers, size_t *out) {
    flt_status status;
    if (z_out_rows != s_out_rows)
        return flt_py_shape_error("flt_recon_peek", "z_out.shape[0]", z_out_rows,
                                  s_out_rows);
    if (flags_out_rows != s_out_rows)
        return flt_py_shape_error("flt_recon_peek", "flags_out.shape[0]",
                                  flags_out_rows, s_out_rows);
    if (flags_out_fibers != z_out_fibers)
        return flt_py_shape_error("flt_recon_peek", "flags_out.shape[1]",
                                  flags_out_fibers, z_out_fibers);
    Py_BEGIN_ALLOW_THREADS
    status = flt_recon_peek($self, s_out_rows, z_out_fibers, s_out, z_out,
                            flags_out, out);
    Py_END_ALLOW_THREADS
    return status;
  }

  flt_status finish_sheet() {
    flt_status status;
    Py_BEGIN_ALLOW_THREADS
    status = flt_recon_end_sheet($self);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The carry-over: fills height_out and slope_out (K,), returns the knot
   * position in mm. */
  flt_status boundary_into(double *height_out, size_t height_out_fibers,
                      double *slope_out, size_t slope_out_fibers, double *out) {
    if (slope_out_fibers != height_out_fibers)
        return flt_py_shape_error("flt_recon_boundary", "slope_out.shape[0]",
                                  slope_out_fibers, height_out_fibers);
    return flt_recon_boundary($self, height_out_fibers, out, height_out,
                              slope_out);
  }
}

%inline %{
/* flt_reconstruct over numpy arrays; z_out and flags_out are (N, K).
 * masked: 0 no mask, 1 `valid` is a mask, 2 it holds the extractor's
 * FLT_FLAG_* bits (flt_reconstruct_flagged). */
flt_status flt_py_reconstruct(const flt_options *options,
                              const double *s, size_t s_rows,
                              const double *height, size_t height_rows,
                              size_t height_fibers,
                              const double *slope, size_t slope_rows,
                              size_t slope_fibers,
                              const unsigned char *valid, size_t valid_rows,
                              size_t valid_fibers, int masked,
                              double *z_out, size_t z_out_rows,
                              size_t z_out_fibers,
                              unsigned char *flags_out, size_t flags_out_rows,
                              size_t flags_out_fibers) {
    flt_status status;
    if (!masked) valid = NULL;
    status = flt_py_check_block("flt_reconstruct", s_rows, height_rows,
                                height_fibers, slope_rows, slope_fibers, valid,
                                valid_rows, valid_fibers);
    if (status != FLT_OK) return status;
    if (z_out_rows != s_rows || z_out_fibers != height_fibers)
        return flt_py_shape_error("flt_reconstruct", "z_out.size",
                                  z_out_rows * z_out_fibers,
                                  s_rows * height_fibers);
    if (flags_out_rows != s_rows || flags_out_fibers != height_fibers)
        return flt_py_shape_error("flt_reconstruct", "flags_out.size",
                                  flags_out_rows * flags_out_fibers,
                                  s_rows * height_fibers);
    Py_BEGIN_ALLOW_THREADS
    if (masked == 2)
      status = flt_reconstruct_flagged(options, s_rows, height_fibers, s, height, slope,
                                       valid, z_out, flags_out);
    else
      status = flt_reconstruct(options, s_rows, height_fibers, s, height, slope,
                               valid, z_out, flags_out);
    Py_END_ALLOW_THREADS
    return status;
}
%}

%include "flatline/recon.h"
