// SPDX-License-Identifier: Apache-2.0
/*
 * flatline/sim.h: the simulated sensor (and the reference-sensor
 * calibration, flt_calib_create_reference).
 *
 * Wrapped as they are: create (calib may be None: the reference sensor),
 * add_defect, clear_sheet, fibers, frame_size, pixel_format, rewind and
 * flt_calib_create_reference. The array calls are replaced by methods with
 * numpy.i's argument patterns; next_rows, next_frame and surface release the
 * GIL, so threads with their own simulators run in parallel.
 */

/* flt_pixel_format comes from extractor.h, wrapped by extractor.i. */

%ignore flt_sim_destroy;
%ignore flt_sim_set_height_map;
%ignore flt_sim_surface;
%ignore flt_sim_next_rows;
%ignore flt_sim_next_frame;
%ignore flt_sim_strip_edges;
%ignore flt_sim_fiber_flags;

%typemap(in, numinputs=0) flt_sim **out (flt_sim *temp = NULL) { $1 = &temp; }
%typemap(argout) flt_sim **out {
  %append_output(SWIG_NewPointerObj(*$1, $descriptor(flt_sim *), SWIG_POINTER_OWN));
}
%typemap(in, numinputs=0) flt_pixel_format *out (flt_pixel_format temp) { $1 = &temp; }
%typemap(argout) flt_pixel_format *out { %append_output(PyLong_FromLong((long)*$1)); }

%apply (double *IN_ARRAY2, size_t DIM1, size_t DIM2) {
  (const double *heights, size_t rows, size_t cols)
};
%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *x, size_t x_count),
  (const double *s, size_t s_count)
};
%apply (double *INPLACE_ARRAY1, size_t DIM1) {
  (double *z_out, size_t z_out_count),
  (double *encoder_out, size_t encoder_out_rows),
  (double *s_out, size_t s_out_rows),
  (double *truth_row_out, size_t truth_row_out_fibers),
  (double *edge_left_out, size_t edge_left_out_count),
  (double *edge_right_out, size_t edge_right_out_count)
};
%apply (double *IN_ARRAY1, size_t DIM1) {
  (const double *edge_encoder, size_t edge_encoder_count)
};
%apply (unsigned char *INPLACE_ARRAY1, size_t DIM1) {
  (unsigned char *edge_present_out, size_t edge_present_out_count),
  (unsigned char *sim_flags_out, size_t sim_flags_out_fibers)
};
%apply (double *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (double *height_out, size_t height_out_rows, size_t height_out_fibers),
  (double *slope_out, size_t slope_out_rows, size_t slope_out_fibers),
  (double *truth_out, size_t truth_out_rows, size_t truth_out_fibers),
  (double *peak_rows_out, size_t peak_rows_out_lasers, size_t peak_rows_out_width)
};
%apply (unsigned char *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (unsigned char *valid_out, size_t valid_out_rows, size_t valid_out_fibers),
  (unsigned char *frame8_out, size_t frame8_out_rows, size_t frame8_out_cols)
};
%apply (unsigned short *INPLACE_ARRAY2, size_t DIM1, size_t DIM2) {
  (unsigned short *frame16_out, size_t frame16_out_rows, size_t frame16_out_cols)
};

%{
/* Renders the next frame into a C-contiguous (height, width) array of
 * `bytes_per_pixel` bytes per pixel, with the truth (fibers,) and the exact
 * line centres (2, width). */
static flt_status flt_py_sim_frame(flt_sim *sim, void *frame, size_t frame_rows,
                                   size_t frame_cols, size_t bytes_per_pixel,
                                   double *truth, size_t truth_fibers,
                                   double *peak_rows, size_t peak_lasers,
                                   size_t peak_width, double *encoder_mm) {
    const char *fn = "flt_sim_next_frame";
    uint32_t width = 0, height = 0;
    flt_pixel_format format = FLT_PIXEL_MONO8;
    size_t fibers = 0;
    flt_status status;
    if ((status = flt_sim_frame_size(sim, &width, &height)) != FLT_OK ||
        (status = flt_sim_pixel_format(sim, &format)) != FLT_OK ||
        (status = flt_sim_fibers(sim, &fibers)) != FLT_OK)
        return status;
    if ((format == FLT_PIXEL_MONO8) != (bytes_per_pixel == 1)) {
        char message[160];
        PyOS_snprintf(message, sizeof message,
                      "%s: the simulator renders %d-bit pixels, which need a %s "
                      "frame_out", fn, (int)format,
                      format == FLT_PIXEL_MONO8 ? "uint8" : "uint16");
        flt_py_raise((int)FLT_ERR_INVALID_ARGUMENT, message);
        return FLT_ERR_INVALID_ARGUMENT;
    }
    if (frame_rows != height)
        return flt_py_shape_error(fn, "frame_out.shape[0]", frame_rows, height);
    if (frame_cols != width)
        return flt_py_shape_error(fn, "frame_out.shape[1]", frame_cols, width);
    if (truth_fibers != fibers)
        return flt_py_shape_error(fn, "truth_out.shape[0]", truth_fibers, fibers);
    if (peak_lasers != 2)
        return flt_py_shape_error(fn, "peak_rows_out.shape[0]", peak_lasers, 2);
    if (peak_width != width)
        return flt_py_shape_error(fn, "peak_rows_out.shape[1]", peak_width, width);
    Py_BEGIN_ALLOW_THREADS
    status = flt_sim_next_frame(sim, frame, frame_rows * frame_cols * bytes_per_pixel,
                                frame_cols * bytes_per_pixel, encoder_mm, fibers,
                                truth, peak_rows, peak_rows ? peak_lasers * peak_width : 0);
    Py_END_ALLOW_THREADS
    return status;
}
%}

%nodefaultctor flt_sim;
struct flt_sim {};
%extend flt_sim {
  ~flt_sim() { flt_sim_destroy($self); }

  /* heights (rows, cols), row r at s0 + r ds, column c at x0 + c dx (mm). */
  flt_status set_height_map_array(const double *heights, size_t rows, size_t cols,
                                  double s0_mm, double ds_mm, double x0_mm,
                                  double dx_mm) {
    return flt_sim_set_height_map($self, rows, cols, s0_mm, ds_mm, x0_mm, dx_mm,
                                  heights);
  }

  /* x, s, z_out: (count,) each. */
  flt_status surface_into(const double *x, size_t x_count, const double *s,
                          size_t s_count, double *z_out, size_t z_out_count) {
    flt_status status;
    if (s_count != x_count)
        return flt_py_shape_error("flt_sim_surface", "s.shape[0]", s_count, x_count);
    if (z_out_count != x_count)
        return flt_py_shape_error("flt_sim_surface", "z_out.shape[0]", z_out_count,
                                  x_count);
    Py_BEGIN_ALLOW_THREADS
    status = flt_sim_surface($self, x_count, x, s, z_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The next n rows into encoder (n,), s (n,), height, slope, valid, truth
   * (n, K). */
  flt_status next_rows_into(double *encoder_out, size_t encoder_out_rows,
                            double *s_out, size_t s_out_rows,
                            double *height_out, size_t height_out_rows,
                            size_t height_out_fibers,
                            double *slope_out, size_t slope_out_rows,
                            size_t slope_out_fibers,
                            unsigned char *valid_out, size_t valid_out_rows,
                            size_t valid_out_fibers,
                            double *truth_out, size_t truth_out_rows,
                            size_t truth_out_fibers) {
    const char *fn = "flt_sim_next_rows";
    const size_t rows = s_out_rows, fibers = height_out_fibers;
    flt_status status;
    if (encoder_out_rows != rows)
        return flt_py_shape_error(fn, "encoder_mm_out.shape[0]", encoder_out_rows, rows);
    if (height_out_rows != rows)
        return flt_py_shape_error(fn, "height_out.shape[0]", height_out_rows, rows);
    if (slope_out_rows != rows || slope_out_fibers != fibers)
        return flt_py_shape_error(fn, "slope_out.size", slope_out_rows * slope_out_fibers,
                                  rows * fibers);
    if (valid_out_rows != rows || valid_out_fibers != fibers)
        return flt_py_shape_error(fn, "valid_out.size", valid_out_rows * valid_out_fibers,
                                  rows * fibers);
    if (truth_out_rows != rows || truth_out_fibers != fibers)
        return flt_py_shape_error(fn, "truth_out.size", truth_out_rows * truth_out_fibers,
                                  rows * fibers);
    Py_BEGIN_ALLOW_THREADS
    status = flt_sim_next_rows($self, rows, fibers, encoder_out, s_out, height_out,
                               slope_out, valid_out, truth_out);
    Py_END_ALLOW_THREADS
    return status;
  }

  /* The next frame into an 8-bit (Mono8) or 16-bit (Mono10/12/16) array of
   * the frame size; returns the encoder position, mm. */
  flt_status next_frame_u8(unsigned char *frame8_out, size_t frame8_out_rows,
                           size_t frame8_out_cols, double *truth_row_out,
                           size_t truth_row_out_fibers, double *peak_rows_out,
                           size_t peak_rows_out_lasers, size_t peak_rows_out_width,
                           double *encoder_mm_out) {
    return flt_py_sim_frame($self, frame8_out, frame8_out_rows, frame8_out_cols, 1,
                            truth_row_out, truth_row_out_fibers, peak_rows_out,
                            peak_rows_out_lasers, peak_rows_out_width, encoder_mm_out);
  }

  flt_status next_frame_u16(unsigned short *frame16_out, size_t frame16_out_rows,
                            size_t frame16_out_cols, double *truth_row_out,
                            size_t truth_row_out_fibers, double *peak_rows_out,
                            size_t peak_rows_out_lasers, size_t peak_rows_out_width,
                            double *encoder_mm_out) {
    return flt_py_sim_frame($self, frame16_out, frame16_out_rows, frame16_out_cols, 2,
                            truth_row_out, truth_row_out_fibers, peak_rows_out,
                            peak_rows_out_lasers, peak_rows_out_width, encoder_mm_out);
  }

  /* The true edges under laser 0, 1 or 2 (the row) at the encoder
   * positions (n,): left, right (n,) mm and present (n,). */
  flt_status strip_edges_into(unsigned laser, const double *edge_encoder,
                              size_t edge_encoder_count, double *edge_left_out,
                              size_t edge_left_out_count, double *edge_right_out,
                              size_t edge_right_out_count, unsigned char *edge_present_out,
                              size_t edge_present_out_count) {
    const char *fn = "flt_sim_strip_edges";
    if (edge_left_out_count != edge_encoder_count)
      return flt_py_shape_error(fn, "left_mm_out.shape[0]", edge_left_out_count,
                                edge_encoder_count);
    if (edge_right_out_count != edge_encoder_count)
      return flt_py_shape_error(fn, "right_mm_out.shape[0]", edge_right_out_count,
                                edge_encoder_count);
    if (edge_present_out_count != edge_encoder_count)
      return flt_py_shape_error(fn, "present_out.shape[0]", edge_present_out_count,
                                edge_encoder_count);
    return flt_sim_strip_edges($self, laser, edge_encoder_count, edge_encoder, edge_left_out,
                               edge_right_out, edge_present_out);
  }

  /* The true fiber flags (K,) of a frame at encoder_mm. */
  flt_status fiber_flags_into(double encoder_mm, unsigned char *sim_flags_out,
                              size_t sim_flags_out_fibers) {
    return flt_sim_fiber_flags($self, encoder_mm, sim_flags_out_fibers, sim_flags_out);
  }
}

%include "flatline/sim.h"
