// SPDX-License-Identifier: Apache-2.0
// The frame-to-profile extractor (flatline/extractor.h): per column and laser
// the strongest valid peak in the laser's band, its sub-pixel row from the
// Savitzky-Golay derivative, the calibrated map to (x, z), and the resampling
// onto the fiber grid.
#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "calibration/calib_internal.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/options.hpp"
#include "extraction/extractor_internal.hpp"
#include "extraction/peak_kernels.hpp"
#include "flatline/extractor.h"
#include "flatline/recon.h"

using namespace flt;

namespace {

constexpr std::uint32_t k_extractor_magic = 0x464c5445u;  // "FLTE"
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// The column map (undistort + homography) as a polynomial of this degree in
// the row, fitted at k_map_nodes Chebyshev nodes over the band. Degree 5
// keeps the fit error below 1e-6 mm over a 128-row band of the reference
// lens (checked at build time, see map_error_mm).
constexpr int k_map_degree = 5;
constexpr int k_map_terms = k_map_degree + 1;
constexpr int k_map_nodes = 24;
// The shape check (flt_extractor::reject_misshapen): a peak is compared
// with the clean line's shape in its block of k_shape_block columns, which
// the quantiles of the block's peaks give even when a reflection lies along
// the line over half the block.
constexpr std::uint32_t k_shape_block = 256;  // columns
// A detour's peaks lie mostly farther than this from the chord between
// its neighbours (reject_detours).
constexpr double k_detour_tolerance_px = 3.0;
// Wide lines (a strip out of focus): a peak at least k_wide_line px wide at
// half maximum (as the shape check measures it) is centred by Steger's
// detector at the line's own scale instead of the Savitzky-Golay window,
// which is then narrower than the line and reads its noise (docs/sensor.md,
// "Centre estimators": the two are equal on lines of sigma 3.5 px, which
// measure about 8 px; on sigma 4 and 5 px Steger's error is 12 % and 28 %
// lower). Scales on a grid of k_wide_scale_step px from k_wide_line / 2.355
// (extended down to k_steger_first_scale for textured backgrounds) up to
// the widest line the extractor accepts (extract_max_width), at most
// k_wide_max_scale.
constexpr double k_wide_line = 8.0;                      // px at half maximum
constexpr double k_wide_scale_step = 0.25;               // px
constexpr double k_wide_max_scale = 16.0;                // px (reach 64 rows)
constexpr double k_fwhm_per_sigma = 2.3548200450309493;  // 2 sqrt(2 ln 2)
constexpr double k_wide_scale_factor = 1.3;              // scale per width / 2.355 (wide_centre)
// Steger's kernels start this fine (px), on the wide lines' grid, for the
// lines over a textured background (textured_block).
constexpr double k_steger_first_scale = k_wide_line / k_fwhm_per_sigma - 10 * k_wide_scale_step;
// A textured background: pixels beside the line that differ from row to row
// by more than k_texture_ratio of the line's height (the robust standard
// deviation of one pixel, from its row-to-row differences). Such a
// background is additive noise inside the line's rows, for which a
// Gaussian-weighted derivative (Steger's, at k_textured_scale_factor times
// the line's sigma) reads the centre with less error than the
// Savitzky-Golay window, whose weights suit the speckle that grows with the
// line's own light. Measured on the simulator (docs/sensor.md, "Centre
// estimators"): equal at 0.02 (texture 0.2 under ambient light 0.1 of full
// scale), Steger 20-28 % lower at 0.05-0.1; on clean lines (0.0035) the
// Savitzky-Golay centre is 25-45 % lower.
constexpr double k_texture_ratio = 0.03;
constexpr double k_textured_scale_factor = 1.2;
// Background rows sampled per side of the line, starting this many line
// widths (at half maximum) from its centre (3.5 sigma: the line's tail is
// 0.2 % of its height there), in every k_texture_sampling-th column (32:
// 8 columns, 64 steps a block; 16 measured the same at twice the cost).
constexpr long k_texture_rows = 4;
constexpr double k_texture_distance = 1.5;
constexpr std::uint32_t k_texture_sampling = 32;
// Thin lines: the Savitzky-Golay window is sized for a line of sigma 2 px
// (extract_sg_window 11 = 2.34 x its width at half maximum). On a thinner
// line such a window reaches past the line into its background, whose
// texture (a floor, a board's print, a coated strip) then drags the fitted
// parabola's vertex: on photos of a green line about 3 px wide across a
// printed chessboard the 11-row window read the line 0.50 px RMS from its
// course, a 7-row window 0.26 px. A peak narrower than the window's line is
// centred again with a window k_thin_window_per_width times its width
// (half-window at least 2 rows), the same zero-crossing search
// (thin_centre).
constexpr double k_thin_window_per_width = 2.34;
// The quantiles come from every k_shape_sampling-th column of the block (32
// peaks: the quartiles to about a quarter of the scatter), which keeps their
// cost small.
constexpr std::uint32_t k_shape_sampling = 8;
constexpr std::size_t k_shape_min_peaks = 8;  // sampled per block, else a neighbour's
constexpr std::size_t k_shape_samples = k_shape_block / k_shape_sampling;  // per block, at most
static_assert(k_shape_samples == 32, "sort_samples sorts 32 values");

// Batcher's odd-even merge sort of 32 values as its 191 compare-exchanges,
// listed at compile time. A block's quantiles are read from its samples
// sorted this way (min and max, no branches): about 150 ns per sort, three
// per block, where selecting each of five quantiles with std::nth_element
// took about 300 ns (its comparisons on noisy widths mispredict), a tenth of
// the extractor's time in a profile. The order statistics are the same
// values either way.
struct sort_network {
    unsigned char pair[256][2];
    int pairs;
};
constexpr sort_network make_sort_network() {
    sort_network net{};
    net.pairs = 0;
    for (int p = 1; p < 32; p <<= 1)
        for (int k = p; k >= 1; k >>= 1)
            for (int j = k % p; j + k < 32; j += 2 * k)
                for (int i = 0; i < k; ++i) {
                    const int x = i + j, y = i + j + k;
                    if (y < 32 && x / (2 * p) == y / (2 * p)) {
                        net.pair[net.pairs][0] = static_cast<unsigned char>(x);
                        net.pair[net.pairs][1] = static_cast<unsigned char>(y);
                        ++net.pairs;
                    }
                }
    return net;
}
constexpr sort_network k_sort_network = make_sort_network();
static_assert(k_sort_network.pairs == 191, "Batcher's network for 32 values");

// values[0, n) (n <= 32, no NaN) sorted ascending: the slots past n are
// filled with +infinity, which sorts after every value.
void sort_samples(double *values, std::size_t n) {
    for (std::size_t i = n; i < k_shape_samples; ++i)
        values[i] = std::numeric_limits<double>::infinity();
    for (int c = 0; c < k_sort_network.pairs; ++c) {
        double &a = values[k_sort_network.pair[c][0]], &b = values[k_sort_network.pair[c][1]];
        const double lo = std::min(a, b), hi = std::max(a, b);
        a = lo, b = hi;
    }
}
// Tolerances in robust standard deviations of the column-to-column scatter
// (from the blocks' quartiles), which the noise sets: with the reference
// speckle (5 % per pixel) and shot noise the scatter is about 4 % for the
// width, 2 % for the area and 0.8 % of the width for the skew, so the limits
// are about 1.2, 1.15 and 0.055 (set on the simulator: no wrong column
// beyond 0.7 px was kept, and no clean column rejected in 330,000).
constexpr double k_width_tolerance = 5;
constexpr double k_area_tolerance = 7;
constexpr double k_skew_tolerance = 7;
// The scatters never count as less than these (relative to the width or
// area): noise-free frames must not turn the small shape changes with the
// line's sub-pixel phase into rejections.
constexpr double k_min_scatter = 0.01;
constexpr double k_min_skew_scatter = 0.002;

void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

struct band {
    std::uint32_t first = 0, rows = 0;
    bool automatic = false;
};

// Where one laser sees the strip in a frame (flt_extractor::find_strip).
// Sides are in sensor x: 0 the low-x edge ("left"), 1 the high-x edge.
struct strip_view {
    bool present = false;
    bool open[2] = {true, true};  // that edge is not seen (beyond the view)
    double edge[2] = {0, 0};      // mm; NaN where open or absent
    // A glint lay on that edge's columns (edge_column); its edge was then
    // taken from the other laser where that one's was clean (cross_edges).
    bool glint[2] = {false, false};
    long u_first = 0, u_last = -1;  // the strip's outermost line columns
};

// Edge refinement (flt_extractor::edge_column): the partly covered column's
// share of the line's light, summed over this many columns either side of
// the strip's last line column, against the median light of the line
// columns between k_edge_reference_near and k_edge_reference_far inwards.
constexpr long k_edge_columns = 3;
constexpr long k_edge_reference_near = 4, k_edge_reference_far = 28;
// A glint on the edge (a sheared edge's burr, specular): one of the columns
// from k_edge_columns beyond the last line column to k_edge_glint_reach
// inside it holds more than k_edge_glint_light times the line's light. A
// clean line's columns scatter by their speckle, a few % of their light;
// the partly covered column holds less than a whole one. A glint saturates
// (the simulator's peak at 1.5-4 times full scale over 1-6 columns).
constexpr long k_edge_glint_reach = 6;
constexpr double k_edge_glint_light = 1.15;
// The two lasers' edges of one side shifted by more than this (mm, three
// times their clean scatter: 0.07-0.10 mm RMS each) show a yaw
// (cross_edges).
constexpr double k_edge_shift_mm = 0.3;
// Background rows either side of the light's window.
constexpr long k_edge_background_rows = 3;

}  // namespace

struct flt_extractor {
    std::uint32_t magic = k_extractor_magic;
    flt_calib *calib = nullptr;
    std::uint32_t width = 0, height = 0;
    double offset_mm[2] = {0, 0};
    unsigned ahead = 0;             // the laser reading the larger s
    double laser_spacing = 0;       // mm
    double first_x = 0, pitch = 1;  // fiber grid, mm
    std::size_t fibers = 0;

    band bands[2];
    bool maps_ready = false;
    int sg_half = 3;
    std::vector<float> sg_derivative;  // 2 * sg_half + 1 taps
    // Steger's kernels for wide lines, per scale i (k_wide_line / 2.355 +
    // i k_wide_scale_step px): the Gaussian's first and second derivatives
    // integrated over each pixel, taps -reach..reach, at wide_first[i].
    std::vector<double> wide_d1, wide_d2;
    std::vector<std::size_t> wide_first;
    std::vector<long> wide_reach;
    // Narrower Savitzky-Golay derivative taps for thin lines: thin_taps[h]
    // has 2 h + 1 taps (h from 2 to sg_half - 1; empty where the order does
    // not fit in the window).
    std::vector<std::vector<float>> thin_taps;
    double min_peak = 0.1, max_width = 12;
    double strip_min_z = -100, edge_gap = 50, min_strip_width = 100;  // mm

    // Per laser: the map of column u is x(t), z(t), t = (v - v_mid) / v_half,
    // coefficients poly[laser][(u * 2 + {0: x, 1: z}) * k_map_terms + k].
    std::vector<double> poly[2];
    double v_mid[2] = {0, 0}, v_half[2] = {1, 1};
    double map_error_mm = 0;          // largest fit error at the build check points
    std::vector<double> map_scratch;  // 2 * nodes * width

    // Per frame, reused.
    std::vector<std::uint16_t> best_value, best_row;  // [width]
    std::vector<double> peak_row[2];                  // [width], px
    std::vector<double> column_x[2], column_z[2];     // [width], mm
    std::vector<double> fiber_z[2];                   // [fibers], mm
    // suspect: saturated, or a brighter peak rejected (column_peak).
    std::vector<std::uint8_t> suspect_column, tainted_column, fringe_row;  // [width]
    // Columns the peak search found no line in at all (too faint above
    // their background, or too wide), which bridge_dim_stretches may fill.
    std::vector<std::uint8_t> no_peak_column;  // [width]
    std::vector<peak_shape> shape;             // [width]
    std::vector<double> shape_scratch;         // [width]
    // textured_block: a block's sampled background differences and heights.
    std::vector<double> texture_steps, texture_heights;
    // Per block of k_shape_block columns: the lower quartile of the widths
    // (px) and of the areas (counts x rows) and the relative scatters.
    std::vector<double> block_width, block_area, block_scatter;  // [blocks], [3 * blocks]
    // The median width of each block's peaks, px (NaN: not known).
    std::vector<double> block_line_width;
    // The line's slope in each block, rows per column (measure_block_slopes),
    // and the row steps it takes the median of ([width]).
    std::vector<double> block_slope, slope_steps;
    std::vector<double> fit_sums;         // [5 * fibers]
    std::vector<std::uint8_t> fit_flags;  // [fibers]
    double support = 1;                   // half-width of a fiber's resampling window, mm
    std::vector<double> row_sum;          // [height], auto band
    bool has_frame = false;
    // The line in the field, per frame: accepted saturated peaks, the
    // neighbours' median row (continuity check), the strip each laser sees,
    // its fibers off the strip, the row's flags, the saturation counts.
    std::vector<std::uint8_t> saturated_column;  // [width]
    // Where the peak is saturated: the column's best peak without it (the
    // line under a glint, if it shows), and its shape.
    std::vector<double> alternative_row;        // [width], px; read only where saturated
    std::vector<peak_shape> alternative_shape;  // [width]
    std::vector<std::uint32_t> saturated_run;   // [width], columns
    // A peak lower than extract_strip_min_z: the roller table's line (or
    // another line below the strip), not the strip's; the shape and
    // continuity checks leave it out of their references.
    std::vector<std::uint8_t> low_column;  // [width]
    std::size_t changed_rows = 0;          // peaks the checks rejected or replaced, this laser
    std::vector<double> edge_light;        // [width] scratch
    // reject_detours: the segments of peaks that continue each other.
    std::vector<std::uint32_t> segment_first, segment_last, segment_count;  // [width]
    // This laser's shape limits from reject_misshapen (false: too few peaks
    // to know the line's shape), for a peak found after it ran.
    bool shape_known = false;
    double shape_limit[3] = {0, 0, 0};  // width, area, skew factors
    // reject_detours: where it rejected a detour, the row the line is
    // expected at in each of its columns (the chord between the
    // neighbours), NaN elsewhere; it shares shape_scratch's storage
    // (reject_misshapen's scratch, done by then). detour_columns: how many.
    std::size_t detour_columns = 0;
    strip_view strip[2];
    std::vector<std::uint8_t> fiber_off[2];  // [fibers]
    std::vector<std::uint8_t> row_flags;     // [fibers], FLT_FLAG_*
    std::size_t peak_count[2] = {0, 0}, saturated_count[2] = {0, 0};

    ~flt_extractor() { flt_calib_destroy(calib); }

    void build_maps();
    void detect_bands(const unsigned char *frame, std::size_t stride, int bytes,
                      std::uint32_t full_scale);
    template <class Pixel>
    void extract(const unsigned char *frame, std::size_t stride, std::uint32_t full_scale);
    void build_wide_kernels();
    template <class Pixel>
    double thin_centre(const unsigned char *frame, std::size_t stride, std::uint32_t u, double row,
                       double width_px) const;
    template <class Pixel>
    double wide_centre(const unsigned char *frame, std::size_t stride, std::uint32_t u, double row,
                       double width_px) const;
    template <class Pixel>
    double steger_centre(const unsigned char *frame, std::size_t stride, std::uint32_t u,
                         double row, double scale) const;
    template <class Pixel>
    bool textured_block(const unsigned char *frame, std::size_t stride, const band &b,
                        std::size_t block, const double *rows);
    void resample(unsigned laser);
    void measure_block_slopes(const double *rows);
    void reject_glint_fringes(double *rows);
    void reject_detours(double *rows);
    bool far_course(const double *rows, long left_end, long right_end, double *u0, double *v0,
                    double *u1, double *v1) const;
    void reject_misshapen(double *rows);
    bool well_formed(std::uint32_t u, const peak_shape &sh) const;
    template <class Pixel>
    void look_under_detours(const unsigned char *frame, std::size_t stride, const band &b,
                            const peak_params &params, double *rows);
    template <class Pixel>
    std::size_t bridge_dim_stretches(const unsigned char *frame, std::size_t stride, const band &b,
                                     const peak_params &params, double *rows);
    template <class Pixel>
    void find_strip(const unsigned char *frame, std::size_t stride, unsigned laser,
                    std::uint32_t min_value);
    template <class Pixel>
    double edge_column(const unsigned char *frame, std::size_t stride, unsigned laser, long end,
                       long direction, bool *glint);
    void cross_edges();
    double column_map_x(unsigned laser, double u, double v) const;
};

namespace {

// Savitzky-Golay derivative taps: fit a polynomial of `order` to 2h + 1
// samples by least squares; the derivative at the centre is a fixed linear
// combination of the samples.
std::vector<float> sg_derivative_taps(int half, int order) {
    const int n = 2 * half + 1;
    Eigen::MatrixXd a(n, order + 1);
    for (int j = -half; j <= half; ++j) {
        const double t = double(j) / half;  // scaled for conditioning
        double p = 1;
        for (int k = 0; k <= order; ++k) {
            a(j + half, k) = p;
            p *= t;
        }
    }
    const Eigen::MatrixXd pinv = (a.transpose() * a).ldlt().solve(a.transpose());
    std::vector<float> taps(n);
    for (int j = 0; j < n; ++j)
        taps[j] = float(pinv(1, j) / half);  // d/dj = d/dt / h
    // Odd by symmetry; exactly so, since the peak kernel relies on it.
    for (int j = 1; j <= half; ++j) {
        const float odd = 0.5f * (taps[half + j] - taps[half - j]);
        taps[half + j] = odd, taps[half - j] = -odd;
    }
    taps[half] = 0;
    return taps;
}

}  // namespace

void flt_extractor::build_maps() {
    // Chebyshev nodes over the rows the SG window may touch.
    for (unsigned laser = 0; laser < 2; ++laser) {
        const band &b = bands[laser];
        const double lo = double(b.first) - sg_half - 1.0;
        const double hi = double(b.first + b.rows - 1) + sg_half + 1.0;
        v_mid[laser] = 0.5 * (lo + hi);
        v_half[laser] = 0.5 * (hi - lo);
    }
    double node_t[k_map_nodes];
    Eigen::Matrix<double, k_map_nodes, k_map_terms> vander;
    for (int i = 0; i < k_map_nodes; ++i) {
        node_t[i] = std::cos(M_PI * (i + 0.5) / k_map_nodes);
        double p = 1;
        for (int k = 0; k < k_map_terms; ++k) {
            vander(i, k) = p;
            p *= node_t[i];
        }
    }
    const Eigen::Matrix<double, k_map_terms, k_map_nodes> map_fit =
        (vander.transpose() * vander).ldlt().solve(vander.transpose());
    map_error_mm = 0;
    for (unsigned laser = 0; laser < 2; ++laser) {
        double *pts = map_scratch.data();
        for (std::uint32_t u = 0; u < width; ++u)
            for (int i = 0; i < k_map_nodes; ++i) {
                pts[2 * (std::size_t(u) * k_map_nodes + i)] = u;
                pts[2 * (std::size_t(u) * k_map_nodes + i) + 1] =
                    v_mid[laser] + v_half[laser] * node_t[i];
            }
        check(flt_calib_image_to_plane(calib, laser, std::size_t(width) * k_map_nodes, pts, pts));
        for (std::uint32_t u = 0; u < width; ++u) {
            const double *col = pts + 2 * std::size_t(u) * k_map_nodes;
            bool finite = true;
            Eigen::Matrix<double, k_map_nodes, 1> xs, zs;
            for (int i = 0; i < k_map_nodes; ++i) {
                xs(i) = col[2 * std::ptrdiff_t(i)], zs(i) = col[2 * std::ptrdiff_t(i) + 1];
                finite = finite && std::isfinite(xs(i)) && std::isfinite(zs(i));
            }
            double *cx = &poly[laser][(std::size_t(u) * 2 + 0) * k_map_terms];
            double *cz = &poly[laser][(std::size_t(u) * 2 + 1) * k_map_terms];
            if (!finite) {
                std::fill(cx, cx + k_map_terms, k_nan);
                std::fill(cz, cz + k_map_terms, k_nan);
                continue;
            }
            const Eigen::Matrix<double, k_map_terms, 1> ax = map_fit * xs, az = map_fit * zs;
            for (int k = 0; k < k_map_terms; ++k)
                cx[k] = ax(k), cz[k] = az(k);
            for (int i = 0; i < k_map_nodes; ++i) {
                double px = 0, pz = 0;
                for (int k = k_map_degree; k >= 0; --k)
                    px = px * node_t[i] + cx[k], pz = pz * node_t[i] + cz[k];
                map_error_mm =
                    std::max(map_error_mm, std::max(std::fabs(px - xs(i)), std::fabs(pz - zs(i))));
            }
        }
    }
    // The column spacing on the strip (mm per column) near the middle of the
    // frame and band: a fiber's window spans at least one spacing each side.
    const std::size_t mid_u = width / 2;
    const double *c0 = &poly[0][(mid_u * 2) * k_map_terms];
    const double *c1 = &poly[0][((mid_u + (width > 1 ? 1 : 0)) * 2) * k_map_terms];
    const double spacing = std::fabs(c1[0] - c0[0]);
    support = std::max(pitch, std::isfinite(spacing) ? 1.01 * spacing : pitch);
    maps_ready = true;
}

// The two brightest rows of the frame's row sums (every 4th column) are the
// lines; each band reaches halfway to the other line on both sides. Only
// rows where either laser's line can lie on the strip are searched: those
// of heights within -+extract_strip_min_z of the pass line under the middle
// of the fiber grid (the roller table's line, far lower, is brighter than
// a narrow strip's, and a head or tail shows only the table).
//
// A frame with one line (one laser switched on while commissioning, a still
// image) places both bands too, when the line can be only one laser's: the
// other laser's line is where the calibration puts it at the same height,
// and the bands are laid as for two lines. The row is one laser's when its
// height through that laser's plane lies within -+extract_strip_min_z and
// its height through the other's does not; a row that could be either is
// refused (a wrong guess would read every height wrong, with confidence).
void flt_extractor::detect_bands(const unsigned char *frame, std::size_t stride, int bytes,
                                 std::uint32_t full_scale) {
    // Each laser's line at the pass line (z = 0) under the middle of the
    // fiber grid, (u, v) px: the lasers' order, and the column the heights
    // of a single line are read in.
    const double x_mid = first_x + 0.5 * pitch * double(fibers - 1);
    double at_pass_line[2][2];
    for (unsigned laser = 0; laser < 2; ++laser) {
        double p[2] = {x_mid, 0.0};
        check(flt_calib_plane_to_image(calib, laser, 1, p, at_pass_line[laser]));
    }
    long allowed_lo = long(height), allowed_hi = -1;
    for (unsigned laser = 0; laser < 2; ++laser) {
        double p[4] = {x_mid, strip_min_z, x_mid, -strip_min_z}, img[4];
        check(flt_calib_plane_to_image(calib, laser, 2, p, img));
        for (int i = 0; i < 2; ++i)
            if (std::isfinite(img[2 * i + 1])) {
                const double v = std::min(std::max(img[2 * i + 1], -1.0), double(height));
                allowed_lo = std::min(allowed_lo, long(std::floor(v)));
                allowed_hi = std::max(allowed_hi, long(std::ceil(v)));
            }
    }
    allowed_lo = std::max(0L, allowed_lo);
    allowed_hi = std::min(long(height) - 1, allowed_hi);
    if (allowed_hi < allowed_lo)
        allowed_lo = 0, allowed_hi = long(height) - 1;  // the prediction failed: search all
    for (std::uint32_t v = 0; v < height; ++v) {
        const unsigned char *row = frame + std::size_t(v) * stride;
        double sum = 0;
        if (bytes == 1)
            for (std::uint32_t u = 0; u < width; u += 4)
                sum += row[u];
        else
            for (std::uint32_t u = 0; u < width; u += 4)
                sum += reinterpret_cast<const std::uint16_t *>(row)[u];
        row_sum[v] = sum;
    }
    const double floor_level = *std::min_element(row_sum.begin(), row_sum.end());
    const auto first =
        std::max_element(row_sum.begin() + allowed_lo, row_sum.begin() + allowed_hi + 1);
    const long r1 = long(first - row_sum.begin());
    const long exclusion = long(std::ceil(2 * max_width));
    long r2 = -1;
    for (long v = allowed_lo; v <= allowed_hi; ++v)
        if (std::labs(v - r1) > exclusion && (r2 < 0 || row_sum[v] > row_sum[r2]))
            r2 = v;
    long top, bottom;
    unsigned upper;
    if (r2 >= 0 && row_sum[r2] - floor_level > 0.25 * (row_sum[r1] - floor_level)) {
        // Two lines. Which laser is the upper line: the calibration's
        // prediction at z = 0 under the middle of the fiber grid.
        top = std::min(r1, r2), bottom = std::max(r1, r2);
        upper = at_pass_line[0][1] <= at_pass_line[1][1] ? 0 : 1;
    } else {
        // One line at most. It is one when its row stands out of the
        // others (outside the line's exclusion) by a quarter of
        // extract_min_peak per sampled column: a line over a quarter of
        // the width at the weakest peak the extractor accepts.
        double others = 0;
        std::size_t n_others = 0;
        for (long v = 0; v < long(height); ++v)
            if (std::labs(v - r1) > exclusion)
                others += row_sum[std::size_t(v)], ++n_others;
        const std::uint32_t sampled_columns = (width + 3) / 4;  // every 4th, as summed
        const double sampled = double(sampled_columns);
        const double excess = n_others ? (row_sum[r1] - others / double(n_others)) / sampled : 0;
        if (!(excess >= 0.25 * min_peak * double(full_scale)))
            throw error(FLT_ERR_NUMERIC,
                        "the first frame does not show two laser lines, nor one (no row "
                        "stands out); set the bands with extract_laser0_first_row/_rows and "
                        "extract_laser1_first_row/_rows");
        // Its height through each laser's plane, in the column that sees
        // the middle of the fiber grid.
        double z_of[2];
        for (unsigned laser = 0; laser < 2; ++laser) {
            double point[2] = {at_pass_line[laser][0], double(r1)}, plane[2];
            check(flt_calib_image_to_plane(calib, laser, 1, point, plane));
            z_of[laser] = plane[1];
        }
        // A laser could cast it when its height lies within the rows
        // searched; of two that could, the one that puts it nearer the
        // pass line did when the other puts it at least twice as far (the
        // strip runs near the pass line: the reference sensor tells the
        // lasers apart up to about 33 mm from it). Else it is ambiguous.
        const double reach = std::fabs(strip_min_z);
        bool could_be[2] = {std::fabs(z_of[0]) <= reach, std::fabs(z_of[1]) <= reach};
        if (could_be[0] && could_be[1]) {
            const unsigned nearer = std::fabs(z_of[0]) <= std::fabs(z_of[1]) ? 0 : 1;
            if (std::fabs(z_of[1 - nearer]) >= 2 * std::fabs(z_of[nearer]))
                could_be[1 - nearer] = false;
        }
        char message[320];
        if (could_be[0] == could_be[1]) {
            std::snprintf(message, sizeof message,
                          "the first frame shows one laser line, at row %ld, which would lie "
                          "at z = %.1f mm for laser 0 and %.1f mm for laser 1: %s laser's "
                          "(within -+extract_strip_min_z, one at most half as far from z = 0 "
                          "as the other); set the bands with "
                          "extract_laser0_first_row/_rows and extract_laser1_first_row/_rows",
                          r1, z_of[0], z_of[1], could_be[0] ? "either" : "neither");
            throw error(FLT_ERR_NUMERIC, message);
        }
        const unsigned seen = could_be[0] ? 0 : 1;
        double p[2] = {x_mid, z_of[seen]}, img[2];
        check(flt_calib_plane_to_image(calib, 1 - seen, 1, p, img));
        const double other = img[1];
        if (!(other >= 0 && other <= double(height) - 1) ||
            std::fabs(other - double(r1)) <= double(exclusion)) {
            std::snprintf(message, sizeof message,
                          "the first frame shows one laser line, laser %u's at row %ld; laser "
                          "%u's would lie at row %.1f, %s; set the bands with "
                          "extract_laser0_first_row/_rows and extract_laser1_first_row/_rows",
                          seen, r1, 1 - seen, other,
                          std::fabs(other - double(r1)) <= double(exclusion)
                              ? "too close to it for two bands"
                              : "outside the frame");
            throw error(FLT_ERR_NUMERIC, message);
        }
        const long r_other = long(std::lround(other));
        top = std::min(r1, r_other), bottom = std::max(r1, r_other);
        upper = r1 < r_other ? seen : 1 - seen;
        FLT_LOG(FLT_LOG_INFO, "extractor",
                "automatic bands from one line: laser %u's at row %ld (z = %.1f mm), laser "
                "%u's placed at row %ld by the calibration",
                seen, r1, z_of[seen], 1 - seen, r_other);
    }
    const long mid = (top + bottom + 1) / 2, half = (bottom - top) / 2;
    band b[2];
    b[upper].first = std::uint32_t(std::max(0L, top - half));
    b[upper].rows = std::uint32_t(mid - long(b[upper].first));
    b[1 - upper].first = std::uint32_t(mid);
    b[1 - upper].rows = std::uint32_t(std::min(long(height), bottom + half + 1) - mid);
    for (unsigned laser = 0; laser < 2; ++laser)
        if (long(b[laser].rows) < 2 * sg_half + 1)
            throw error(FLT_ERR_NUMERIC,
                        "the automatic band is shorter than the Savitzky-Golay window");
    for (unsigned laser = 0; laser < 2; ++laser)
        if (bands[laser].automatic)
            bands[laser].first = b[laser].first, bands[laser].rows = b[laser].rows;
    build_maps();
    for (unsigned laser = 0; laser < 2; ++laser)
        bands[laser].automatic = false;
}

template <class Pixel>
void flt_extractor::extract(const unsigned char *frame, std::size_t stride,
                            std::uint32_t full_scale) {
    const peak_params params{sg_half,
                             sg_derivative.data(),
                             std::uint32_t(std::ceil(min_peak * full_scale)),
                             full_scale,
                             int(std::floor(max_width)),
                             height,
                             long(3 * sg_half / 2),
                             long(std::max(3 * sg_half / 2, sg_half + 3))};
    for (unsigned laser = 0; laser < 2; ++laser) {
        const band &b = bands[laser];
        band_maximum<Pixel>(frame, stride, width, b.first, b.rows, best_value.data(),
                            best_row.data());
        double *rows_out = peak_row[laser].data();
        const double *coeffs = poly[laser].data();
        const double inv_half = 1.0 / v_half[laser], mid = v_mid[laser];
        bool any_suspect = false;
        // Eight columns at a time where the line is clean; column_peak
        // reads the rest (the same bits either way).
        unsigned measured = 0;
        for (std::uint32_t u = 0; u < width; ++u) {
            if (u % k_peak_lanes == 0)
                measured =
                    u + k_peak_lanes <= width
                        ? column_peaks<Pixel>(frame, stride, u, b.first, b.rows, &best_value[u],
                                              &best_row[u], params, &rows_out[u], &shape[u])
                        : 0;
            if ((measured >> (u % k_peak_lanes)) & 1u) {
                suspect_column[u] = saturated_column[u] = 0;
                continue;
            }
            bool suspect = false, saturated = false;
            rows_out[u] =
                column_peak<Pixel>(frame, stride, u, b.first, b.rows, best_value[u], best_row[u],
                                   params, true, &suspect, &saturated, &shape[u]);
            suspect_column[u] = suspect;
            saturated_column[u] = saturated;
            any_suspect = any_suspect || suspect;
            if (saturated) {
                // The reading without the saturated peak, for the
                // continuity check to choose from (a glint over the line).
                bool unused_suspect = false, unused_saturated = false;
                alternative_row[u] = column_peak<Pixel>(
                    frame, stride, u, b.first, b.rows, best_value[u], best_row[u], params, false,
                    &unused_suspect, &unused_saturated, &alternative_shape[u]);
            }
        }
        // A wide line is centred at its own scale (k_wide_line). Not one
        // whose maximum comes near full scale: there the sensor's response
        // flattens the top and a bright line glows, so the width measures
        // the flattening and the glow, not defocus, and the glow's
        // asymmetry would drag a kernel that wide (on the saturated red
        // photos it did: 87.0 -> 86.0 % kept, 0.22 -> 0.25 px).
        if (!wide_reach.empty())
            for (std::uint32_t u = 0; u < width; ++u)
                if (shape[u].width >= k_wide_line && !saturated_column[u] &&
                    4 * std::uint32_t(best_value[u]) < 3 * full_scale && rows_out[u] == rows_out[u])
                    rows_out[u] = wide_centre<Pixel>(frame, stride, u, rows_out[u], shape[u].width);
        for (std::uint32_t u = 0; u < width; ++u)
            no_peak_column[u] = !(rows_out[u] == rows_out[u]) && best_value[u] < full_scale;
        // (x, z) of column u's peak at row v through the column map.
        auto map_column = [&](std::uint32_t u, double v, double *x_out, double *z_out) {
            double x = k_nan, z = k_nan;
            if (v == v) {
                const double t = (v - mid) * inv_half;
                const double *cx = coeffs + (std::size_t(u) * 2) * k_map_terms;
                const double *cz = cx + k_map_terms;
                x = cx[k_map_degree], z = cz[k_map_degree];
                for (int k = k_map_degree - 1; k >= 0; --k)
                    x = x * t + cx[k], z = z * t + cz[k];
            }
            *x_out = x, *z_out = z;
        };
        // Lines below the strip (the roller table) are told apart first,
        // so that the checks' references are the strip's line alone; a
        // reading under a saturated peak that lies that low is no
        // alternative to it.
        double *xs = column_x[laser].data(), *zs = column_z[laser].data();
        for (std::uint32_t u = 0; u < width; ++u) {
            map_column(u, rows_out[u], &xs[u], &zs[u]);
            low_column[u] = zs[u] < strip_min_z;
            if (saturated_column[u] && alternative_row[u] == alternative_row[u]) {
                double x, z;
                map_column(u, alternative_row[u], &x, &z);
                if (z < strip_min_z)
                    alternative_row[u] = k_nan;
            }
        }
        // Shape first, so that the continuity check's medians see only
        // well-formed peaks.
        changed_rows = 0;
        reject_misshapen(rows_out);
        // A thin line is centred again with a window its own size
        // (k_thin_window_per_width), an unsaturated one only (a plateau's
        // centre is its half-maximum crossings' midpoint). Its width: the
        // median of its block's, which the shape check has just measured;
        // one column's width under speckle may be a single bright grain's.
        // A row that moves is mapped again at once (only its column).
        for (std::uint32_t u = 0; u < width; ++u) {
            const double line_width = block_line_width[u / k_shape_block];
            if (line_width * k_thin_window_per_width < double(2 * sg_half) &&
                !saturated_column[u] && !low_column[u] && rows_out[u] == rows_out[u]) {
                const double thin = thin_centre<Pixel>(frame, stride, u, rows_out[u], line_width);
                if (thin != rows_out[u]) {
                    rows_out[u] = thin;
                    map_column(u, thin, &xs[u], &zs[u]);
                }
            }
        }
        // Over a textured background (sim_texture under ambient light, a
        // concrete floor, scale) Steger's centre is the better (textured_block).
        for (std::size_t blk = 0; blk < block_line_width.size(); ++blk) {
            const double line_width = block_line_width[blk];
            if (wide_reach.empty() || !textured_block<Pixel>(frame, stride, b, blk, rows_out))
                continue;
            const double scale = std::max(k_steger_first_scale,
                                          k_textured_scale_factor * line_width / k_fwhm_per_sigma);
            const std::uint32_t u0 = std::uint32_t(blk) * k_shape_block;
            const std::uint32_t u1 = std::min(width, u0 + k_shape_block);
            for (std::uint32_t u = u0; u < u1; ++u)
                if (shape[u].width < k_wide_line && !saturated_column[u] && !low_column[u] &&
                    rows_out[u] == rows_out[u]) {
                    const double centre =
                        steger_centre<Pixel>(frame, stride, u, rows_out[u], scale);
                    if (centre != rows_out[u]) {
                        rows_out[u] = centre;
                        map_column(u, centre, &xs[u], &zs[u]);
                    }
                }
        }
        if (any_suspect)
            reject_glint_fringes(rows_out);
        reject_detours(rows_out);
        if (detour_columns > 0)
            look_under_detours<Pixel>(frame, stride, b, params, rows_out);
        changed_rows += bridge_dim_stretches<Pixel>(frame, stride, b, params, rows_out);
        // The checks reject peaks or take the reading under a saturated
        // one (rarely): then the columns are mapped again.
        if (changed_rows)
            for (std::uint32_t u = 0; u < width; ++u)
                map_column(u, rows_out[u], &xs[u], &zs[u]);
        find_strip<Pixel>(frame, stride, laser, params.min_value);
    }
    // The fibers after both lasers' edges are known (cross_edges).
    cross_edges();
    for (unsigned laser = 0; laser < FLT_CALIB_LASERS; ++laser)
        resample(laser);
}

// Whether the background beside block `block`'s line is textured
// (k_texture_ratio): in every k_texture_sampling-th column with an
// unsaturated peak on the strip's line, the k_texture_rows + 1 rows on
// either side from k_texture_distance line widths off its centre (inside
// the band) give their row-to-row steps and the column its height (its
// brightest pixel over their mean). The block is textured when the median
// |step| / (0.6745 sqrt 2), one pixel's robust noise, exceeds
// k_texture_ratio of the median height; fewer than 4 columns: not judged
// (false). About 2 % of a frame's time (every 32nd column).
template <class Pixel>
bool flt_extractor::textured_block(const unsigned char *frame, std::size_t stride, const band &b,
                                   std::size_t block, const double *rows) {
    const double line_width = block_line_width[block];
    if (!(line_width > 0))
        return false;
    const long reach = long(std::ceil(k_texture_distance * line_width));
    const long first = long(b.first), last = long(b.first + b.rows) - 1;
    const std::uint32_t u0 = std::uint32_t(block) * k_shape_block;
    const std::uint32_t u1 = std::min(width, u0 + k_shape_block);
    std::size_t steps = 0, columns = 0;
    for (std::uint32_t u = u0; u < u1; u += k_texture_sampling) {
        if (!(rows[u] == rows[u]) || saturated_column[u] || low_column[u])
            continue;
        const long centre = std::lround(rows[u]);
        if (centre - reach - k_texture_rows < first || centre + reach + k_texture_rows > last)
            continue;
        double sum = 0;
        for (long side = -1; side <= 1; side += 2) {
            double previous = 0;
            for (long i = 0; i <= k_texture_rows; ++i) {
                const long v = centre + side * (reach + i);
                const double pixel =
                    double(reinterpret_cast<const Pixel *>(frame + std::size_t(v) * stride)[u]);
                sum += pixel;
                if (i > 0)
                    texture_steps[steps++] = std::fabs(pixel - previous);
                previous = pixel;
            }
        }
        texture_heights[columns++] = double(best_value[u]) - sum / double(2 * (k_texture_rows + 1));
    }
    if (columns < 4)
        return false;
    std::nth_element(texture_heights.begin(), texture_heights.begin() + long(columns / 2),
                     texture_heights.begin() + long(columns));
    const double line_height = texture_heights[columns / 2];
    if (!(line_height > 0))
        return false;
    // The median |step| above k_texture_ratio * line_height * 0.6745 sqrt 2:
    // more than half of the steps above it (a count, not a sort).
    const double limit = k_texture_ratio * line_height * 0.6745 * std::sqrt(2.0);
    std::size_t above = 0;
    for (std::size_t i = 0; i < steps; ++i)
        above += texture_steps[i] > limit;
    return 2 * above > steps;
}

// Steger's kernels at scales s = k_steger_first_scale + i k_wide_scale_step
// up to the widest line extract_max_width lets through (at most
// k_wide_max_scale): tap k of the first derivative is the Gaussian's
// increase over the pixel k -+ 1/2, g(k + 1/2) - g(k - 1/2), and of the
// second the same of its derivative; 4 s rows each side. None when no line
// 2.1 px wide is accepted (extract_max_width below 2.1).
void flt_extractor::build_wide_kernels() {
    wide_d1.clear(), wide_d2.clear(), wide_first.clear(), wide_reach.clear();
    const double first_scale = k_steger_first_scale;
    const double last_scale = std::min(k_wide_max_scale, max_width / k_fwhm_per_sigma);
    for (int i = 0; first_scale + i * k_wide_scale_step <= last_scale + 1e-9; ++i) {
        const double scale = first_scale + i * k_wide_scale_step;
        const long reach = long(std::ceil(4 * scale));
        wide_first.push_back(wide_d1.size());
        wide_reach.push_back(reach);
        auto density = [&](double x) {
            return std::exp(-0.5 * x * x / (scale * scale)) / (scale * std::sqrt(2 * M_PI));
        };
        auto slope = [&](double x) {
            return -x / (scale * scale) * density(x);
        };
        for (long k = -reach; k <= reach; ++k) {
            const double a = double(k) - 0.5, b = double(k) + 0.5;
            wide_d1.push_back(density(b) - density(a));
            wide_d2.push_back(slope(b) - slope(a));
        }
    }
}

// The centre of a wide line in column u (Steger's detector in one
// dimension): the profile r = I * g at the grid's scale nearest
// k_wide_scale_factor width_px / 2.355,
// its centre row v0 + t with t = -r'(v0) / r''(v0), from the row nearest the
// Savitzky-Golay centre `row` or, when the step leaves that pixel, from its
// neighbour (the one with the shorter step). A constant background drops
// out (the first kernel sums to zero; the second to within e^-8 of it).
// `row` itself where the kernel leaves the frame or the profile is not
// concave there.
template <class Pixel>
double flt_extractor::wide_centre(const unsigned char *frame, std::size_t stride, std::uint32_t u,
                                  double row, double width_px) const {
    // The shape's width is measured against the local background within
    // gather_reach rows, which on a wide line is still its own flank: a
    // sigma of 4-5 px measures 1.9-2.1 sigma instead of 2.355 sigma. The
    // factor brings the scale back to at least the line's sigma, where the
    // centre's noise is least (of 1, 1.15 and 1.3, 1.3 read best).
    return steger_centre<Pixel>(frame, stride, u, row,
                                k_wide_scale_factor * width_px / k_fwhm_per_sigma);
}

// Steger's centre at `scale` (px; the grid's nearest), as wide_centre says.
template <class Pixel>
double flt_extractor::steger_centre(const unsigned char *frame, std::size_t stride, std::uint32_t u,
                                    double row, double scale) const {
    const double first_scale = k_steger_first_scale;  // the grid's
    const std::size_t i =
        std::min(wide_reach.size() - 1,
                 std::size_t(std::max(0.0, std::round((scale - first_scale) / k_wide_scale_step))));
    const long reach = wide_reach[i];
    const double *d1 = wide_d1.data() + wide_first[i] + std::size_t(reach);
    const double *d2 = wide_d2.data() + wide_first[i] + std::size_t(reach);
    auto step_at = [&](long v0) {
        if (v0 - reach < 0 || v0 + reach >= long(height))
            return k_nan;
        double r1 = 0, r2 = 0;
        for (long k = -reach; k <= reach; ++k) {
            const double light =
                double(reinterpret_cast<const Pixel *>(frame + std::size_t(v0 - k) * stride)[u]);
            r1 += light * d1[k], r2 += light * d2[k];
        }
        return r2 < 0 ? -r1 / r2 : k_nan;
    };
    const long v0 = std::lround(row);
    const double t0 = step_at(v0);
    double best = t0;
    long best_v = v0;
    if (std::fabs(t0) > 0.5) {
        const long v1 = v0 + (t0 > 0 ? 1 : -1);
        const double t1 = step_at(v1);
        if (std::fabs(t1) < std::fabs(t0))
            best = t1, best_v = v1;
    }
    return std::fabs(best) <= 1.0 ? double(best_v) + best : row;
}

// The zero crossing of a narrower Savitzky-Golay derivative (2 h + 1 rows
// about width x k_thin_window_per_width, h from 2 to sg_half - 1) next to
// `row`, the peak the full window found: the rows around it are
// searched as column_peak does (at most 2 rows away). Where the window
// leaves the frame, no crossing is found or it lies farther than the
// line's width from `row` (the wide window can be dragged by more than half
// the width, by a step in the background a few rows away), `row` stands.
template <class Pixel>
double flt_extractor::thin_centre(const unsigned char *frame, std::size_t stride, std::uint32_t u,
                                  double row, double width_px) const {
    const long h = std::clamp(std::lround(0.5 * (width_px * k_thin_window_per_width - 1)), 2L,
                              long(sg_half) - 1);
    const std::vector<float> &taps = thin_taps[std::size_t(h)];
    const long i0 = long(std::floor(row));
    if (taps.empty() || i0 - 3 - h < 0 || i0 + 3 + h >= long(height))
        return row;
    auto px = [&](long v) {
        return float(reinterpret_cast<const Pixel *>(frame + std::size_t(v) * stride)[u]);
    };
    auto derivative = [&](long i) {
        float d = 0;
        for (long j = 1; j <= h; ++j)
            d += taps[std::size_t(h + j)] * (px(i + j) - px(i - j));
        return d;
    };
    // The crossing (+ above, - below) between rows i and i + 1, nearest
    // the full window's first.
    double best = row;
    double nearest = width_px;
    for (long i = i0 - 2; i <= i0 + 2; ++i) {
        const float d0 = derivative(i), d1 = derivative(i + 1);
        if (d0 > 0 && d1 <= 0) {
            const double v = double(i) + double(d0) / double(d0 - d1);
            if (std::fabs(v - row) <= nearest)
                best = v, nearest = std::fabs(v - row);
        }
    }
    return best;
}

// x (mm) of the column map of laser L at a fractional column u and row v:
// linear between the two columns around u. NaN outside the frame.
double flt_extractor::column_map_x(unsigned laser, double u, double v) const {
    if (!(u >= 0 && u <= double(width - 1)))
        return k_nan;
    const std::size_t u0 = std::min(std::size_t(u), std::size_t(width > 1 ? width - 2 : 0));
    const double t = (v - v_mid[laser]) / v_half[laser];
    double x[2];
    for (int i = 0; i < 2; ++i) {
        const double *cx = &poly[laser][((u0 + std::size_t(i)) * 2) * k_map_terms];
        double value = cx[k_map_degree];
        for (int k = k_map_degree - 1; k >= 0; --k)
            value = value * t + cx[k];
        x[i] = value;
    }
    return width > 1 ? x[0] + (u - double(u0)) * (x[1] - x[0]) : x[0];
}

// The light of the line in column u around row v (counts x rows): the sum
// over rows v -+ reach above the column's background there (the mean of
// the k_edge_background_rows rows beyond either end). A column the strip
// covers in part gets that share of the line's light (the pixel integrates
// over its width), which makes the edge measurable to a fraction of a
// column. NaN where the rows leave the frame.
template <class Pixel>
static double line_light(const unsigned char *frame, std::size_t stride, std::uint32_t height,
                         long u, double v, long reach) {
    const long centre = long(std::lround(v));
    const long first = centre - reach - k_edge_background_rows;
    const long last = centre + reach + k_edge_background_rows;
    if (first < 0 || last >= long(height))
        return k_nan;
    auto px = [&](long row) -> double {
        return double(reinterpret_cast<const Pixel *>(frame + std::size_t(row) * stride)[u]);
    };
    double light = 0, background = 0;
    for (long row = centre - reach; row <= centre + reach; ++row)
        light += px(row);
    for (long j = 1; j <= k_edge_background_rows; ++j)
        background += px(centre - reach - j) + px(centre + reach + j);
    background /= double(2 * k_edge_background_rows);
    return light - double(2 * reach + 1) * background;
}

// The strip's edge beyond its last line column `end`, the strip lying
// towards -direction: a fractional column, NaN when it is not seen. The
// columns end -+ k_edge_columns each hold a share phi = light / reference
// (clamped to [0, 1]: a glint cannot cover more than the whole column) of
// the line's light, so the strip covers sum(phi) columns of them:
//   edge = end - direction (k_edge_columns + 1/2) + direction sum(phi)
// (pixel u spans u -+ 1/2). The reference is the median light of the line
// columns k_edge_reference_near..far inwards, each at its own row. *glint
// says whether a glint lay on the edge (k_edge_glint_light): then the
// columns' shares are too large and the edge lies outward.
template <class Pixel>
double flt_extractor::edge_column(const unsigned char *frame, std::size_t stride, unsigned laser,
                                  long end, long direction, bool *glint) {
    const long w = long(width);
    *glint = false;
    if (end - direction * k_edge_columns < 0 || end - direction * k_edge_columns >= w ||
        end + direction * (k_edge_columns + 1) < 0 || end + direction * (k_edge_columns + 1) >= w)
        return k_nan;  // the strip reaches (nearly) the frame's border: not seen
    const double *rows = peak_row[laser].data();
    const long reach = sg_half + 2;
    std::size_t n = 0;
    for (long i = k_edge_reference_near; i <= k_edge_reference_far; ++i) {
        const long u = end - direction * i;
        if (u < 0 || u >= w || !(rows[u] == rows[u]))
            continue;
        const double light = line_light<Pixel>(frame, stride, height, u, rows[u], reach);
        if (light == light)
            edge_light[n++] = light;
    }
    if (n < 3)
        return k_nan;
    std::nth_element(edge_light.begin(), edge_light.begin() + long(n / 2),
                     edge_light.begin() + long(n));
    const double reference = edge_light[n / 2];
    if (!(reference > 0))
        return k_nan;
    const double v = rows[end];
    double covered = 0;
    for (long i = -k_edge_columns; i <= k_edge_columns; ++i) {
        const double light =
            line_light<Pixel>(frame, stride, height, end + direction * i, v, reach);
        if (!(light == light))
            return k_nan;
        covered += std::min(1.0, std::max(0.0, light / reference));
        *glint = *glint || light > k_edge_glint_light * reference;
    }
    for (long i = k_edge_columns + 1; i <= k_edge_glint_reach; ++i) {
        const long u = end - direction * i;
        if (u < 0 || u >= w || !(rows[u] == rows[u]))
            continue;
        const double light = line_light<Pixel>(frame, stride, height, u, rows[u], reach);
        *glint = *glint || light > k_edge_glint_light * reference;
    }
    return double(end) - double(direction) * (double(k_edge_columns) + 0.5) +
           double(direction) * covered;
}

// Where laser L sees the strip in this frame. A column holds the strip's
// line when it has a valid peak at least extract_strip_min_z high (a lower
// line is the roller table). Runs of such columns continue across columns
// whose peak was rejected (there is light: a reflection, a glint) and
// across dark stretches (no peak above extract_min_peak, or the table) up to
// extract_edge_gap mm wide (dust, scale); the widest run at least
// extract_min_strip_width mm wide is the strip. Its ends are refined to a
// fraction of a column from the light the partly covered columns hold
// (edge_column), and mapped to x through the column map at the end
// column's row.
template <class Pixel>
void flt_extractor::find_strip(const unsigned char *frame, std::size_t stride, unsigned laser,
                               std::uint32_t min_value) {
    strip_view &sv = strip[laser];
    sv = strip_view();
    sv.edge[0] = sv.edge[1] = k_nan;
    const double *xs = column_x[laser].data(), *zs = column_z[laser].data();
    const long w = long(width);
    auto is_line = [&](long u) {
        return xs[u] == xs[u] && zs[u] >= strip_min_z;
    };
    auto is_dark = [&](long u) {
        return best_value[std::size_t(u)] < min_value || (zs[u] == zs[u] && zs[u] < strip_min_z);
    };
    // best_value holds this laser's band maximum (band_maximum ran last for
    // it in extract()).
    // Per run: its line columns and the saturated ones among them (the
    // strip's saturation, for flt_extractor_saturation: a line beside the
    // strip is no reason to change the exposure).
    long best_first = 0, best_last = -1;
    double best_extent = -1;
    long run_first = -1, run_last = -1;
    std::size_t run_peaks = 0, run_saturated = 0;
    peak_count[laser] = saturated_count[laser] = 0;
    auto close_run = [&]() {
        if (run_first < 0)
            return;
        const double extent = std::fabs(xs[run_last] - xs[run_first]);
        if (extent > best_extent) {
            best_extent = extent, best_first = run_first, best_last = run_last;
            peak_count[laser] = run_peaks, saturated_count[laser] = run_saturated;
        }
    };
    for (long u = 0; u < w; ++u) {
        if (!is_line(u))
            continue;
        if (run_first >= 0 && u > run_last + 1) {
            // The longest dark stretch between the two line columns.
            long longest = 0, current = 0;
            for (long g = run_last + 1; g < u; ++g) {
                current = is_dark(g) ? current + 1 : 0;
                longest = std::max(longest, current);
            }
            const double mm_per_column = std::fabs(xs[u] - xs[run_last]) / double(u - run_last);
            if (double(longest) * mm_per_column > edge_gap) {
                close_run();
                run_first = -1;
            }
        }
        if (run_first < 0)
            run_first = u, run_peaks = run_saturated = 0;
        run_last = u;
        ++run_peaks;
        run_saturated += saturated_column[std::size_t(u)];
    }
    close_run();
    if (best_last < 0 || best_extent < min_strip_width) {
        peak_count[laser] = saturated_count[laser] = 0;
        return;  // no strip under this laser
    }
    sv.present = true;
    sv.u_first = best_first;
    sv.u_last = best_last;
    bool glint[2];
    const double u_edge[2] = {edge_column<Pixel>(frame, stride, laser, best_first, -1, &glint[0]),
                              edge_column<Pixel>(frame, stride, laser, best_last, +1, &glint[1])};
    const double x_edge[2] = {column_map_x(laser, u_edge[0], peak_row[laser][best_first]),
                              column_map_x(laser, u_edge[1], peak_row[laser][best_last])};
    // Sensor x may run either way with u.
    const bool increasing = xs[best_last] > xs[best_first];
    for (int end = 0; end < 2; ++end) {
        const int side = increasing ? end : 1 - end;
        sv.open[side] = !(x_edge[end] == x_edge[end]);
        sv.edge[side] = x_edge[end];
        sv.glint[side] = glint[end] && !sv.open[side];
    }
}

// An edge with a glint on it lies outward: the glint's light makes the
// partly covered columns look covered. The other laser sees the same edge
// laser spacing further along the strip, and glints are specular: where
// that laser's edge is clean, it is taken. The two edges differ by the
// strip's yaw times the spacing (a guided strip: about 1e-3, 0.1 mm). A
// larger shift shows on the far side when both lasers' edges there are
// clean: beyond k_edge_shift_mm it is added. Where both lasers' edges have
// a glint, both stay as measured, flagged.
void flt_extractor::cross_edges() {
    strip_view &a = strip[0], &b = strip[1];
    if (!(a.present && b.present))
        return;
    const double before[2][2] = {{a.edge[0], a.edge[1]}, {b.edge[0], b.edge[1]}};
    for (int side = 0; side < 2; ++side) {
        if (a.open[side] || b.open[side] || a.glint[side] == b.glint[side])
            continue;
        const bool a_glint = a.glint[side];
        strip_view &glinted = a_glint ? a : b;
        const int other = 1 - side;
        double shift = 0;  // glinted minus clean, from the far side
        if (!a.open[other] && !b.open[other] && !a.glint[other] && !b.glint[other])
            shift =
                a_glint ? before[0][other] - before[1][other] : before[1][other] - before[0][other];
        glinted.edge[side] = (a_glint ? before[1][side] : before[0][side]) +
                             (std::fabs(shift) > k_edge_shift_mm ? shift : 0.0);
    }
}

// A dim secondary reflection that overlaps the line (within a few line
// widths) passes the peak search: the sum is one unsaturated peak narrower
// than extract_max_width. But the Savitzky-Golay derivative over its window
// acts much like a centroid, and the reflection drags it by up to 1.5 px
// (3 mm of z on the reference sensor). The same reflection adds light next
// to the line (area), widens it at half maximum (width) and pulls its
// half-maximum crossings off-centre (skew), while a clean line keeps the
// shape of its neighbours. So a peak is rejected when
//   width > W (1 + (0.6745 + k_width_tolerance) sigma_w),
//   area  > A (1 + (0.6745 + k_area_tolerance) sigma_a),
//   |skew| > k_skew_tolerance sigma_s W,
// or when its shape cannot be measured. W and A are the lower quartiles of
// the widths and areas of the peaks in the column's block, interpolated
// linearly between block centres (a line whose width or brightness changes
// slowly across the frame is followed), the 0.6745 steps from the quartile
// to the median, and sigma_w, sigma_a, sigma_s are the relative scatters
// (interquartile half-range / 0.6745 / median, and the median |skew| /
// 0.6745 / median width), the median over the blocks so that a block full
// of reflections does not loosen its own limits. Noisier frames get wider
// limits by themselves. A reflection that coincides with the line to within
// a fraction of its width adds little area and moves the centre by little.
void flt_extractor::reject_misshapen(double *rows) {
    const std::size_t blocks = block_width.size();
    double *values = shape_scratch.data();
    // values[0, end) partially sorted so that the q-quantile of the first n
    // is in place (end = n, or the place of a larger quantile found before).
    auto quantile = [&](std::size_t n, double q, std::size_t end) {
        const auto i = std::size_t(std::lround(q * double(n - 1)));
        std::nth_element(values, values + i, values + end);
        return values[i];
    };
    auto quantile_place = [](std::size_t n, double q) {
        return std::size_t(std::lround(q * double(n - 1)));
    };
    // Per block: quartiles of width and area, median |skew|.
    double *scatter = block_scatter.data();  // [3 * blocks]: width, area, skew
    std::size_t measured_blocks = 0;
    for (std::size_t b = 0; b < blocks; ++b) {
        const std::uint32_t u0 = std::uint32_t(b) * k_shape_block;
        const std::uint32_t u1 = std::min(width, u0 + k_shape_block);
        block_width[b] = block_area[b] = block_line_width[b] = k_nan;
        std::size_t n = 0;
        for (std::uint32_t u = u0; u < u1; u += k_shape_sampling)
            if (rows[u] == rows[u] && !saturated_column[u] && !low_column[u] &&
                shape[u].width == shape[u].width && shape[u].area == shape[u].area)
                ++n;
        if (n < k_shape_min_peaks)
            continue;
        double median[2];
        for (int which = 0; which < 3; ++which) {
            std::size_t m = 0;
            for (std::uint32_t u = u0; u < u1; u += k_shape_sampling)
                if (rows[u] == rows[u] && !saturated_column[u] && !low_column[u] &&
                    shape[u].width == shape[u].width && shape[u].area == shape[u].area)
                    values[m++] = which == 0   ? shape[u].width
                                  : which == 1 ? shape[u].area
                                               : std::fabs(shape[u].skew);
            sort_samples(values, m);
            if (which < 2) {
                const double upper = values[quantile_place(m, 0.5)];
                const double lower = values[quantile_place(m, 0.25)];
                median[which] = upper;
                (which == 0 ? block_width : block_area)[b] = lower;
                if (which == 0)
                    block_line_width[b] = upper;
                scatter[measured_blocks * 3 + std::size_t(which)] =
                    (upper - lower) / (0.6745 * upper);
            } else {
                scatter[measured_blocks * 3 + 2] =
                    values[quantile_place(m, 0.5)] / (0.6745 * median[0]);
            }
        }
        ++measured_blocks;
    }
    shape_known = measured_blocks > 0;
    if (measured_blocks == 0) {
        // Too few peaks to know the line's shape: reject nothing here.
        return;
    }
    double sigma[3];
    for (int which = 0; which < 3; ++which) {
        for (std::size_t i = 0; i < measured_blocks; ++i)
            values[i] = scatter[i * 3 + which];
        sigma[which] = std::max(which == 2 ? k_min_skew_scatter : k_min_scatter,
                                quantile(measured_blocks, 0.5, measured_blocks));
    }
    // A block with too few peaks takes its nearest measured neighbour's
    // quartiles.
    for (std::size_t b = 0; b < blocks; ++b) {
        if (block_width[b] == block_width[b])
            continue;
        for (std::size_t step = 1; step < blocks; ++step) {
            std::size_t near =
                b >= step && block_width[b - step] == block_width[b - step] ? b - step : b + step;
            if (near < blocks && block_width[near] == block_width[near]) {
                block_width[b] = block_width[near], block_area[b] = block_area[near];
                block_line_width[b] = block_line_width[near];
                break;
            }
        }
    }
    const double width_limit = 1 + (0.6745 + k_width_tolerance) * sigma[0];
    const double area_limit = 1 + (0.6745 + k_area_tolerance) * sigma[1];
    const double skew_limit = k_skew_tolerance * sigma[2];
    shape_limit[0] = width_limit, shape_limit[1] = area_limit, shape_limit[2] = skew_limit;
    // Between block centres c_b = (b + 1/2) k_shape_block - 1/2 the
    // references are linear in u; before the first and after the last centre
    // they are constant.
    const double half_block = 0.5 * double(k_shape_block) - 0.5;
    for (std::size_t segment = 0; segment <= blocks; ++segment) {
        const std::size_t b0 = segment == 0 ? 0 : segment - 1;
        const std::size_t b1 = std::min(blocks - 1, segment);
        const double c0 = double(b0) * k_shape_block + half_block;
        const long u_first = segment == 0 ? 0 : long(std::floor(c0)) + 1;
        const long u_last = segment == blocks
                                ? long(width) - 1
                                : long(std::floor(double(b1) * k_shape_block + half_block));
        const double width_step =
            b1 == b0 ? 0 : (block_width[b1] - block_width[b0]) / double(k_shape_block);
        const double area_step =
            b1 == b0 ? 0 : (block_area[b1] - block_area[b0]) / double(k_shape_block);
        for (long u = u_first; u <= std::min(u_last, long(width) - 1); ++u) {
            const double offset = segment == 0 ? 0 : double(u) - c0;
            const double ref_width = block_width[b0] + offset * width_step;
            const double ref_area = block_area[b0] + offset * area_step;
            // The reading under a saturated peak is judged like any peak.
            double &alternative = alternative_row[std::size_t(u)];
            if (saturated_column[std::size_t(u)] && alternative == alternative) {
                const peak_shape &sh = alternative_shape[std::size_t(u)];
                if (!(sh.width <= width_limit * ref_width && sh.area <= area_limit * ref_area &&
                      std::fabs(sh.skew) <= skew_limit * ref_width))
                    alternative = k_nan;
            }
            // Saturated peaks have the plateau's shape, not the line's:
            // the continuity check alone judges them. The table's line is
            // not the strip's and is not judged by its shape.
            if (!(rows[u] == rows[u]) || saturated_column[std::size_t(u)] ||
                low_column[std::size_t(u)])
                continue;
            const peak_shape &sh = shape[std::size_t(u)];
            const bool well_formed = sh.width <= width_limit * ref_width &&
                                     sh.area <= area_limit * ref_area &&
                                     std::fabs(sh.skew) <= skew_limit * ref_width;
            if (!well_formed)
                rows[u] = k_nan, ++changed_rows;  // also when the shape is NaN
        }
    }
}

// The line is one connected curve across the columns. Where a spurious
// reflection is brighter than the line (over a dark patch of the strip the
// line carries a fraction of its light) the column's peak is the
// reflection's: a run of peaks that continue each other but leave the line
// and come back to it. The peaks are cut into segments where they stop
// continuing each other (a step of more than k_detour_step_px plus half a
// pixel per column of gap, across gaps of up to k_detour_gap columns); a
// segment with longer segments on both sides, each within k_detour_reach
// columns of it, whose peaks lie mostly more than k_detour_tolerance_px from the
// straight line between its neighbours' facing ends, is a detour and is
// rejected (its columns lose their peak: a fiber there is invalid, never
// measured off the line). Lines below the strip (the roller table's) take
// no part.
void flt_extractor::reject_detours(double *rows) {
    constexpr double k_detour_step_px = 2.0;
    constexpr long k_detour_gap = 8, k_detour_reach = 32, k_detour_far_reach = 128;
    const long w = long(width);
    // Segments as [first, last] column ranges of line peaks, in order (at
    // most one per column: the scratch is [width], allocated at create).
    std::uint32_t *first = segment_first.data(), *last = segment_last.data();
    std::uint32_t *count = segment_count.data();
    std::size_t segments = 0;
    double *expected_row = shape_scratch.data();
    detour_columns = 0;
    auto is_peak = [&](long u) {
        return rows[u] == rows[u] && !low_column[std::size_t(u)];
    };
    long previous = -1;
    for (long u = 0; u < w; ++u) {
        if (!is_peak(u))
            continue;
        const long gap = previous < 0 ? 0 : u - previous - 1;
        const bool continues =
            previous >= 0 && gap <= k_detour_gap &&
            std::fabs(rows[u] - rows[previous]) <= k_detour_step_px + 0.5 * double(gap);
        if (!continues)
            first[segments] = std::uint32_t(u), count[segments] = 0, ++segments;
        last[segments - 1] = std::uint32_t(u), ++count[segments - 1];
        previous = u;
    }
    for (std::size_t i = 1; i + 1 < segments; ++i) {
        // Only a segment that takes over from the line and hands back to
        // it within a gap: across a longer stretch without peaks the
        // chord between the neighbours' ends is no estimate of a curved
        // line. Up to k_detour_far_reach columns the course is instead a
        // straight line fitted to both neighbours' nearest peaks, where it
        // fits them (far_course).
        const std::uint32_t n = count[i];
        if (n == 0)
            continue;
        // The neighbours: the nearest longer segment on each side (a
        // shorter one between, a speck, is judged on its own), searched
        // no farther than k_detour_far_reach columns, so that a frame of
        // many short segments (noise, no line) costs O(segments x reach),
        // not O(segments^2).
        std::size_t left = i - 1, right = i + 1;
        while (left > 0 && count[left] <= n &&
               long(first[i]) - long(last[left]) <= k_detour_far_reach)
            --left;
        while (right + 1 < segments && count[right] <= n &&
               long(first[right]) - long(last[i]) <= k_detour_far_reach)
            ++right;
        if (!(count[left] > n && count[right] > n))
            continue;
        const long reach =
            std::max(long(first[i]) - long(last[left]), long(first[right]) - long(last[i]));
        double u0 = double(last[left]), v0 = rows[last[left]];
        double u1 = double(first[right]), v1 = rows[first[right]];
        if (reach > k_detour_reach &&
            !(reach <= k_detour_far_reach &&
              far_course(rows, last[left], first[right], &u0, &v0, &u1, &v1)))
            continue;
        // The course between the neighbours.
        std::size_t off = 0;
        for (long u = first[i]; u <= long(last[i]); ++u)
            if (is_peak(u)) {
                const double expected = v0 + (double(u) - u0) * (v1 - v0) / (u1 - u0);
                off += std::fabs(rows[u] - expected) > k_detour_tolerance_px;
            }
        if (2 * off <= std::size_t(n))
            continue;
        if (detour_columns == 0)
            std::fill(expected_row, expected_row + w, k_nan);
        for (long u = first[i]; u <= long(last[i]); ++u) {
            if (is_peak(u))
                rows[u] = k_nan, ++changed_rows;
            expected_row[u] = v0 + (double(u) - u0) * (v1 - v0) / (u1 - u0);
            ++detour_columns;
        }
        // The next segment is not judged against a rejected one.
        count[i] = 0;
    }
    // A stray: a segment of at most k_stray_peaks peaks (no longer than
    // the gaps a segment bridges) that continues neither neighbour within
    // k_detour_reach columns is a bright speck, not the line: the line is
    // one curve, and a peak nothing around it confirms is not read as the
    // line. Continuing: the facing ends within k_detour_step_px plus
    // k_stray_bend px per column between them, along the line's slope in
    // the block (measure_block_slopes: a line at 35 degrees climbs 0.7 rows
    // per column). On the unseen monochrome plate's photos two single peaks
    // lay 50 and 146 px off the line; on the simulator's field frames with
    // 15 % speckle the check removes 23 peaks, 18 of them more than 1 mm off
    // (docs/sensor.md, "Field frames").
    constexpr auto k_stray_peaks = std::uint32_t(k_detour_gap);
    constexpr double k_stray_bend = 0.1;
    bool slopes_known = false;
    auto continued_by = [&](std::size_t i, std::size_t j) {
        if (count[j] == 0)
            return false;  // a rejected detour
        const long from = j < i ? long(last[j]) : long(first[j]);
        const long to = j < i ? long(first[i]) : long(last[i]);
        const long gap = std::labs(to - from);
        const double along = block_slope[std::size_t(to) / k_shape_block] * double(to - from);
        return gap <= k_detour_reach && std::fabs(rows[to] - rows[from] - along) <=
                                            k_detour_step_px + k_stray_bend * double(gap);
    };
    for (std::size_t i = 0; i < segments; ++i) {
        if (count[i] == 0 || count[i] > k_stray_peaks)
            continue;
        if (!slopes_known)
            measure_block_slopes(rows), slopes_known = true;
        if ((i > 0 && continued_by(i, i - 1)) || (i + 1 < segments && continued_by(i, i + 1)))
            continue;
        for (long u = first[i]; u <= long(last[i]); ++u)
            if (is_peak(u))
                rows[u] = k_nan, ++changed_rows;
    }
}

// The line's course between two pieces of it far apart (a segment between
// them judged across long gaps, reject_detours): a straight line fitted
// to up to k_course_anchors peaks of each piece nearest the gap (at least
// half of them, within 2 k_course_anchors columns of its end), given as
// two points (u0, v0), (u1, v1) on it. False where the pieces do not
// agree on one straight course within k_course_rms_px RMS (a line that
// curves or steps there: no prediction).
bool flt_extractor::far_course(const double *rows, long left_end, long right_end, double *u0,
                               double *v0, double *u1, double *v1) const {
    constexpr long k_course_anchors = 8;
    constexpr double k_course_rms_px = 0.5;
    const long w = long(width);
    double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
    int sides[2] = {0, 0};
    for (int side = 0; side < 2; ++side) {
        const long step = side == 0 ? -1 : 1;
        const long from = side == 0 ? left_end : right_end;
        for (long j = from; j >= 0 && j < w && std::labs(j - from) < 2 * k_course_anchors &&
                            sides[side] < k_course_anchors;
             j += step) {
            if (!(rows[j] == rows[j]) || low_column[std::size_t(j)])
                continue;
            const double x = double(j - left_end), y = rows[j];
            sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y;
            ++sides[side];
        }
    }
    if (sides[0] < k_course_anchors / 2 || sides[1] < k_course_anchors / 2)
        return false;
    const double n = double(sides[0] + sides[1]);
    const double det = n * sxx - sx * sx;
    if (!(det > 0))
        return false;
    const double slope = (n * sxy - sx * sy) / det, a = (sy - slope * sx) / n;
    if (!(syy - a * sy - slope * sxy <= n * k_course_rms_px * k_course_rms_px))
        return false;
    *u0 = double(left_end), *v0 = a;
    *u1 = double(right_end), *v1 = a + slope * double(right_end - left_end);
    return true;
}

// Whether a peak found after reject_misshapen ran has the line's shape in
// column u: the same limits against the same references, the block
// quartiles interpolated linearly between block centres.
bool flt_extractor::well_formed(std::uint32_t u, const peak_shape &sh) const {
    if (!shape_known)
        return false;
    const double half_block = 0.5 * double(k_shape_block) - 0.5;
    const std::size_t blocks = block_width.size();
    const double at = (double(u) - half_block) / double(k_shape_block);  // in block centres
    const std::size_t b0 = at <= 0 ? 0 : std::min(blocks - 1, std::size_t(at));
    const std::size_t b1 = std::min(blocks - 1, b0 + 1);
    const double f = at <= 0 || b1 == b0 ? 0 : std::min(1.0, at - double(b0));
    const double ref_width = block_width[b0] + f * (block_width[b1] - block_width[b0]);
    const double ref_area = block_area[b0] + f * (block_area[b1] - block_area[b0]);
    return sh.width <= shape_limit[0] * ref_width && sh.area <= shape_limit[1] * ref_area &&
           std::fabs(sh.skew) <= shape_limit[2] * ref_width;
}

// Under a rejected detour the line may still show: dimmer than the
// reflection (over a dark patch), but a peak. In each of its columns the
// brightest local maximum within k_under_detour_px of the row the
// neighbours' chord expects is measured as any candidate (column_peak,
// which may go on to the next ones; a saturated peak there is passed
// over, as the reflection's glow), and kept when its centre lies within
// that distance of the chord, nothing brighter lies within the rows its
// centre is measured from, and its shape is the line's (well_formed). Else
// the column stays without a peak. k_under_detour_px is 1 mm of height on
// the reference sensor; at 1 px, 3 of 10 peaks found on field frames with
// 15 % speckle were more than 1 mm off (lib/extraction/README.md).
template <class Pixel>
void flt_extractor::look_under_detours(const unsigned char *frame, std::size_t stride,
                                       const band &b, const peak_params &params, double *rows) {
    constexpr double k_under_detour_px = 0.5;
    const double *expected_row = shape_scratch.data();
    const long band_lo = long(b.first), band_hi = long(b.first + b.rows) - 1;
    auto px = [&](std::uint32_t u, long v) -> std::uint32_t {
        return reinterpret_cast<const Pixel *>(frame + std::size_t(v) * stride)[u];
    };
    for (std::uint32_t u = 0; u < width; ++u) {
        const double expected = expected_row[u];
        if (!(expected == expected) || rows[u] == rows[u])
            continue;
        const long lo = std::max(band_lo, long(std::ceil(expected - k_under_detour_px)));
        const long hi = std::min(band_hi, long(std::floor(expected + k_under_detour_px)));
        std::uint32_t best = 0;
        long best_v = -1;
        for (long v = lo; v <= hi; ++v) {
            const std::uint32_t value = px(u, v);
            if (value <= best || (v > band_lo && px(u, v - 1) > value) ||
                (v < band_hi && px(u, v + 1) > value))
                continue;
            best = value, best_v = v;
        }
        if (best_v < 0 || best < params.min_value)
            continue;
        bool suspect = false, saturated = false;
        peak_shape sh{k_nan, k_nan, k_nan};
        const double v = column_peak<Pixel>(frame, stride, u, b.first, b.rows, best, best_v, params,
                                            false, &suspect, &saturated, &sh);
        // Nothing brighter than the found peak within the rows its centre
        // is measured from (a reflection that close drags it).
        bool clear = v == v;
        const long around = params.gather_reach;
        for (long r = std::max(0L, best_v - around);
             clear && r <= std::min(long(height) - 1, best_v + around); ++r)
            clear = px(u, r) <= best;
        if (clear && std::fabs(v - expected) <= k_under_detour_px && well_formed(u, sh))
            rows[u] = v, shape[u] = sh, saturated_column[u] = 0, ++changed_rows;
    }
}

// A dim stretch of the line between two confident pieces of it: where the
// line crosses a dark patch (a black square of a board, a dark coated or
// oiled patch of strip) it may rise only a few counts above that patch,
// under extract_min_peak, and the peak search finds nothing there. The
// line is one curve: the pieces on both sides say where it runs, so in
// such a gap only the rows within k_bridge_search_px of that course are
// searched, and a maximum there is taken when it stands out of the gap's
// own background noise (k_bridge_min_snr standard deviations, measured on
// the rows beside the line in the gap's columns), not out of a fixed share
// of full scale. Only columns with no peak at all qualify: a peak the
// checks rejected stays rejected. The course is a straight line fitted to
// k_bridge_anchor peaks on each side, within k_bridge_anchor_reach columns
// of the gap; it must fit them within k_bridge_anchor_rms_px (a line that
// curves or steps there is not predicted), and a gap longer than
// k_bridge_max_gap columns is not bridged. A maximum beside something
// bright (its two sides' backgrounds differ by more than the line rises),
// or wider than twice the line, is not taken. The centre is a Gaussian-
// weighted centroid of the light above the background (a ramp between the
// two sides), and must lie within k_bridge_tolerance_px of the course:
// 0.5 px, as under a detour (1 mm of height on the reference sensor; with
// 1 px, simulated field frames with texture under ambient light kept a
// peak 1.27 mm off). Returns the columns filled.
template <class Pixel>
std::size_t flt_extractor::bridge_dim_stretches(const unsigned char *frame, std::size_t stride,
                                                const band &b, const peak_params &params,
                                                double *rows) {
    constexpr long k_bridge_max_gap = 64;
    constexpr int k_bridge_anchor = 8;
    constexpr long k_bridge_anchor_reach = 24;
    constexpr double k_bridge_anchor_rms_px = 0.5;
    constexpr double k_bridge_search_px = 1.5;
    constexpr double k_bridge_tolerance_px = 0.5;
    constexpr double k_bridge_min_snr = 5.0;
    constexpr long k_background_rows = 6;  // rows beside the line per side
    constexpr double k_bridge_side_share = 1.0;
    constexpr int k_bridge_passes = 4;
    const long w = long(width);
    const long band_lo = long(b.first), band_hi = long(b.first + b.rows) - 1;
    auto px = [&](std::uint32_t u, long v) -> double {
        return double(reinterpret_cast<const Pixel *>(frame + std::size_t(v) * stride)[u]);
    };
    auto on_line = [&](long u) {
        return rows[u] == rows[u] && !low_column[std::size_t(u)];
    };
    std::size_t filled = 0;
    long u = 0;
    while (u < w) {
        if (rows[u] == rows[u]) {
            ++u;
            continue;
        }
        const long g0 = u;
        while (u < w && !(rows[u] == rows[u]))
            ++u;
        const long g1 = u - 1;  // the gap: columns g0..g1
        if (g0 == 0 || u >= w || g1 - g0 + 1 > k_bridge_max_gap)
            continue;
        bool any = false;
        for (long j = g0; j <= g1 && !any; ++j)
            any = no_peak_column[std::size_t(j)] != 0;
        if (!any)
            continue;
        // The anchors: the nearest valid peaks on each side (none on the
        // table's line), least squares row = a + c (j - g0).
        double sx = 0, sy = 0, sxx = 0, sxy = 0, syy = 0;
        int sides[2] = {0, 0};
        for (int side = 0; side < 2; ++side) {
            const long step = side == 0 ? -1 : 1;
            const long from = side == 0 ? g0 - 1 : g1 + 1;
            for (long j = from; j >= 0 && j < w && std::labs(j - from) < k_bridge_anchor_reach &&
                                sides[side] < k_bridge_anchor;
                 j += step) {
                if (low_column[std::size_t(j)])
                    break;
                if (!on_line(j))
                    continue;
                const double x = double(j - g0), y = rows[j];
                sx += x, sy += y, sxx += x * x, sxy += x * y, syy += y * y;
                ++sides[side];
            }
        }
        if (sides[0] < k_bridge_anchor / 2 || sides[1] < k_bridge_anchor / 2)
            continue;
        const double n = double(sides[0] + sides[1]);
        const double det = n * sxx - sx * sx;
        if (!(det > 0))
            continue;
        const double slope = (n * sxy - sx * sy) / det, a = (sy - slope * sx) / n;
        // Residual sum of squares of the fit, from the sums.
        const double rss = syy - a * sy - slope * sxy;
        if (!(rss <= n * k_bridge_anchor_rms_px * k_bridge_anchor_rms_px))
            continue;
        double line_width = block_line_width[std::size_t(g0) / k_shape_block];
        if (!(line_width > 0))
            line_width = 3.0;
        // The line's rows: +-0.85 of its width at half maximum (+-2 sigma);
        // its background lies beyond them.
        const long half = std::max(1L, long(std::ceil(0.85 * line_width)));
        // The line's Gaussian sigma (its width at half maximum / 2.355)
        // and the rows within 3 of it.
        const double inv_sigma = k_fwhm_per_sigma / line_width;
        const long reach = std::max(2L, long(std::ceil(3.0 * line_width / k_fwhm_per_sigma)));
        // The background beside the line in the gap's columns: its level
        // per column (the mean of both sides' rows) and its noise over the
        // gap (the mean absolute row-to-row step: 2 sigma / sqrt(pi) for
        // Gaussian noise; texture only raises it, which makes the test
        // stricter).
        const long off = half + 2;
        double step_sum = 0;
        long steps = 0;
        for (long j = g0; j <= g1; ++j) {
            const long e = std::lround(a + slope * double(j - g0));
            for (int side = 0; side < 2; ++side) {
                const long sgn = side == 0 ? -1 : 1;
                for (long k = off; k < off + k_background_rows; ++k) {
                    const long v0 = e + sgn * k, v1 = v0 + sgn;
                    if (std::min(v0, v1) < band_lo || std::max(v0, v1) > band_hi)
                        break;
                    step_sum += std::fabs(px(std::uint32_t(j), v1) - px(std::uint32_t(j), v0));
                    ++steps;
                }
            }
        }
        if (steps < 8)
            continue;
        const double sigma = std::max(0.5, 0.886227 * step_sum / double(steps));
        for (long j = g0; j <= g1; ++j) {
            if (!no_peak_column[std::size_t(j)])
                continue;
            const double expected = a + slope * double(j - g0);
            const long lo = std::max(band_lo + 1, long(std::ceil(expected - k_bridge_search_px)));
            const long hi = std::min(band_hi - 1, long(std::floor(expected + k_bridge_search_px)));
            long best_v = -1;
            double best = -1;
            for (long v = lo; v <= hi; ++v) {
                const double value = px(std::uint32_t(j), v);
                if (value > best && px(std::uint32_t(j), v - 1) <= value &&
                    px(std::uint32_t(j), v + 1) <= value)
                    best = value, best_v = v;
            }
            if (best_v < 0 || best >= double(params.full_scale))
                continue;
            // The background on each side of the course; a line beside
            // something bright (a reflection, a patch's edge) is not
            // measured here: its sides differ.
            double side_level[2] = {0, 0};
            bool inside = true;
            for (int side = 0; side < 2; ++side) {
                const long sgn = side == 0 ? -1 : 1;
                for (long k = off; k < off + k_background_rows; ++k) {
                    const long v = std::lround(expected) + sgn * k;
                    inside = inside && v >= band_lo && v <= band_hi;
                    if (inside)
                        side_level[side] += px(std::uint32_t(j), v);
                }
                side_level[side] /= double(k_background_rows);
            }
            if (!inside)
                continue;
            // Level at the course and its slope across the line, counts per
            // row (the sides' means lie off + (k_background_rows - 1) / 2
            // rows away).
            const double background = 0.5 * (side_level[0] + side_level[1]);
            const double ramp = (side_level[1] - side_level[0]) /
                                (2.0 * double(off) + double(k_background_rows - 1));
            const double contrast = best - background;
            if (!(contrast >= k_bridge_min_snr * sigma) ||
                !(std::fabs(side_level[0] - side_level[1]) <= k_bridge_side_share * contrast))
                continue;
            // As narrow as the line: the rows at or above half the contrast.
            long w_lo = best_v, w_hi = best_v;
            while (w_lo > band_lo &&
                   px(std::uint32_t(j), w_lo - 1) - background >= 0.5 * contrast &&
                   best_v - w_lo <= 2 * half)
                --w_lo;
            while (w_hi < band_hi &&
                   px(std::uint32_t(j), w_hi + 1) - background >= 0.5 * contrast &&
                   w_hi - best_v <= 2 * half)
                ++w_hi;
            if (double(w_hi - w_lo + 1) > 2.0 * line_width + 1.0)
                continue;
            // The centre: the light above the background weighted by a
            // Gaussian of the line's own width, centred again on each
            // estimate (a matched filter: at a symmetric line's centre the
            // weighted offsets cancel, and over a few rows of noise it
            // scatters about 2/3 as much as a plain centroid).
            double centre = double(best_v);
            for (int pass = 0; pass < k_bridge_passes && centre == centre; ++pass) {
                const long c = std::lround(centre);
                double sw = 0, swv = 0;
                for (long v = std::max(band_lo, c - reach); v <= std::min(band_hi, c + reach);
                     ++v) {
                    const double light =
                        px(std::uint32_t(j), v) - background - ramp * (double(v) - expected);
                    const double d = (double(v) - centre) * inv_sigma;
                    const double weight = light * std::exp(-0.5 * d * d);
                    sw += weight, swv += weight * double(v);
                }
                centre = sw > 0 ? swv / sw : k_nan;
            }
            if (centre == centre && std::fabs(centre - expected) <= k_bridge_tolerance_px) {
                rows[j] = centre;
                shape[std::size_t(j)] = peak_shape{k_nan, k_nan, k_nan};
                saturated_column[std::size_t(j)] = 0;
                ++filled;
            }
        }
    }
    return filled;
}

// The line's slope per block of k_shape_block columns, rows per column:
// the median of its peaks' row steps over k_slope_span columns (the
// table's line left out; a glint's few columns do not move a median).
// A line across the image at 35 degrees climbs 0.7 rows per column:
// in the glint check (reject_glint_fringes) its peaks' runs continue each
// other along the slope, and the neighbours' median row is taken after
// carrying each to the column along it; without that the runs break
// wherever noise adds a third of a row to a step, and the median is off
// by the slope times the neighbours' imbalance between the sides (the
// stray check in reject_detours judges its gaps along it too). Not up to
// k_level_slope, where the imbalance costs less (0.1 row per column
// moves the median by about the 0.5 px tolerance only when all of one
// side's neighbours are missing), so a level line is judged exactly as
// it was.
void flt_extractor::measure_block_slopes(const double *rows) {
    constexpr long k_slope_span = 8;
    constexpr double k_level_slope = 0.1;
    const long w = long(width);
    double *steps = slope_steps.data();
    for (std::size_t b = 0; b < block_slope.size(); ++b) {
        const long u0 = long(b * k_shape_block), u1 = std::min(w, u0 + long(k_shape_block));
        std::size_t n = 0;
        for (long u = u0; u < u1 && u + k_slope_span < w; ++u) {
            const long v = u + k_slope_span;
            if (rows[u] == rows[u] && rows[v] == rows[v] && !low_column[std::size_t(u)] &&
                !low_column[std::size_t(v)])
                steps[n++] = (rows[v] - rows[u]) / double(k_slope_span);
        }
        block_slope[b] = 0;
        if (n >= k_shape_min_peaks) {
            std::nth_element(steps, steps + n / 2, steps + n);
            if (std::fabs(steps[n / 2]) > k_level_slope)
                block_slope[b] = steps[n / 2];
        }
    }
}

// A specular glint saturates in its core, which is rejected, but its fringe
// columns are bright, unsaturated and narrow: there the brightest peak is the
// glint, not the line. Likewise, where the brightest peak was rejected (a
// glint, or the line with a reflection too wide to pass), the next candidate
// may be a reflection away from the line. Near such a suspect column, a peak
// more than k_glint_tolerance_px off the median of the valid peaks around it
// is rejected (the line is continuous across columns: the reference strip's
// steepest cross slope moves it < 0.2 px over the window).
//
// A saturated peak is measured (the plateau's middle), so a glint over the
// line is the column's peak. Such a column also has the reading without it
// (alternative_row: the line under the glint, if it shows). A saturated
// peak vouches for its neighbours only within a run of at least a window's
// width of peaks that continue each other (a line, saturated or not; a
// glint off the line is shorter), so a glint cannot vouch for itself. A
// column keeps its peak if it continues the line, else the reading without
// it if that does (the line under a glint), else nothing.
void flt_extractor::reject_glint_fringes(double *rows) {
    constexpr long reach = 10, window = 12;
    constexpr double k_glint_tolerance_px = 0.5;
    constexpr int k_min_neighbours = 4;  // valid peaks in the window besides u
    const long w = long(width);
    long last_suspect = -(1L << 30);
    // tainted[u]: a suspect column within +-reach (two sweeps).
    for (long u = 0; u < w; ++u) {
        if (suspect_column[u])
            last_suspect = u;
        tainted_column[u] = u - last_suspect <= reach;
    }
    last_suspect = 1L << 30;
    for (long u = w - 1; u >= 0; --u) {
        if (suspect_column[u])
            last_suspect = u;
        tainted_column[u] = tainted_column[u] || last_suspect - u <= reach;
    }
    measure_block_slopes(rows);
    auto slope_at = [&](long u) {
        return block_slope[std::size_t(u) / k_shape_block];
    };
    // Runs of peaks that continue each other (within 1 px from column to
    // column, along the slope), saturated or not, their length at every
    // saturated column of the run. A line whose light hovers at full scale
    // (a bright line over white squares) is saturated in most columns but
    // not all; counting only unbroken saturated stretches cut it into
    // pieces shorter than the window, none of which vouched (the unseen
    // monochrome plate's photos lost 1,400 of their 9,593 line columns
    // so). A glint off the line steps away from it: its run stays short.
    constexpr double k_run_step_px = 1.0;
    constexpr std::uint32_t k_min_saturated_run = 2 * window + 1;
    {
        long start = 0;
        for (long u = 0; u <= w; ++u) {
            const bool continues = u < w && u > start && rows[u] == rows[u] &&
                                   rows[u - 1] == rows[u - 1] && !low_column[std::size_t(u)] &&
                                   !low_column[std::size_t(u - 1)] &&
                                   std::fabs(rows[u] - rows[u - 1] - slope_at(u)) <= k_run_step_px;
            if (continues)
                continue;
            for (long j = start; j < u; ++j)
                saturated_run[std::size_t(j)] =
                    saturated_column[std::size_t(j)] ? std::uint32_t(u - start) : 0;
            start = u;
        }
    }
    auto vouches = [&](long j) {
        return !(saturated_column[std::size_t(j)] &&
                 saturated_run[std::size_t(j)] < k_min_saturated_run) &&
               !low_column[std::size_t(j)] && rows[j] == rows[j];
    };
    for (long u = 0; u < w; ++u) {
        if (!tainted_column[u] || !(rows[u] == rows[u]) || low_column[std::size_t(u)])
            continue;
        // The neighbours' readings of the line: unsaturated peaks, and
        // saturated ones within a long run of them (a line saturated all
        // along). A short run of saturated peaks may be a glint, on the
        // line or off it: it does not vouch, the line around it decides.
        double around[2 * window + 1];
        int n = 0;
        const double slope = slope_at(u);
        for (long j = std::max(0L, u - window); j <= std::min(w - 1, u + window); ++j)
            if (vouches(j))
                around[n++] = rows[j] + slope * double(u - j);
        // Too few neighbours to confirm the peak (itself among the n): a
        // glint's fringe column amid rejected ones looks just like that.
        if (n <= k_min_neighbours) {
            fringe_row[u] = 1;
            continue;
        }
        std::nth_element(around, around + n / 2, around + n);
        const double median = around[n / 2];

        // The peak if it continues the line, else the reading under it.
        if (std::fabs(rows[u] - median) <= k_glint_tolerance_px)
            fringe_row[u] = 0;
        else if (saturated_column[std::size_t(u)] &&
                 std::fabs(alternative_row[std::size_t(u)] - median) <= k_glint_tolerance_px)
            fringe_row[u] = 2;
        else
            fringe_row[u] = 1;
    }
    for (long u = 0; u < w; ++u) {
        if (!tainted_column[u] || !(rows[u] == rows[u]))
            continue;
        if (fringe_row[u] == 2) {
            rows[u] = alternative_row[std::size_t(u)], ++changed_rows;
            saturated_column[std::size_t(u)] = 0;
        } else if (fringe_row[u] == 1) {
            rows[u] = k_nan, ++changed_rows;
        }
        fringe_row[u] = 0;
    }
}

// Resampling onto the fiber grid: a least-squares line z = a + b (x - x_k)
// through the valid columns within +-support of fiber k, evaluated at x_k.
// Unbiased where z is locally linear across the width, and it averages the
// ~2 support / column-spacing columns' peak noise instead of keeping one.
// Strict validity: the fiber needs a column on each side, and a run of
// invalid columns anywhere within its support makes it invalid (nothing is
// bridged across a missing peak).
void flt_extractor::resample(unsigned laser) {
    double *out = fiber_z[laser].data();
    std::uint8_t *off = fiber_off[laser].data();
    std::fill(out, out + fibers, k_nan);
    const strip_view &sv = strip[laser];
    if (!sv.present) {
        std::fill(off, off + fibers, std::uint8_t(1));
        return;
    }
    std::fill(fit_flags.begin(), fit_flags.end(), std::uint8_t(0));
    const double *xs = column_x[laser].data(), *zs = column_z[laser].data();
    const double inv_pitch = 1.0 / pitch, last = double(fibers - 1);
    const double half = support;
    enum : std::uint8_t { left = 1, right = 2, poisoned = 4 };
    // The fibers with lo <= x_k <= hi. Clamped to [-1, fibers] while still a
    // double: a column mapped far off the grid (an extreme homography, or
    // the plane's horizon inside the frame) gives indices far beyond any
    // integer, and converting those would be undefined.
    auto fiber_range = [&](double lo, double hi, long *k0, long *k1) {
        const double a = std::ceil((lo - first_x) * inv_pitch);
        const double b = std::floor((hi - first_x) * inv_pitch);
        *k0 = a > 0.0 ? long(std::min(a, last + 1.0)) : 0;  // NaN: 0
        *k1 = b < last ? long(std::max(b, -1.0)) : long(last);
        if (!(b == b))
            *k1 = -1;  // NaN: no fiber
    };
    // Across a gap in the line (columns without a peak) the fibers the gap
    // spans are poisoned: no fiber is fitted across missing columns. And
    // whether x runs one way along the strip's columns, as it does through
    // any sane lens and homography.
    double previous_x = k_nan;
    bool gap = false, rising = true, falling = true;
    // Only the strip's columns: beyond its ends there is no strip to miss.
    for (long u = sv.u_first; u <= sv.u_last; ++u) {
        const double x = xs[u];
        if (!(x == x)) {
            gap = true;
            continue;
        }
        if (previous_x == previous_x) {
            rising = rising && x >= previous_x;
            falling = falling && x <= previous_x;
        }
        if (gap && previous_x == previous_x) {
            long k0, k1;
            fiber_range(std::min(previous_x, x) - half, std::max(previous_x, x) + half, &k0, &k1);
            for (long k = k0; k <= k1; ++k)
                fit_flags[std::size_t(k)] |= poisoned;
        }
        gap = false;
        previous_x = x;
    }
    // Each fiber's window sums over the columns within +-half of it, added
    // in column order. Column u serves fiber k when k >= ceil(lo) and
    // k <= floor(hi), lo and hi its window's ends in fibers; for a whole k
    // that is k >= lo and k <= hi, compared as doubles.
    auto window_lo = [&](double x) {
        return (x - half - first_x) * inv_pitch;
    };
    auto window_hi = [&](double x) {
        return (x + half - first_x) * inv_pitch;
    };
    auto add = [&](double *sums, std::uint8_t *flags, double x, double z, std::size_t k) {
        const double dx = x - (first_x + double(k) * pitch);
        sums[0] += 1, sums[1] += dx, sums[2] += dx * dx, sums[3] += z, sums[4] += z * dx;
        *flags |= dx <= 0 ? left : 0;
        *flags |= dx >= 0 ? right : 0;
    };
    if (rising || falling) {
        // Fiber by fiber, the sums in registers: a fiber's columns are one
        // run, found by two pointers. Column by column (below) each column's
        // update waited for the previous column's store to the same fiber,
        // and that chain was most of this function's time.
        long from = sv.u_first;
        for (std::size_t i = 0; i < fibers; ++i) {
            const std::size_t k = rising ? i : fibers - 1 - i;
            const double kd = double(k);
            // Columns whose windows end before fiber k (rising; falling:
            // begin after it), and columns without a peak, serve no later
            // fiber.
            while (from <= sv.u_last &&
                   !(rising ? window_hi(xs[from]) >= kd : window_lo(xs[from]) <= kd))
                ++from;
            // (add's sums, spelled out as scalars: an array here stayed on
            // the stack, and its loads waited for its stores.)
            const double x_k = first_x + kd * pitch;
            double n = 0, sum_dx = 0, sum_dx2 = 0, sum_z = 0, sum_z_dx = 0;
            std::uint8_t flags = fit_flags[k];
            for (long u = from; u <= sv.u_last; ++u) {
                const double x = xs[u];
                if (!(x == x))
                    continue;
                if (!(rising ? window_lo(x) <= kd : window_hi(x) >= kd))
                    break;  // this column's window, and every later one, misses fiber k
                const double z = zs[u], dx = x - x_k;
                n += 1, sum_dx += dx, sum_dx2 += dx * dx, sum_z += z, sum_z_dx += z * dx;
                flags |= dx <= 0 ? left : 0;
                flags |= dx >= 0 ? right : 0;
            }
            double *sums = &fit_sums[5 * k];
            sums[0] = n, sums[1] = sum_dx, sums[2] = sum_dx2, sums[3] = sum_z, sums[4] = sum_z_dx;
            fit_flags[k] = flags;
        }
    } else {
        std::fill(fit_sums.begin(), fit_sums.end(), 0.0);
        for (long u = sv.u_first; u <= sv.u_last; ++u) {
            const double x = xs[u];
            if (!(x == x))
                continue;
            long k0, k1;
            fiber_range(x - half, x + half, &k0, &k1);
            for (long k = k0; k <= k1; ++k)
                add(&fit_sums[5 * std::size_t(k)], &fit_flags[std::size_t(k)], x, zs[u],
                    std::size_t(k));
        }
    }
    for (std::size_t k = 0; k < fibers; ++k) {
        const double x_k = first_x + double(k) * pitch;
        // The edge rule: a fiber belongs to the strip when its x lies
        // between the edges; one whose window reaches past a seen edge is
        // fitted from the strip's side alone.
        off[k] = (!sv.open[0] && x_k < sv.edge[0]) || (!sv.open[1] && x_k > sv.edge[1]);
        if (off[k])
            continue;
        std::uint8_t required = left | right;
        if (!sv.open[0] && x_k - half < sv.edge[0])
            required &= std::uint8_t(~left);
        if (!sv.open[1] && x_k + half > sv.edge[1])
            required &= std::uint8_t(~right);
        const std::uint8_t got = fit_flags[k];
        if ((got & poisoned) || (got & required) != required || !(got & (left | right)))
            continue;
        const double *sums = &fit_sums[5 * k];
        const double det = sums[0] * sums[2] - sums[1] * sums[1];
        if (sums[0] == 1) {
            if (got == (left | right))
                out[k] = sums[3];  // a column exactly on the fiber
        } else if (det > 1e-12 * sums[0] * sums[2]) {
            out[k] = (sums[3] * sums[2] - sums[1] * sums[4]) / det;
        }
    }
}

namespace {

flt_status check_handle(const char *fn, const flt_extractor *ex) {
    if (ex == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'extractor' is NULL", fn);
    if (ex->magic != k_extractor_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'extractor' is not a live flt_extractor handle", fn);
    return FLT_OK;
}

// The strip one laser saw in the last frame (laser 0 or 1), or the row's
// (laser 2): its edges (NaN where open or absent) and FLT_STRIP_* flags.
void strip_of(const flt_extractor &ex, unsigned laser, double *left, double *right,
              unsigned *strip_flags) {
    bool present;
    bool open[2], glint[2];
    double edge[2];
    if (laser < FLT_CALIB_LASERS) {
        const strip_view &sv = ex.strip[laser];
        present = sv.present;
        for (int side = 0; side < 2; ++side)
            open[side] = sv.open[side], edge[side] = sv.edge[side], glint[side] = sv.glint[side];
    } else {
        // The row's material lies between the two lasers' readings: the
        // mean of their edges, seen only where both see that edge (after
        // cross_edges: the clean one where one had a glint); a glint only
        // where both had one.
        const strip_view &a = ex.strip[0], &b = ex.strip[1];
        present = a.present && b.present;
        for (int side = 0; side < 2; ++side) {
            open[side] = a.open[side] || b.open[side];
            edge[side] = 0.5 * (a.edge[side] + b.edge[side]);
            glint[side] = a.glint[side] && b.glint[side];
        }
    }
    unsigned flags = 0;
    if (!present) {
        flags = FLT_STRIP_NONE | FLT_STRIP_LEFT_OPEN | FLT_STRIP_RIGHT_OPEN;
    } else {
        flags |= open[0] ? unsigned(FLT_STRIP_LEFT_OPEN) : 0u;
        flags |= open[1] ? unsigned(FLT_STRIP_RIGHT_OPEN) : 0u;
        flags |= glint[0] && !open[0] ? unsigned(FLT_STRIP_LEFT_GLINT) : 0u;
        flags |= glint[1] && !open[1] ? unsigned(FLT_STRIP_RIGHT_GLINT) : 0u;
    }
    *left = present && !open[0] ? edge[0] : k_nan;
    *right = present && !open[1] ? edge[1] : k_nan;
    *strip_flags = flags;
}

// The peaks on the strip in the last frame and the saturated ones, of one
// laser (0 or 1) or of both (2).
void saturation_of(const flt_extractor &ex, unsigned laser, std::size_t *peaks,
                   std::size_t *saturated) {
    *peaks = 0;
    *saturated = 0;
    for (unsigned l = 0; l < FLT_CALIB_LASERS; ++l)
        if (laser == l || laser == FLT_CALIB_LASERS) {
            *peaks += ex.peak_count[l];
            *saturated += ex.saturated_count[l];
        }
}

}  // namespace

extractor_frame_view flt::extractor_frame_of(const flt_extractor *extractor) {
    extractor_frame_view v;
    v.fiber_flags = extractor->row_flags.data();
    strip_of(*extractor, FLT_CALIB_LASERS, &v.left_mm, &v.right_mm, &v.strip_flags);
    saturation_of(*extractor, FLT_CALIB_LASERS, &v.peaks, &v.saturated);
    return v;
}

extern "C" {

FLT_API flt_status FLT_CALL flt_extractor_create(const flt_calib *calib, const flt_options *options,
                                                 flt_extractor **out) {
    const char *fn = "flt_extractor_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, calib);
        int finished = 0;
        if (flt_calib_is_finished(calib, &finished) != FLT_OK)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'calib' is not a live flt_calib handle", fn);
        if (!finished)
            return fail(FLT_ERR_STATE, "%s: argument 'calib' is not finished", fn);
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_EXTRACT_SG_WINDOW}))
            return st;
        auto ex = std::make_unique<flt_extractor>();
        ex->calib = copy_calib(calib);
        check(flt_calib_get_frame_size(ex->calib, &ex->width, &ex->height));
        for (unsigned laser = 0; laser < 2; ++laser)
            check(flt_calib_get_laser_offset(ex->calib, laser, &ex->offset_mm[laser]));
        ex->laser_spacing = std::fabs(ex->offset_mm[1] - ex->offset_mm[0]);
        ex->ahead = ex->offset_mm[0] < ex->offset_mm[1] ? 0 : 1;
        check(flt_calib_get_fiber_grid(ex->calib, &ex->first_x, &ex->pitch, &ex->fibers));

        const int window = int(option_value(options, FLT_OPT_EXTRACT_SG_WINDOW));
        const int order = int(option_value(options, FLT_OPT_EXTRACT_SG_ORDER));
        if (window % 2 == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: option 'extract_sg_window' = %d must be odd",
                        fn, window);
        if (window < order + 2)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'extract_sg_window' = %d must be at least "
                        "'extract_sg_order' + 2 = %d",
                        fn, window, order + 2);
        ex->sg_half = window / 2;
        if (std::max(3 * ex->sg_half / 2, ex->sg_half + 3) > k_max_gather_reach)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'extract_sg_window' = %d is too large for the peak "
                        "kernel (at most %ld)",
                        fn, window, 2 * (2 * k_max_gather_reach / 3) + 1);
        ex->sg_derivative = sg_derivative_taps(ex->sg_half, order);
        ex->thin_taps.assign(std::size_t(ex->sg_half), {});
        for (int h = 2; h < ex->sg_half; ++h)
            if (2 * h + 1 >= order + 2)
                ex->thin_taps[std::size_t(h)] = sg_derivative_taps(h, order);
        ex->min_peak = option_value(options, FLT_OPT_EXTRACT_MIN_PEAK);
        ex->max_width = option_value(options, FLT_OPT_EXTRACT_MAX_WIDTH);
        ex->strip_min_z = option_value(options, FLT_OPT_EXTRACT_STRIP_MIN_Z);
        ex->edge_gap = option_value(options, FLT_OPT_EXTRACT_EDGE_GAP);
        ex->min_strip_width = option_value(options, FLT_OPT_EXTRACT_MIN_STRIP_WIDTH);

        const flt_option first_key[2] = {FLT_OPT_EXTRACT_LASER0_FIRST_ROW,
                                         FLT_OPT_EXTRACT_LASER1_FIRST_ROW};
        const flt_option rows_key[2] = {FLT_OPT_EXTRACT_LASER0_ROWS, FLT_OPT_EXTRACT_LASER1_ROWS};
        for (unsigned laser = 0; laser < 2; ++laser) {
            band &b = ex->bands[laser];
            b.first = std::uint32_t(option_value(options, first_key[laser]));
            b.rows = std::uint32_t(option_value(options, rows_key[laser]));
            b.automatic = b.rows == 0;
            if (b.automatic)
                continue;
            if (std::uint64_t(b.first) + b.rows > ex->height)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: option 'extract_laser%u_first_row' = %u + "
                            "'extract_laser%u_rows' = %u exceeds the frame height %u",
                            fn, laser, b.first, laser, b.rows, ex->height);
            if (b.rows < std::uint32_t(window))
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: option 'extract_laser%u_rows' = %u is shorter than the "
                            "Savitzky-Golay window %d",
                            fn, laser, b.rows, window);
        }
        if (ex->bands[0].automatic != ex->bands[1].automatic)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: options 'extract_laser0_rows' = %u and "
                        "'extract_laser1_rows' = %u: set both bands or neither",
                        fn, ex->bands[0].rows, ex->bands[1].rows);

        const std::size_t w = ex->width;
        for (unsigned laser = 0; laser < 2; ++laser) {
            ex->poly[laser].assign(w * 2 * k_map_terms, k_nan);
            ex->peak_row[laser].assign(w, k_nan);
            ex->column_x[laser].assign(w, k_nan);
            ex->column_z[laser].assign(w, k_nan);
            ex->fiber_z[laser].assign(ex->fibers, k_nan);
            ex->fiber_off[laser].assign(ex->fibers, 0);
        }
        ex->row_flags.assign(ex->fibers, 0);
        ex->saturated_column.assign(w, 0);
        ex->alternative_row.assign(w, k_nan);
        ex->alternative_shape.assign(w, peak_shape{k_nan, k_nan, k_nan});
        ex->saturated_run.assign(w, 0);
        ex->low_column.assign(w, 0);

        ex->edge_light.assign(std::size_t(k_edge_reference_far - k_edge_reference_near + 1), 0);
        ex->suspect_column.assign(w, 0);
        ex->no_peak_column.assign(w, 0);
        ex->tainted_column.assign(w, 0);
        ex->segment_first.assign(w, 0);
        ex->segment_last.assign(w, 0);
        ex->segment_count.assign(w, 0);
        ex->fringe_row.assign(w, 0);
        ex->shape.assign(w, peak_shape{k_nan, k_nan, k_nan});
        // (at least a block's samples: sort_samples fills all 32 slots)
        ex->shape_scratch.assign(std::max<std::size_t>(w, k_shape_samples), 0);
        ex->texture_steps.assign(
            std::size_t(k_shape_block / k_texture_sampling) * 2 * std::size_t(k_texture_rows), 0);
        ex->texture_heights.assign(std::size_t(k_shape_block / k_texture_sampling), 0);
        const std::size_t blocks = (w + k_shape_block - 1) / k_shape_block;
        ex->block_width.assign(blocks, k_nan);
        ex->block_line_width.assign(blocks, k_nan);
        ex->block_slope.assign(blocks, 0);
        ex->slope_steps.assign(w, 0.0);
        ex->block_area.assign(blocks, k_nan);
        ex->block_scatter.assign(3 * blocks, k_nan);
        ex->fit_sums.assign(5 * ex->fibers, 0);
        ex->fit_flags.assign(ex->fibers, 0);
        ex->best_value.assign(w, 0);
        ex->best_row.assign(w, 0);
        ex->row_sum.assign(ex->height, 0);
        ex->map_scratch.assign(2 * w * k_map_nodes, 0);
        ex->build_wide_kernels();
        if (!ex->bands[0].automatic)
            ex->build_maps();
        *out = ex.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_extractor_destroy(flt_extractor *extractor) {
    guard_void([&] {
        if (extractor && extractor->magic == k_extractor_magic) {
            extractor->magic = 0;
            delete extractor;
        }
    });
}

FLT_API flt_status FLT_CALL flt_extractor_fibers(const flt_extractor *extractor, size_t *out) {
    const char *fn = "flt_extractor_fibers";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = extractor->fibers;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_band(const flt_extractor *extractor, unsigned laser,
                                               uint32_t *first_row_out, uint32_t *rows_out) {
    const char *fn = "flt_extractor_band";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        if (laser >= FLT_CALIB_LASERS)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'laser' = %u is not 0 or 1", fn,
                        laser);
        FLT_CHECK_NOT_NULL(fn, first_row_out);
        FLT_CHECK_NOT_NULL(fn, rows_out);
        if (!extractor->maps_ready)
            return fail(FLT_ERR_STATE,
                        "%s: the band is automatic and no frame has been processed yet", fn);
        *first_row_out = extractor->bands[laser].first;
        *rows_out = extractor->bands[laser].rows;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_process(flt_extractor *extractor, const void *frame,
                                                  flt_pixel_format format, uint32_t width,
                                                  uint32_t height, size_t stride_bytes,
                                                  double encoder_mm, size_t fibers, double *s_out,
                                                  double *height_out, double *slope_out,
                                                  uint8_t *valid_out) {
    const char *fn = "flt_extractor_process";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        flt_extractor &ex = *extractor;
        FLT_CHECK_NOT_NULL(fn, frame);
        FLT_CHECK_NOT_NULL(fn, height_out);
        FLT_CHECK_NOT_NULL(fn, slope_out);
        const int raw_format = enum_arg(format);
        if (raw_format != FLT_PIXEL_MONO8 && raw_format != FLT_PIXEL_MONO10 &&
            raw_format != FLT_PIXEL_MONO12 && raw_format != FLT_PIXEL_MONO16)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'format' = %d is not a flt_pixel_format (8, 10, 12 "
                        "or 16)",
                        fn, raw_format);
        if (width != ex.width || height != ex.height)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'width' x 'height' = %u x %u but the calibration's "
                        "frames are %u x %u px",
                        fn, width, height, ex.width, ex.height);
        const int bytes = format == FLT_PIXEL_MONO8 ? 1 : 2;
        if (stride_bytes < std::size_t(width) * bytes)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'stride_bytes' = %zu is less than width %u x %d "
                        "bytes per pixel",
                        fn, stride_bytes, width, bytes);
        // The caller vouches for height rows of stride_bytes; a product that
        // overflows the address space cannot describe any buffer.
        if (height > 0 && stride_bytes > std::numeric_limits<std::size_t>::max() / height)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'stride_bytes' = %zu times height %u overflows the "
                        "address space",
                        fn, stride_bytes, height);
        if (bytes == 2 &&
            (stride_bytes % 2 != 0 || reinterpret_cast<std::uintptr_t>(frame) % 2 != 0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: 16-bit frames need an even 'stride_bytes' (= %zu) and a "
                        "2-byte aligned 'frame'",
                        fn, stride_bytes);
        if (!std::isfinite(encoder_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'encoder_mm' = %g is not finite",
                        fn, encoder_mm);
        if (fibers != ex.fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' = %zu but the calibration has %zu", fn, fibers,
                        ex.fibers);
        const auto *pixels = static_cast<const unsigned char *>(frame);
        const std::uint32_t full_scale = (1u << unsigned(format)) - 1u;
        if (!ex.maps_ready)
            ex.detect_bands(pixels, stride_bytes, bytes, full_scale);
        if (bytes == 1)
            ex.extract<std::uint8_t>(pixels, stride_bytes, full_scale);
        else
            ex.extract<std::uint16_t>(pixels, stride_bytes, full_scale);
        const unsigned ahead = ex.ahead, behind = 1 - ahead;
        const double inv_spacing = 1.0 / ex.laser_spacing;
        const double *za = ex.fiber_z[ahead].data(), *zb = ex.fiber_z[behind].data();
        const std::uint8_t *off_a = ex.fiber_off[ahead].data(),
                           *off_b = ex.fiber_off[behind].data();
        for (std::size_t k = 0; k < fibers; ++k) {
            const bool valid = za[k] == za[k] && zb[k] == zb[k];
            height_out[k] = valid ? 0.5 * (za[k] + zb[k]) : k_nan;
            slope_out[k] = valid ? (za[k] - zb[k]) * inv_spacing : k_nan;
            if (valid_out)
                valid_out[k] = valid ? 1 : 0;
            ex.row_flags[k] = valid                  ? 0
                              : off_a[k] || off_b[k] ? std::uint8_t(FLT_FLAG_OFF_STRIP)
                                                     : std::uint8_t(FLT_FLAG_INVALID_INPUT);
        }
        if (s_out)
            *s_out = encoder_mm - 0.5 * (ex.offset_mm[0] + ex.offset_mm[1]);
        ex.has_frame = true;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_peaks(const flt_extractor *extractor, size_t width,
                                                double *rows_out) {
    const char *fn = "flt_extractor_peaks";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        FLT_CHECK_NOT_NULL(fn, rows_out);
        if (width != extractor->width)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'width' = %zu but the frames are %u px wide", fn, width,
                        extractor->width);
        if (!extractor->has_frame)
            return fail(FLT_ERR_STATE, "%s: no frame has been processed yet", fn);
        for (unsigned laser = 0; laser < 2; ++laser)
            std::memcpy(rows_out + laser * width, extractor->peak_row[laser].data(),
                        width * sizeof(double));
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_fiber_flags(const flt_extractor *extractor, size_t fibers,
                                                      uint8_t *flags_out) {
    const char *fn = "flt_extractor_fiber_flags";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        FLT_CHECK_NOT_NULL(fn, flags_out);
        if (fibers != extractor->fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' = %zu but the calibration has %zu", fn, fibers,
                        extractor->fibers);
        if (!extractor->has_frame)
            return fail(FLT_ERR_STATE, "%s: no frame has been processed yet", fn);
        std::memcpy(flags_out, extractor->row_flags.data(), fibers);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_strip(const flt_extractor *extractor, unsigned laser,
                                                double *left_mm_out, double *right_mm_out,
                                                double *width_mm_out, double *centre_mm_out,
                                                unsigned *strip_flags_out) {
    const char *fn = "flt_extractor_strip";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        if (laser > FLT_CALIB_LASERS)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'laser' = %u is not 0, 1 or 2 (the row)", fn, laser);
        if (!extractor->has_frame)
            return fail(FLT_ERR_STATE, "%s: no frame has been processed yet", fn);
        double left = 0.0, right = 0.0;
        unsigned flags = 0;
        strip_of(*extractor, laser, &left, &right, &flags);
        const bool both = left == left && right == right;
        if (left_mm_out)
            *left_mm_out = left;
        if (right_mm_out)
            *right_mm_out = right;
        if (width_mm_out)
            *width_mm_out = both ? right - left : k_nan;
        if (centre_mm_out)
            *centre_mm_out = both ? 0.5 * (left + right) : k_nan;
        if (strip_flags_out)
            *strip_flags_out = flags;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_saturation(const flt_extractor *extractor, unsigned laser,
                                                     size_t *peaks_out, size_t *saturated_out,
                                                     double *fraction_out) {
    const char *fn = "flt_extractor_saturation";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        if (laser > FLT_CALIB_LASERS)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'laser' = %u is not 0, 1 or 2 (both)", fn, laser);
        if (!extractor->has_frame)
            return fail(FLT_ERR_STATE, "%s: no frame has been processed yet", fn);
        std::size_t peaks = 0, saturated = 0;
        saturation_of(*extractor, laser, &peaks, &saturated);
        if (peaks_out)
            *peaks_out = peaks;
        if (saturated_out)
            *saturated_out = saturated;
        if (fraction_out)
            *fraction_out = peaks ? double(saturated) / double(peaks) : 0.0;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_extractor_laser_profiles(const flt_extractor *extractor,
                                                         size_t fibers, double *z_out) {
    const char *fn = "flt_extractor_laser_profiles";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, extractor))
            return st;
        FLT_CHECK_NOT_NULL(fn, z_out);
        if (fibers != extractor->fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'fibers' = %zu but the calibration has %zu", fn, fibers,
                        extractor->fibers);
        if (!extractor->has_frame)
            return fail(FLT_ERR_STATE, "%s: no frame has been processed yet", fn);
        for (unsigned laser = 0; laser < 2; ++laser)
            std::memcpy(z_out + laser * fibers, extractor->fiber_z[laser].data(),
                        fibers * sizeof(double));
        return FLT_OK;
    });
}

}  // extern "C"
