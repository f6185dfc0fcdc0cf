// SPDX-License-Identifier: Apache-2.0
// The simulated sensor (flatline/sim.h): sheet model, motion and noise,
// profile rows and rendered camera frames, with ground truth.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "calibration/calib_internal.hpp"
#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/recon.h"
#include "flatline/sim.h"
#include "core/crt_math.hpp"
#include "simulation/sim_random.hpp"

using namespace flt;

namespace {

constexpr std::uint32_t k_sim_magic = 0x464c5453u;  // "FLTS"
constexpr std::size_t k_max_defects = 64;
constexpr double k_pi = 3.14159265358979323846;
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
// sim_dark_patches: the cells of the strip's reflectance, mm across and along.
constexpr double k_patch_across_mm = 60.0, k_patch_along_mm = 150.0;
// sim_texture: the cells of the strip's fine texture, mm across and along
// (a few columns and rows of the reference geometry).
constexpr double k_grain_mm = 2.0;

// Random streams of one frame (see sim_random.hpp).
enum stream : std::uint64_t {
    stream_motion = 1,
    stream_row_noise = 2,
    stream_peak_noise = 3,
    stream_pixels = 4,
    stream_reflections = 5,
    stream_wander = 6,  // seeded with the knot index, not the frame
    stream_edge_glints = 7,
    stream_patches = 8,  // seeded with the patch's cell, not the frame
    stream_texture = 9   // seeded with the texture's cell, not the frame
};

struct defect {
    flt_sim_defect kind;
    double amplitude_mm, period_mm;
};

struct sim_params {
    std::uint64_t seed;
    double frame_spacing, start, strip_width;
    double heave_sigma, tilt_sigma;
    double ecc_amplitude, ecc_period;
    double shear_amplitude, shear_decay, shear_period, shear_interval;
    double peak_sigma_px;
    int bit_depth;
    double line_sigma_px, line_peak, background, speckle, full_well, reflections;
    // The line in the field.
    flt_sim_surround surround;
    double strip_offset, wander_amplitude, wander_period, wander_sigma, wander_length;
    double coil_length, coil_gap, second_width;
    double table_depth, roller_pitch, roller_gap, table_brightness;
    double edge_glints, blooming;
    // What real photos show besides.
    double depth_of_field, dark_patches, gamma, ambient, texture;
};

sim_params read_params(const flt_options *o) {
    sim_params p;
    p.seed = std::uint64_t(option_value(o, FLT_OPT_SIM_SEED));
    p.frame_spacing = option_value(o, FLT_OPT_SIM_FRAME_SPACING);
    p.start = option_value(o, FLT_OPT_SIM_START);
    p.strip_width = option_value(o, FLT_OPT_SIM_STRIP_WIDTH);
    p.heave_sigma = option_value(o, FLT_OPT_SIM_HEAVE_SIGMA);
    p.tilt_sigma = option_value(o, FLT_OPT_SIM_TILT_SIGMA);
    p.ecc_amplitude = option_value(o, FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE);
    p.ecc_period = option_value(o, FLT_OPT_SIM_ECCENTRICITY_PERIOD);
    p.shear_amplitude = option_value(o, FLT_OPT_SIM_SHEAR_AMPLITUDE);
    p.shear_decay = option_value(o, FLT_OPT_SIM_SHEAR_DECAY);
    p.shear_period = option_value(o, FLT_OPT_SIM_SHEAR_PERIOD);
    p.shear_interval = option_value(o, FLT_OPT_SIM_SHEAR_INTERVAL);
    p.peak_sigma_px = option_value(o, FLT_OPT_SIM_PEAK_SIGMA);
    p.bit_depth = int(option_value(o, FLT_OPT_SIM_BIT_DEPTH));
    p.line_sigma_px = option_value(o, FLT_OPT_SIM_LINE_SIGMA);
    p.line_peak = option_value(o, FLT_OPT_SIM_LINE_PEAK);
    p.background = option_value(o, FLT_OPT_SIM_BACKGROUND);
    p.speckle = option_value(o, FLT_OPT_SIM_SPECKLE);
    p.full_well = option_value(o, FLT_OPT_SIM_FULL_WELL);
    p.reflections = option_value(o, FLT_OPT_SIM_REFLECTIONS);
    p.surround = flt_sim_surround(int(option_value(o, FLT_OPT_SIM_SURROUND)));
    p.strip_offset = option_value(o, FLT_OPT_SIM_STRIP_OFFSET);
    p.wander_amplitude = option_value(o, FLT_OPT_SIM_WANDER_AMPLITUDE);
    p.wander_period = option_value(o, FLT_OPT_SIM_WANDER_PERIOD);
    p.wander_sigma = option_value(o, FLT_OPT_SIM_WANDER_SIGMA);
    p.wander_length = option_value(o, FLT_OPT_SIM_WANDER_LENGTH);
    p.coil_length = option_value(o, FLT_OPT_SIM_COIL_LENGTH);
    p.coil_gap = option_value(o, FLT_OPT_SIM_COIL_GAP);
    p.second_width = option_value(o, FLT_OPT_SIM_SECOND_WIDTH);
    p.table_depth = option_value(o, FLT_OPT_SIM_TABLE_DEPTH);
    p.roller_pitch = option_value(o, FLT_OPT_SIM_ROLLER_PITCH);
    p.roller_gap = option_value(o, FLT_OPT_SIM_ROLLER_GAP);
    p.table_brightness = option_value(o, FLT_OPT_SIM_TABLE_BRIGHTNESS);
    p.edge_glints = option_value(o, FLT_OPT_SIM_EDGE_GLINTS);
    p.blooming = option_value(o, FLT_OPT_SIM_BLOOMING);
    p.depth_of_field = option_value(o, FLT_OPT_SIM_DEPTH_OF_FIELD);
    p.dark_patches = option_value(o, FLT_OPT_SIM_DARK_PATCHES);
    p.gamma = option_value(o, FLT_OPT_SIM_GAMMA);
    p.ambient = option_value(o, FLT_OPT_SIM_AMBIENT);
    p.texture = option_value(o, FLT_OPT_SIM_TEXTURE);
    return p;
}

void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

// The random walk of the strip's lateral wander: knots every
// sim_wander_length / 16 of encoder travel from sim_start, a discrete
// Ornstein-Uhlenbeck process w_{n+1} = a w_n + sigma sqrt(1 - a^2) xi_{n+1}
// (a = exp(-1/16), stationary standard deviation sigma, w_0 = sigma xi_0),
// each xi_n drawn from (sim_seed, n). The cursor keeps the last four knots,
// so frames in order cost one step per knot; a query behind it restarts
// from knot 0 (flt_sim_strip_edges may be asked anything).
constexpr int k_walk_knots_per_length = 16;

struct walk_cursor {
    long long last = -1;         // index of the newest knot in w
    double w[4] = {0, 0, 0, 0};  // w[i] = knot last - 3 + i
};

// Length of [a, b] (a <= b) lying in the roller table's gaps: [k pitch,
// k pitch + gap) for every integer k; G is its cumulative function.
double table_gap_length(double a, double b, double pitch, double gap) {
    auto cumulative = [&](double x) {
        const double k = std::floor(x / pitch);
        return k * gap + std::min(x - k * pitch, gap);
    };
    return cumulative(b) - cumulative(a);
}

// The share of [lo, hi] (column interval, mm) inside [left, right].
double overlap_share(double lo, double hi, double left, double right) {
    if (!(hi > lo))
        return (lo >= left && lo <= right) ? 1.0 : 0.0;
    const double a = std::max(lo, left), b = std::min(hi, right);
    return b > a ? (b - a) / (hi - lo) : 0.0;
}

}  // namespace

struct flt_sim {
    std::uint32_t magic = k_sim_magic;
    sim_params params;
    flt_calib *calib = nullptr;
    std::uint32_t width = 0, height = 0;  // frame, px
    double offset_mm[2] = {0, 0};
    double ahead_laser = 0;        // the laser reading the larger s
    double laser_spacing = 0;      // |offset_1 - offset_0|, mm
    std::vector<double> fiber_x;   // mm
    std::vector<double> dz_dv[2];  // per fiber, mm per px of peak error
    std::vector<defect> defects;
    // User height map.
    std::size_t map_rows = 0, map_cols = 0;
    double map_s0 = 0, map_ds = 1, map_x0 = 0, map_dx = 1;
    std::vector<double> map;
    std::uint64_t frame = 0;
    // Frame rendering: each laser's surface is sampled at `samples` x
    // positions from x_lo in steps of x_step (mm), finer than a column.
    double x_lo[2] = {0, 0}, x_step[2] = {1, 1};
    std::size_t samples[2] = {0, 0};
    bool u_increasing[2] = {true, true};
    std::vector<double> plane_points, image_points;  // 2 * max samples
    std::vector<double> centre_row[2];               // [width], px
    std::vector<float> intensity;                    // [width * height]
    // The line in the field, per laser and column of the current frame: x
    // of the column's centre on the strip's line (mm) and the share of the
    // column the strip covers; the table line's row and the share of the
    // column where it is lit (static: the table does not move).
    std::vector<double> strip_x[2], strip_cover[2];  // [width]
    // The line's height (mm) and its strip reflectance, per laser and column
    // of the current frame (sim_depth_of_field, sim_dark_patches).
    std::vector<double> strip_z[2], strip_reflectance[2];  // [width]
    // Ambient light (sim_ambient), per column of the current frame: the
    // strip's x there (mm from its centre line), the material position s
    // (mm) at row ambient_v0 and its change per row, and the light on bare
    // steel (counts, times the share of the column on the strip; 0: none).
    std::vector<double> ambient_xs, ambient_s0, ambient_v0, ambient_ds_dv, ambient_light;
    std::vector<double> noiseless_row[2];  // [width]: the line's row before sim_peak_sigma
    // The reflectance cells each column is in while add_ambient walks down
    // the rows: the cell's along index and its value, per kind.
    std::vector<double> patch_along, patch_value, grain_along, grain_value;  // [width]
    std::vector<double> table_row[2], table_cover_lo[2], table_cover_hi[2];  // [width]
    std::vector<float> spill;  // [width * height] with blooming
    std::vector<float> carry;  // [width] with blooming
    std::vector<float> noise;  // [width]: one row's shot-noise draws (quantise)
    mutable walk_cursor walk;  // lateral wander

    ~flt_sim() { flt_calib_destroy(calib); }

    double full_scale() const { return double((1u << params.bit_depth) - 1u); }

    // The sheet at strip coordinate x (mm from the centre line) and material
    // position s, for a strip `strip_width` wide.
    double sheet(double x, double s, double strip_width) const {
        const double half = 0.5 * strip_width;
        const double xc = std::min(std::max(x, -half), half);
        const double q = xc / half;  // -1 .. 1
        double z = 0;
        for (const defect &d : defects) {
            double g = 0;
            switch (d.kind) {
                case FLT_SIM_FLAT:
                    g = 0;
                    break;
                case FLT_SIM_CENTRE_BUCKLE: {
                    const double c = flt::crt::cos(k_pi * xc / strip_width);
                    g = c * c;
                    break;
                }
                case FLT_SIM_WAVY_EDGE_LEFT:
                    g = q < 0 ? q * q * q * q : 0;
                    break;
                case FLT_SIM_WAVY_EDGE_RIGHT:
                    g = q > 0 ? q * q * q * q : 0;
                    break;
                case FLT_SIM_WAVY_EDGE_BOTH:
                    g = q * q * q * q;
                    break;
                case FLT_SIM_QUARTER_BUCKLE: {
                    const double a = (std::fabs(xc) - 0.25 * strip_width) / (0.125 * strip_width);
                    g = flt::crt::exp(-a * a);
                    break;
                }
                case FLT_SIM_BOW:
                    g = 1;
                    break;
                case FLT_SIM_CROSSBOW:
                    g = q * q;
                    break;
                default:
                    g = 0;
                    break;
            }
            const double w = d.period_mm > 0 ? flt::crt::sin(2 * k_pi * s / d.period_mm) : 1.0;
            z += d.amplitude_mm * g * w;
        }
        if (map_rows)
            z += height_map(x, s);
        return z;
    }

    double height_map(double x, double s) const {
        double fr = (s - map_s0) / map_ds, fc = (x - map_x0) / map_dx;
        fr = std::min(std::max(fr, 0.0), double(map_rows - 1));
        fc = std::min(std::max(fc, 0.0), double(map_cols - 1));
        const std::size_t r = std::min(std::size_t(fr), map_rows - 2);
        const std::size_t c = std::min(std::size_t(fc), map_cols - 2);
        const double a = fr - double(r), b = fc - double(c);
        const double *p = &map[r * map_cols + c];
        return (1 - a) * ((1 - b) * p[0] + b * p[1]) +
               a * ((1 - b) * p[map_cols] + b * p[map_cols + 1]);
    }

    // The shear-station ringing at material position s: the damped sine of
    // each earlier cut, until its envelope is negligible (exp(-30)).
    double shear(double s) const {
        const sim_params &p = params;
        if (!(p.shear_amplitude > 0))
            return 0;
        double z = 0;
        double cut = std::floor(s / p.shear_interval) * p.shear_interval;
        for (int k = 0; k < 16; ++k) {
            const double d = s - cut;
            if (d * p.shear_decay > 30)
                break;
            z += p.shear_amplitude * flt::crt::exp(-p.shear_decay * d) *
                 flt::crt::sin(2 * k_pi * d / p.shear_period);
            if (p.shear_decay <= 0)
                break;  // undamped: only the latest cut
            cut -= p.shear_interval;
        }
        return z;
    }

    double encoder_of(std::uint64_t f) const {
        return params.start + double(f) * params.frame_spacing;
    }
    double row_position(double e) const { return e - 0.5 * (offset_mm[0] + offset_mm[1]); }

    struct motion {
        double heave, tilt, eccentricity;
    };
    motion motion_of(std::uint64_t f) const {
        sim_rng rng(params.seed, f, stream_motion);
        motion m;
        m.heave = params.heave_sigma * rng.gauss();
        m.tilt = params.tilt_sigma * rng.gauss();
        m.eccentricity =
            params.ecc_amplitude * flt::crt::sin(2 * k_pi * encoder_of(f) / params.ecc_period);
        return m;
    }

    bool has_edges() const { return params.surround != FLT_SIM_SURROUND_STRIP; }
    bool has_coils() const { return params.coil_length > 0; }

    // The coil at material position s: false between coils; its width.
    bool coil_at(double s, double *strip_width) const {
        *strip_width = params.strip_width;
        if (!has_coils())
            return true;
        const double period = params.coil_length + params.coil_gap;
        const double k = std::floor(s / period);
        if (std::fmod(k, 2.0) != 0.0 && params.second_width > 0)
            *strip_width = params.second_width;
        return k >= 0 && s - k * period < params.coil_length;
    }

    // Knot n of the wander's random walk, moving `cursor` (see walk_cursor).
    void walk_to(walk_cursor &cursor, long long n) const {
        if (n < cursor.last - 3)
            cursor = walk_cursor();
        const double a = flt::crt::exp(-1.0 / k_walk_knots_per_length);
        const double step = params.wander_sigma * std::sqrt(1 - a * a);
        while (cursor.last < n) {
            ++cursor.last;
            sim_rng rng(params.seed, std::uint64_t(cursor.last), stream_wander);
            const double xi = rng.gauss();
            const double next =
                cursor.last == 0 ? params.wander_sigma * xi : a * cursor.w[3] + step * xi;
            cursor.w[0] = cursor.w[1], cursor.w[1] = cursor.w[2], cursor.w[2] = cursor.w[3];
            cursor.w[3] = next;
        }
    }
    double walk_value(walk_cursor &cursor, double e) const {
        if (!(params.wander_sigma > 0))
            return 0;
        const double spacing = params.wander_length / k_walk_knots_per_length;
        const double u = std::max(0.0, (e - params.start) / spacing);
        const long long n = (long long)std::floor(u);
        const double t = u - double(n);
        walk_to(cursor, n + 2);
        // cursor.w = knots n - 1 .. n + 2 (knot -1 is knot 0).
        const double w0 = n == 0 ? cursor.w[1] : cursor.w[0], w1 = cursor.w[1], w2 = cursor.w[2],
                     w3 = cursor.w[3];
        // Catmull-Rom: C1, through the knots.
        return 0.5 * (2 * w1 + (w2 - w0) * t + (2 * w0 - 5 * w1 + 4 * w2 - w3) * t * t +
                      (3 * w1 - w0 - 3 * w2 + w3) * t * t * t);
    }
    // The strip's centre line at encoder position e, sensor x, mm.
    double centre_at(walk_cursor &cursor, double e) const {
        double c = params.strip_offset + walk_value(cursor, e);
        if (params.wander_amplitude > 0)
            c += params.wander_amplitude * flt::crt::sin(2 * k_pi * e / params.wander_period);
        return c;
    }

    // What laser L sees of the strip in a frame at e whose centre line is c.
    struct strip_view {
        bool present;
        double width, left, right;  // mm; left < right
    };
    strip_view view_of(unsigned laser, double e, double c) const {
        strip_view v;
        v.present = coil_at(e - offset_mm[laser], &v.width);
        v.left = c - 0.5 * v.width;
        v.right = c + 0.5 * v.width;
        return v;
    }
    // Whether sensor x is on the strip for that view.
    bool on_strip(const strip_view &v, double x) const {
        return v.present && (!has_edges() || (x >= v.left && x <= v.right));
    }

    // What laser L sees at sensor x in frame f (mm), before peak noise, on
    // a strip of that view centred at c.
    double laser_z(unsigned laser, double e, const motion &m, double x, double c,
                   const strip_view &v) const {
        const double s = e - offset_mm[laser];
        return sheet(x - c, s, v.width) + shear(s) + m.heave + m.tilt * x + m.eccentricity;
    }

    // The truth at fiber x of a row at e whose centre line is c: NaN off the
    // strip.
    double row_truth(double x, double e, double c, const strip_view *views) const {
        if (!on_strip(views[0], x) || !on_strip(views[1], x))
            return k_nan;
        double strip_width;
        coil_at(row_position(e), &strip_width);
        return sheet(x - c, row_position(e), strip_width);
    }

    void make_rows(std::size_t rows, double *encoder_out, double *s_out, double *height_out,
                   double *slope, std::uint8_t *valid, double *truth) {
        const std::size_t n = fiber_x.size();
        const unsigned ahead = unsigned(ahead_laser), behind = 1 - ahead;
        for (std::size_t r = 0; r < rows; ++r, ++frame) {
            const double e = encoder_of(frame);
            const motion m = motion_of(frame);
            sim_rng rng(params.seed, frame, stream_row_noise);
            const double s_row = row_position(e);
            const double c = centre_at(walk, e);
            const strip_view views[2] = {view_of(0, e, c), view_of(1, e, c)};
            if (encoder_out)
                encoder_out[r] = e;
            s_out[r] = s_row;
            for (std::size_t k = 0; k < n; ++k) {
                const double x = fiber_x[k];
                double z[2];
                for (unsigned laser = 0; laser < 2; ++laser) {
                    z[laser] = laser_z(laser, e, m, x, c, views[laser]);
                    if (params.peak_sigma_px > 0)  // drawn on or off the strip alike
                        z[laser] += params.peak_sigma_px * dz_dv[laser][k] * rng.gauss();
                }
                const bool on = on_strip(views[0], x) && on_strip(views[1], x);
                height_out[r * n + k] = on ? 0.5 * (z[0] + z[1]) : k_nan;
                slope[r * n + k] = on ? (z[ahead] - z[behind]) / laser_spacing : k_nan;
                if (valid)
                    valid[r * n + k] = on ? 1 : 0;
                if (truth)
                    truth[r * n + k] = row_truth(x, e, c, views);
            }
        }
    }

    // Each column's line centre row for both lasers in frame f, and where
    // the strip is: the x of each column's centre on the strip's line and
    // the share of the column the strip covers.
    void line_centres(std::uint64_t f) {
        const double e = encoder_of(f);
        const motion m = motion_of(f);
        sim_rng rng(params.seed, f, stream_peak_noise);
        const double c = centre_at(walk, e);
        for (unsigned laser = 0; laser < 2; ++laser) {
            const strip_view view = view_of(laser, e, c);
            const std::size_t ns = samples[laser];
            for (std::size_t i = 0; i < ns; ++i) {
                const double x = x_lo[laser] + double(i) * x_step[laser];
                plane_points[2 * i] = x;
                plane_points[2 * i + 1] = laser_z(laser, e, m, x, c, view);
            }
            check(flt_calib_plane_to_image(calib, laser, ns, plane_points.data(),
                                           image_points.data()));
            // Walk the sampled polyline in increasing u and interpolate the row
            // at every integer column.
            double *centre = centre_row[laser].data();
            std::size_t j = 0;
            auto u_at = [&](std::size_t i) {
                return image_points[2 * (u_increasing[laser] ? i : ns - 1 - i)];
            };
            auto v_at = [&](std::size_t i) {
                return image_points[2 * (u_increasing[laser] ? i : ns - 1 - i) + 1];
            };
            auto x_at = [&](std::size_t i) {
                return plane_points[2 * (u_increasing[laser] ? i : ns - 1 - i)];
            };
            double *column_x = strip_x[laser].data();
            double *column_z = strip_z[laser].data();
            auto z_at = [&](std::size_t i) {
                return plane_points[2 * (u_increasing[laser] ? i : ns - 1 - i) + 1];
            };
            for (std::uint32_t u = 0; u < width; ++u) {
                while (j + 2 < ns && !(u_at(j + 1) >= double(u)))
                    ++j;
                const double u0 = u_at(j), u1 = u_at(j + 1);
                double v = k_nan, x = k_nan, z = k_nan;
                if (u0 <= double(u) && double(u) <= u1 && u1 > u0) {
                    const double t = (double(u) - u0) / (u1 - u0);
                    v = v_at(j) + t * (v_at(j + 1) - v_at(j));
                    x = x_at(j) + t * (x_at(j + 1) - x_at(j));
                    z = z_at(j) + t * (z_at(j + 1) - z_at(j));
                }
                noiseless_row[laser][u] = v;
                if (params.peak_sigma_px > 0)
                    v += params.peak_sigma_px * rng.gauss();
                if (!(v >= 0 && v <= double(height - 1)))
                    v = k_nan;
                centre[u] = v;
                column_x[u] = x;
                column_z[u] = z;
            }
            // The share of each column on the strip: its interval runs
            // halfway to its neighbours' centres.
            double *cover = strip_cover[laser].data();
            for (std::uint32_t u = 0; u < width; ++u) {
                if (!view.present) {
                    cover[u] = 0;
                } else if (!has_edges()) {
                    cover[u] = 1;
                } else {
                    const double xc = column_x[u];
                    const double xl = u > 0 ? column_x[u - 1] : 2 * xc - column_x[u + 1];
                    const double xr = u + 1 < width ? column_x[u + 1] : 2 * xc - column_x[u - 1];
                    const double a = 0.5 * (xl + xc), b = 0.5 * (xc + xr);
                    cover[u] = xc == xc ? overlap_share(std::min(a, b), std::max(a, b), view.left,
                                                        view.right)
                                        : 0.0;
                }
                if (cover[u] == 0)
                    centre[u] = k_nan;
            }
            double *reflectance = strip_reflectance[laser].data();
            const double s_laser = e - offset_mm[laser];
            for (std::uint32_t u = 0; u < width; ++u)
                reflectance[u] = (params.dark_patches > 0 || params.texture > 0) && cover[u] > 0
                                     ? surface_reflectance(column_x[u] - c, s_laser)
                                     : 1.0;
        }
        if (params.ambient > 0)
            ambient_geometry(e, c);
    }

    // Where each column's pixels lie on the strip (sim_ambient). Along a
    // column, the rows between the two lasers' lines see the strip between
    // their material positions e - offset: s is taken linear in the row
    // through both lines (and beyond them), x the mean of the two lines'.
    // A column where either line is not on the polyline, or both share a
    // row, gets no ambient light.
    void ambient_geometry(double e, double c) {
        const double fs = full_scale();
        const double s0 = e - offset_mm[0], s1 = e - offset_mm[1];
        for (std::uint32_t u = 0; u < width; ++u) {
            const double r0 = noiseless_row[0][u], r1 = noiseless_row[1][u];
            const double cover = 0.5 * (strip_cover[0][u] + strip_cover[1][u]);
            const double x = 0.5 * (strip_x[0][u] + strip_x[1][u]);
            ambient_light[u] = 0;
            patch_along[u] = grain_along[u] = k_nan;  // no cell yet
            if (!(r0 == r0 && r1 == r1 && r1 != r0 && x == x && cover > 0))
                continue;
            ambient_xs[u] = x - c;
            ambient_s0[u] = s0;
            ambient_v0[u] = r0;
            ambient_ds_dv[u] = (s1 - s0) / (r1 - r0);
            ambient_light[u] = params.ambient * fs * cover;
        }
    }

    // Adds the ambient light the strip reflects: row by row (the
    // intensity's order), each column's reflectance cell looked up only
    // when the row enters a new one.
    void add_ambient() {
        for (std::uint32_t v = 0; v < height; ++v) {
            float *row = &intensity[std::size_t(v) * width];
            for (std::uint32_t u = 0; u < width; ++u) {
                const double light = ambient_light[u];
                if (!(light > 0))
                    continue;
                const double s = ambient_s0[u] + (double(v) - ambient_v0[u]) * ambient_ds_dv[u];
                double r = 1.0;
                if (params.dark_patches > 0) {
                    const double along = clamped_cell(s / k_patch_along_mm, 1e15);
                    if (!(along == patch_along[u])) {
                        patch_along[u] = along;
                        patch_value[u] = patch_of_cell(
                            clamped_cell(ambient_xs[u] / k_patch_across_mm, 1e9), along);
                    }
                    r *= patch_value[u];
                }
                if (params.texture > 0) {
                    const double along = clamped_cell(s / k_grain_mm, 1e15);
                    if (!(along == grain_along[u])) {
                        grain_along[u] = along;
                        grain_value[u] =
                            grain_of_cell(clamped_cell(ambient_xs[u] / k_grain_mm, 1e9), along);
                    }
                    r *= grain_value[u];
                }
                row[u] += float(light * r);
            }
        }
    }

    // The strip's reflectance at strip coordinate xs (mm from its centre
    // line) and material position s: its dark patches times its texture.
    double surface_reflectance(double xs, double s) const {
        double r = 1.0;
        if (params.dark_patches > 0)
            r *= patch_reflectance(xs, s);
        if (params.texture > 0 && xs == xs && s == s)
            r *= grain_of_cell(clamped_cell(xs / k_grain_mm, 1e9),
                               clamped_cell(s / k_grain_mm, 1e15));
        return r;
    }

    // floor(x), clamped to -+limit while still a double: converting an
    // absurd position to an integer would be undefined.
    static double clamped_cell(double x, double limit) {
        return std::min(std::max(std::floor(x), -limit), limit);
    }

    static std::uint64_t cell_key(double across, double along) {
        return (std::uint64_t(std::int64_t(across)) << 48) ^ std::uint64_t(std::int64_t(along));
    }

    // The strip's reflectance at strip coordinate xs (mm from its centre
    // line) and material position s (sim_dark_patches): cells of
    // k_patch_across_mm x k_patch_along_mm fixed to the strip, each dark
    // with probability sim_dark_patches, then reflecting 0.15-0.5 of what
    // bare steel does (a coated, oiled or scaled patch), drawn from
    // (sim_seed, cell): the same patch in every frame that sees it.
    double patch_reflectance(double xs, double s) const {
        if (!(xs == xs && s == s))
            return 1.0;
        return patch_of_cell(clamped_cell(xs / k_patch_across_mm, 1e9),
                             clamped_cell(s / k_patch_along_mm, 1e15));
    }

    double patch_of_cell(double across, double along) const {
        sim_rng rng(params.seed, cell_key(across, along), stream_patches);
        const double dark = rng.uniform(), level = rng.uniform();
        return dark < params.dark_patches ? 0.15 + 0.35 * level : 1.0;
    }

    // The texture (sim_texture): each k_grain_mm square cell fixed to the
    // strip reflects 1 + texture * (2 U - 1) of bare steel, U uniform from
    // (sim_seed, cell).
    double grain_of_cell(double across, double along) const {
        sim_rng rng(params.seed, cell_key(across, along), stream_texture);
        return 1.0 + params.texture * (2.0 * rng.uniform() - 1.0);
    }

    // The share of column u's interval [lo, hi] on the table (mm) that is
    // lit: not in a roller gap and not under the strip.
    double table_share(double lo, double hi, const strip_view &view) const {
        if (!(hi > lo))
            return 0;
        double lit = (hi - lo) - table_gap_length(lo, hi, params.roller_pitch, params.roller_gap);
        if (view.present) {
            const double a = std::max(lo, view.left), b = std::min(hi, view.right);
            if (b > a)
                lit -= (b - a) - table_gap_length(a, b, params.roller_pitch, params.roller_gap);
        }
        return std::max(0.0, lit / (hi - lo));
    }

    // Adds a Gaussian ridge along columns [u_first, u_last] with centre row
    // v(u) = v0 + slope (u - u0), sigma px, peak amplitude * envelope(u),
    // times a multiplicative speckle factor per pixel.
    void add_ridge(std::uint32_t u, double centre, double sigma, double amplitude, sim_rng &rng) {
        if (!(centre == centre))
            return;
        const double reach = 4.5 * sigma;
        const long v_first = std::max(0L, long(std::floor(centre - reach)));
        const long v_last = std::min(long(height) - 1, long(std::ceil(centre + reach)));
        const double inv = -0.5 / (sigma * sigma);
        const float contrast = float(params.speckle);
        for (long v = v_first; v <= v_last; ++v) {
            const double d = double(v) - centre;
            float speckle = 1.0f + contrast * rng.fast_gauss();
            if (speckle < 0)
                speckle = 0;
            intensity[std::size_t(v) * width + u] +=
                float(amplitude * flt::crt::exp(d * d * inv)) * speckle;
        }
    }

    void add_reflections(std::uint64_t f, double line_amplitude, sim_rng &pixel_rng) {
        sim_rng rng(params.seed, f, stream_reflections);
        const unsigned count = rng.poisson(params.reflections);
        const double fs = full_scale();
        for (unsigned i = 0; i < count; ++i) {
            const bool glint = rng.uniform() < 0.5;
            const double u0 = rng.uniform() * width;
            const std::uint32_t uc = std::min(width - 1, std::uint32_t(u0));
            // Near the lines, where the bands are: up to 60 px beyond either.
            const double c0 = centre_row[0][uc], c1 = centre_row[1][uc];
            double lo = 0, hi = double(height - 1);
            if (c0 == c0 && c1 == c1)
                lo = std::min(c0, c1) - 60, hi = std::max(c0, c1) + 60;
            const double v0 = lo + (hi - lo) * rng.uniform();
            double half_len, sigma, amplitude, slant;
            if (glint) {  // specular glint: short, narrow, saturating
                half_len = 1 + 7 * rng.uniform();
                sigma = 1 + 2 * rng.uniform();
                amplitude = (1.5 + 2.5 * rng.uniform()) * fs;
                slant = 0;
            } else {  // secondary reflection of the line: long and dim
                half_len = 10 + 50 * rng.uniform();
                sigma = 1.5 + 3.5 * rng.uniform();
                amplitude = (0.15 + 0.45 * rng.uniform()) * line_amplitude;
                slant = 0.4 * rng.uniform() - 0.2;
            }
            const long u_first = std::max(0L, long(std::ceil(u0 - half_len)));
            const long u_last = std::min(long(width) - 1, long(std::floor(u0 + half_len)));
            for (long u = u_first; u <= u_last; ++u) {
                const double t = (double(u) - u0) / half_len;
                const double envelope = flt::crt::cos(0.5 * k_pi * t);
                add_ridge(std::uint32_t(u), v0 + slant * (double(u) - u0), sigma,
                          amplitude * envelope * envelope, pixel_rng);
            }
        }
    }

    template <class Pixel> void quantise(void *frame_out, std::size_t stride, sim_rng &rng) {
        const double fs = full_scale();
        // Shot noise: I counts hold I * full_well / fs electrons, whose
        // Poisson sigma is sqrt of that; back in counts sqrt(I * fs / full_well).
        // A tiny full well (1e-30 electrons is inside the option's range)
        // makes fs / full_well overflow a float; 0 * inf or inf * 0 is then
        // NaN, whose conversion to a pixel was undefined. The gain is capped
        // at k_max_gain: a pixel of more than 1e-10 counts then still has a
        // noise sigma beyond full scale (it clips to 0 or full scale as
        // without the cap); only pixels dimmer than that get less noise than
        // the formula. The clamp below is NaN-safe as well.
        constexpr double k_max_gain = 1e20;
        const float gain =
            params.full_well > 0 ? float(std::min(fs / params.full_well, k_max_gain)) : 0.0f;
        const float top = float(fs);
        const float encode = float(1.0 / params.gamma);
        // Locals: a store through a Pixel (bytes may alias anything) would
        // otherwise make the compiler read width and the generator's state
        // again after every pixel.
        const std::uint32_t w = width, h = height;
        sim_rng local = rng;
        for (std::uint32_t v = 0; v < h; ++v) {
            Pixel *row = reinterpret_cast<Pixel *>(static_cast<unsigned char *>(frame_out) +
                                                   std::size_t(v) * stride);
            const float *in = &intensity[std::size_t(v) * w];
            // The row's draws first, one per pixel (so the stream does not
            // depend on which pixels saturate), then the pixels: the
            // generator's serial chain apart, the second loop vectorises.
            float *draw = noise.data();
            if (gain > 0)
                for (std::uint32_t u = 0; u < w; ++u)
                    draw[u] = local.fast_gauss();
            else
                std::fill(draw, draw + w, 0.0f);
            if (encode != 1.0f) {
                // A camera with a gamma (sim_gamma): the pixel encodes
                // full scale times (signal / full scale)^(1 / gamma).
                for (std::uint32_t u = 0; u < w; ++u) {
                    const float value = in[u];
                    const float x = value + std::sqrt(std::max(value, 0.0f) * gain) * draw[u];
                    float level = x > 0.0f ? x / top : 0.0f;  // NaN: 0
                    level = level < 1.0f ? level : 1.0f;
                    const float encoded = top * std::pow(level, encode) + 0.5f;
                    row[u] = Pixel(value >= top || !(encoded < top) ? top : encoded);
                }
                continue;
            }
            // Without branches (selects), so that it vectorises
            // (lib/CMakeLists.txt gives this file the flags it needs).
            for (std::uint32_t u = 0; u < w; ++u) {
                const float value = in[u];
                float x = value + std::sqrt(std::max(value, 0.0f) * gain) * draw[u];
                x += 0.5f;
                x = x > 0.0f ? x : 0.0f;  // NaN: 0
                x = x < top ? x : top;
                row[u] = Pixel(value >= top ? top : x);  // a full well reads full scale
            }
        }
        rng = local;
    }

    // The roller table's line where the strip does not cover it.
    void add_table(std::uint64_t f, double amplitude, sim_rng &rng) {
        const double e = encoder_of(f);
        const double c = centre_at(walk, e);
        for (unsigned laser = 0; laser < 2; ++laser) {
            const strip_view view = view_of(laser, e, c);
            for (std::uint32_t u = 0; u < width; ++u) {
                const double share =
                    table_share(table_cover_lo[laser][u], table_cover_hi[laser][u], view);
                if (share > 0)
                    add_ridge(u, table_row[laser][u], params.line_sigma_px,
                              amplitude * params.table_brightness * share, rng);
            }
        }
    }

    // Specular glints on the line just inside the strip's edges (a sheared
    // edge's burr): saturating, 1-6 columns long, ending at the edge.
    void add_edge_glints(std::uint64_t f, sim_rng &pixel_rng) {
        sim_rng rng(params.seed, f, stream_edge_glints);
        const double fs = full_scale();
        for (unsigned laser = 0; laser < 2; ++laser) {
            const double *cover = strip_cover[laser].data();
            for (int side = 0; side < 2; ++side) {
                const bool glint = rng.uniform() < params.edge_glints;
                const double length = 1 + 5 * rng.uniform();
                const double sigma = 1 + 2 * rng.uniform();
                const double peak = (1.5 + 2.5 * rng.uniform()) * fs;
                if (!glint)
                    continue;
                // The edge: the last column (from this side's end of the
                // strip inwards) that the strip covers at all.
                const long inward = side == 0 ? 1 : -1;
                long edge = -1;
                if (side == 0) {
                    for (long u = 0; u < long(width) && edge < 0; ++u)
                        if (cover[u] > 0)
                            edge = u;
                } else {
                    for (long u = long(width) - 1; u >= 0 && edge < 0; --u)
                        if (cover[u] > 0)
                            edge = u;
                }
                if (edge < 0 || (side == 0 && edge == 0) || (side == 1 && edge == long(width) - 1))
                    continue;  // the strip reaches the frame's border: no edge seen
                for (long i = 0; i < long(std::ceil(length)); ++i) {
                    const long u = edge + inward * i;
                    if (u < 0 || u >= long(width) || !(cover[u] > 0))
                        break;
                    const double t = (double(i) + 0.5) / length;  // 0..1 from the edge
                    const double envelope = flt::crt::cos(0.5 * k_pi * std::min(1.0, t));
                    const double row = centre_row[laser][u];
                    add_ridge(std::uint32_t(u), row, sigma, peak * envelope * envelope * cover[u],
                              pixel_rng);
                }
            }
        }
    }

    // Blooming: a share of the charge above full scale spills along the
    // column, half down and half up, into the first pixels with room.
    void bloom() {
        const float fs = float(full_scale());
        const float share = float(params.blooming);
        bool any = false;
        for (std::size_t i = 0; i < intensity.size(); ++i) {
            const float excess = intensity[i] > fs ? share * (intensity[i] - fs) : 0.0f;
            spill[i] = 0.5f * excess;
            intensity[i] -= excess;
            any = any || excess > 0;
        }
        if (!any)
            return;
        for (int pass = 0; pass < 2; ++pass) {  // down, then up
            std::fill(carry.begin(), carry.end(), 0.0f);
            for (std::uint32_t step = 0; step < height; ++step) {
                const std::uint32_t v = pass == 0 ? step : height - 1 - step;
                float *row = &intensity[std::size_t(v) * width];
                const float *out = &spill[std::size_t(v) * width];
                for (std::uint32_t u = 0; u < width; ++u) {
                    const float room = std::max(0.0f, fs - row[u]);
                    const float take = std::min(carry[u], room);
                    row[u] += take;
                    carry[u] += out[u] - take;
                }
            }
        }
    }

    void render(std::uint64_t f, void *frame_out, std::size_t stride) {
        line_centres(f);
        const double fs = full_scale();
        std::fill(intensity.begin(), intensity.end(), float(params.background * fs));
        if (params.ambient > 0)
            add_ambient();
        sim_rng rng(params.seed, f, stream_pixels);
        const double amplitude = params.line_peak * fs;
        for (unsigned laser = 0; laser < 2; ++laser)
            for (std::uint32_t u = 0; u < width; ++u) {
                const double cover = strip_cover[laser][u];
                if (!(cover > 0))
                    continue;
                // Out of focus the line widens and its peak falls as it
                // widens (the light is the same): sigma grows as
                // sqrt(1 + (z / sim_depth_of_field)^2), focus at z = 0.
                // Dark patches dim the line, not the background.
                double sigma = params.line_sigma_px;
                double peak = amplitude * cover * strip_reflectance[laser][u];
                const double z = strip_z[laser][u];
                if (params.depth_of_field > 0 && z == z) {
                    // Capped: a tiny depth of field (1e-300 mm is inside the
                    // option's range) must not make the ridge infinitely
                    // wide; a thousand times as wide is no line either way.
                    const double d = z / params.depth_of_field;
                    const double grow = std::min(std::sqrt(1 + d * d), 1e3);
                    sigma *= grow, peak /= grow;
                }
                add_ridge(u, centre_row[laser][u], sigma, peak, rng);
            }
        if (params.surround == FLT_SIM_SURROUND_ROLLER_TABLE)
            add_table(f, amplitude, rng);
        if (params.edge_glints > 0 && has_edges())
            add_edge_glints(f, rng);
        if (params.reflections > 0)
            add_reflections(f, amplitude, rng);
        if (params.blooming > 0)
            bloom();
        if (params.bit_depth == 8)
            quantise<std::uint8_t>(frame_out, stride, rng);
        else
            quantise<std::uint16_t>(frame_out, stride, rng);
    }
};

namespace {

flt_status check_handle(const char *fn, const flt_sim *sim) {
    if (sim == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'sim' is NULL", fn);
    if (sim->magic != k_sim_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'sim' is not a live flt_sim handle",
                    fn);
    return FLT_OK;
}

flt_status check_fibers(const char *fn, const flt_sim *sim, std::size_t fibers) {
    if (fibers != sim->fiber_x.size())
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'fibers' = %zu but the simulator has %zu", fn, fibers,
                    sim->fiber_x.size());
    return FLT_OK;
}

// The roller table's line in the image (it does not move): per column its
// row and the x interval the column spans on the table, mm.
void setup_table(flt_sim &sim) {
    for (unsigned laser = 0; laser < 2; ++laser) {
        // Each column's x on the table: map the column at the table's row
        // under the middle of the frame back to the plane.
        double probe[2] = {0, -sim.params.table_depth}, img[2];
        check(flt_calib_plane_to_image(sim.calib, laser, 1, probe, img));
        std::vector<double> pts(2 * std::size_t(sim.width));
        for (std::size_t u = 0; u < sim.width; ++u)
            pts[2 * u] = double(u), pts[2 * u + 1] = img[1];
        // Two passes: x at the row of z = -depth, then the row of that x
        // exactly on z = -depth (the line is not straight in the image).
        check(flt_calib_image_to_plane(sim.calib, laser, sim.width, pts.data(), pts.data()));
        std::vector<double> xs(sim.width);
        for (std::size_t u = 0; u < sim.width; ++u) {
            xs[u] = pts[2 * u];
            pts[2 * u + 1] = -sim.params.table_depth;
        }
        check(flt_calib_plane_to_image(sim.calib, laser, sim.width, pts.data(), pts.data()));
        for (std::uint32_t u = 0; u < sim.width; ++u) {
            const double v = pts[2 * u + 1];
            sim.table_row[laser][u] =
                std::isfinite(v) && v >= 0 && v <= double(sim.height - 1) ? v : k_nan;
        }
        for (std::uint32_t u = 0; u < sim.width; ++u) {
            const double xc = xs[u];
            const double xl = u > 0 ? xs[u - 1] : 2 * xc - xs[u + 1];
            const double xr = u + 1 < sim.width ? xs[u + 1] : 2 * xc - xs[u - 1];
            const double a = 0.5 * (xl + xc), b = 0.5 * (xc + xr);
            sim.table_cover_lo[laser][u] = std::min(a, b);
            sim.table_cover_hi[laser][u] = std::max(a, b);
        }
    }
}

// Sets up the geometry of a simulator from its (private) calibration.
void setup_geometry(flt_sim &sim) {
    check(flt_calib_get_frame_size(sim.calib, &sim.width, &sim.height));
    for (unsigned laser = 0; laser < 2; ++laser)
        check(flt_calib_get_laser_offset(sim.calib, laser, &sim.offset_mm[laser]));
    sim.laser_spacing = std::fabs(sim.offset_mm[1] - sim.offset_mm[0]);
    // s_L = e - offset_L: the smaller offset reads further along the strip.
    sim.ahead_laser = sim.offset_mm[0] < sim.offset_mm[1] ? 0 : 1;
    double first_x, pitch;
    std::size_t count;
    check(flt_calib_get_fiber_grid(sim.calib, &first_x, &pitch, &count));
    sim.fiber_x.resize(count);
    for (std::size_t k = 0; k < count; ++k)
        sim.fiber_x[k] = first_x + double(k) * pitch;

    for (unsigned laser = 0; laser < 2; ++laser) {
        // dz/dv at each fiber at z = 0: map (x, 0) into the image, step one
        // row down and map back.
        std::vector<double> pts(2 * count), img(2 * count);
        for (std::size_t k = 0; k < count; ++k)
            pts[2 * k] = sim.fiber_x[k], pts[2 * k + 1] = 0;
        check(flt_calib_plane_to_image(sim.calib, laser, count, pts.data(), img.data()));
        for (std::size_t k = 0; k < count; ++k)
            img[2 * k + 1] += 1.0;
        check(flt_calib_image_to_plane(sim.calib, laser, count, img.data(), pts.data()));
        sim.dz_dv[laser].resize(count);
        double fallback = 0;
        for (std::size_t k = 0; k < count; ++k)
            if (std::isfinite(pts[2 * k + 1]))
                fallback = std::fabs(pts[2 * k + 1]);
        for (std::size_t k = 0; k < count; ++k)
            sim.dz_dv[laser][k] =
                std::isfinite(pts[2 * k + 1]) ? std::fabs(pts[2 * k + 1]) : fallback;

        // The x range the camera sees on this laser's plane near z = 0: the
        // frame's left and right edges at the row of (0, 0), plus 5 %.
        double origin[2] = {0, 0}, row[2];
        check(flt_calib_plane_to_image(sim.calib, laser, 1, origin, row));
        double edges[4] = {0, row[1], double(sim.width - 1), row[1]};
        check(flt_calib_image_to_plane(sim.calib, laser, 2, edges, edges));
        if (!std::isfinite(edges[0]) || !std::isfinite(edges[2]) || edges[0] == edges[2])
            throw error(FLT_ERR_NUMERIC,
                        "flt_sim_create: the calibration's laser plane is not visible "
                        "across the frame");
        const double lo = std::min(edges[0], edges[2]), hi = std::max(edges[0], edges[2]);
        const double margin = 0.05 * (hi - lo);
        // Half a column's width in mm: the polyline is then finer than the
        // columns, and the row at a column is interpolated between samples
        // whose surface heights differ by microns.
        sim.x_step[laser] = 0.5 * (hi - lo) / double(sim.width);
        sim.x_lo[laser] = lo - margin;
        sim.samples[laser] = std::size_t((hi - lo + 2 * margin) / sim.x_step[laser]) + 2;
        sim.u_increasing[laser] = edges[0] < edges[2];
        sim.centre_row[laser].assign(sim.width, k_nan);
        sim.strip_x[laser].assign(sim.width, k_nan);
        sim.strip_z[laser].assign(sim.width, k_nan);
        sim.strip_reflectance[laser].assign(sim.width, 1.0);
        sim.noiseless_row[laser].assign(sim.width, k_nan);
        sim.strip_cover[laser].assign(sim.width, 1.0);
        sim.table_row[laser].assign(sim.width, k_nan);
        sim.table_cover_lo[laser].assign(sim.width, k_nan);
        sim.table_cover_hi[laser].assign(sim.width, k_nan);
    }
    if (sim.params.surround == FLT_SIM_SURROUND_ROLLER_TABLE)
        setup_table(sim);
    if (sim.params.blooming > 0) {
        sim.spill.assign(std::size_t(sim.width) * sim.height, 0.0f);
        sim.carry.assign(sim.width, 0.0f);
    }
    const std::size_t ns = std::max(sim.samples[0], sim.samples[1]);
    sim.plane_points.assign(2 * ns, 0);
    sim.image_points.assign(2 * ns, 0);
    sim.intensity.assign(std::size_t(sim.width) * sim.height, 0.0f);
    sim.noise.assign(sim.width, 0.0f);
    if (sim.params.ambient > 0)
        for (auto *column : {&sim.ambient_xs, &sim.ambient_s0, &sim.ambient_v0, &sim.ambient_ds_dv,
                             &sim.ambient_light, &sim.patch_along, &sim.patch_value,
                             &sim.grain_along, &sim.grain_value})
            column->assign(sim.width, 0.0);
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_sim_create(const flt_calib *calib, const flt_options *options,
                                           flt_sim **out) {
    const char *fn = "flt_sim_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (flt_status st = check_option_component(fn, options, {FLT_OPT_SIM_SEED}))
            return st;
        const sim_params params = read_params(options);
        if (params.bit_depth != 8 && params.bit_depth != 10 && params.bit_depth != 12 &&
            params.bit_depth != 16)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'sim_bit_depth' = %d is not 8, 10, 12 or 16", fn,
                        params.bit_depth);
        if (params.roller_gap >= params.roller_pitch)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: option 'sim_roller_gap' = %g mm is not less than "
                        "'sim_roller_pitch' = %g mm: the table would be all gap",
                        fn, params.roller_gap, params.roller_pitch);
        auto sim = std::make_unique<flt_sim>();
        sim->params = params;
        if (calib) {
            int finished = 0;
            if (flt_calib_is_finished(calib, &finished) != FLT_OK)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'calib' is not a live flt_calib handle", fn);
            if (!finished)
                return fail(FLT_ERR_STATE, "%s: argument 'calib' is not finished", fn);
            sim->calib = copy_calib(calib);
        } else {
            check(flt_calib_create_reference(0, 2048, -1000.0, 2.0, 1001, &sim->calib));
        }
        setup_geometry(*sim);
        sim->defects.reserve(k_max_defects);
        *out = sim.release();
        return FLT_OK;
    });
}

FLT_API void FLT_CALL flt_sim_destroy(flt_sim *sim) {
    guard_void([&] {
        if (sim && sim->magic == k_sim_magic) {
            sim->magic = 0;
            delete sim;
        }
    });
}

FLT_API flt_status FLT_CALL flt_sim_add_defect(flt_sim *sim, flt_sim_defect kind,
                                               double amplitude_mm, double period_mm) {
    const char *fn = "flt_sim_add_defect";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        if (enum_arg(kind) < int(FLT_SIM_FLAT) || enum_arg(kind) > int(FLT_SIM_CROSSBOW))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'kind' = %d is unknown", fn,
                        enum_arg(kind));
        if (!(std::fabs(amplitude_mm) <= FLT_SIM_MAX_HEIGHT_MM))  // NaN too
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'amplitude_mm' = %g is outside [%g, %g] mm", fn, amplitude_mm,
                        -FLT_SIM_MAX_HEIGHT_MM, FLT_SIM_MAX_HEIGHT_MM);
        // A shorter period makes 2 pi s / period overflow, and sin(inf) NaN.
        if (!(period_mm == 0 || (period_mm >= FLT_SIM_MIN_PERIOD_MM && period_mm <= 1e12)))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'period_mm' = %g must be 0 or in [%g, 1e12] mm", fn,
                        period_mm, FLT_SIM_MIN_PERIOD_MM);
        if (sim->defects.size() >= k_max_defects)
            return fail(FLT_ERR_BUFFER_FULL, "%s: the sheet already has %zu defects", fn,
                        k_max_defects);
        sim->defects.push_back({kind, amplitude_mm, period_mm});
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_clear_sheet(flt_sim *sim) {
    const char *fn = "flt_sim_clear_sheet";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        sim->defects.clear();
        sim->map.clear();
        sim->map_rows = sim->map_cols = 0;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_set_height_map(flt_sim *sim, size_t rows, size_t cols,
                                                   double s0_mm, double ds_mm, double x0_mm,
                                                   double dx_mm, const double *heights) {
    const char *fn = "flt_sim_set_height_map";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        FLT_CHECK_NOT_NULL(fn, heights);
        if (rows < 2 || cols < 2)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'rows' = %zu, 'cols' = %zu must both be >= 2", fn, rows,
                        cols);
        if (rows > std::numeric_limits<std::size_t>::max() / sizeof(double) / cols)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: arguments 'rows' x 'cols' = %zu x %zu overflow", fn, rows, cols);
        const double values[4] = {s0_mm, ds_mm, x0_mm, dx_mm};
        const char *names[4] = {"s0_mm", "ds_mm", "x0_mm", "dx_mm"};
        for (int i = 0; i < 4; ++i)
            if (!std::isfinite(values[i]) || (i % 2 == 1 && !(values[i] > 0)))
                return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s' = %g is %s", fn, names[i],
                            values[i], i % 2 == 1 ? "not finite and > 0" : "not finite");
        for (std::size_t i = 0; i < rows * cols; ++i)
            if (!(std::fabs(heights[i]) <= FLT_SIM_MAX_HEIGHT_MM))  // NaN too
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'heights[%zu]' = %g is outside [%g, %g] mm", fn, i,
                            heights[i], -FLT_SIM_MAX_HEIGHT_MM, FLT_SIM_MAX_HEIGHT_MM);
        std::vector<double> map(heights, heights + rows * cols);
        sim->map.swap(map);
        sim->map_rows = rows, sim->map_cols = cols;
        sim->map_s0 = s0_mm, sim->map_ds = ds_mm, sim->map_x0 = x0_mm, sim->map_dx = dx_mm;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_surface(const flt_sim *sim, size_t count, const double *x,
                                            const double *s, double *z_out) {
    const char *fn = "flt_sim_surface";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        if (count == 0)
            return FLT_OK;
        FLT_CHECK_NOT_NULL(fn, x);
        FLT_CHECK_NOT_NULL(fn, s);
        FLT_CHECK_NOT_NULL(fn, z_out);
        if (count > std::numeric_limits<std::size_t>::max() / sizeof(double))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'count' = %zu overflows the address space", fn, count);
        for (std::size_t i = 0; i < count; ++i) {
            double strip_width;
            sim->coil_at(s[i], &strip_width);
            z_out[i] = sim->sheet(x[i], s[i], strip_width);
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_fibers(const flt_sim *sim, size_t *out) {
    const char *fn = "flt_sim_fibers";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = sim->fiber_x.size();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_frame_size(const flt_sim *sim, uint32_t *width_out,
                                               uint32_t *height_out) {
    const char *fn = "flt_sim_frame_size";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        FLT_CHECK_NOT_NULL(fn, width_out);
        FLT_CHECK_NOT_NULL(fn, height_out);
        *width_out = sim->width;
        *height_out = sim->height;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_pixel_format(const flt_sim *sim, flt_pixel_format *out) {
    const char *fn = "flt_sim_pixel_format";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        FLT_CHECK_NOT_NULL(fn, out);
        *out = flt_pixel_format(sim->params.bit_depth);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_next_rows(flt_sim *sim, size_t rows, size_t fibers,
                                              double *encoder_mm_out, double *s_out,
                                              double *height_out, double *slope_out,
                                              uint8_t *valid_out, double *truth_out) {
    const char *fn = "flt_sim_next_rows";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        if (rows == 0)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rows' is 0", fn);
        if (flt_status st = check_fibers(fn, sim, fibers))
            return st;
        if (rows > std::numeric_limits<std::size_t>::max() / sizeof(double) / fibers)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'rows' = %zu overflows", fn, rows);
        FLT_CHECK_NOT_NULL(fn, s_out);
        FLT_CHECK_NOT_NULL(fn, height_out);
        FLT_CHECK_NOT_NULL(fn, slope_out);
        if (!valid_out && (sim->has_edges() || sim->has_coils()))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'valid_out' is NULL, but the strip has edges or coils "
                        "(sim_surround = %d, sim_coil_length = %g): its off-strip NaNs need "
                        "their flag",
                        fn, int(sim->params.surround), sim->params.coil_length);
        sim->make_rows(rows, encoder_mm_out, s_out, height_out, slope_out, valid_out, truth_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_next_frame(flt_sim *sim, void *frame_out, size_t capacity_bytes,
                                               size_t stride_bytes, double *encoder_mm_out,
                                               size_t fibers, double *truth_out,
                                               double *peak_rows_out, size_t peak_rows_count) {
    const char *fn = "flt_sim_next_frame";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        FLT_CHECK_NOT_NULL(fn, frame_out);
        const std::size_t bytes_per_pixel = sim->params.bit_depth == 8 ? 1 : 2;
        if (stride_bytes < std::size_t(sim->width) * bytes_per_pixel)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'stride_bytes' = %zu is less than width %u x %zu "
                        "bytes per pixel",
                        fn, stride_bytes, sim->width, bytes_per_pixel);
        if (bytes_per_pixel == 2 &&
            (stride_bytes % 2 != 0 || reinterpret_cast<std::uintptr_t>(frame_out) % 2 != 0))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: 16-bit frames need an even 'stride_bytes' (= %zu) and a "
                        "2-byte aligned 'frame_out'",
                        fn, stride_bytes);
        if (stride_bytes > std::numeric_limits<std::size_t>::max() / sim->height ||
            capacity_bytes < stride_bytes * sim->height)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'capacity_bytes' = %zu is less than stride %zu x "
                        "height %u",
                        fn, capacity_bytes, stride_bytes, sim->height);
        if (truth_out)
            if (flt_status st = check_fibers(fn, sim, fibers))
                return st;
        if (peak_rows_out && peak_rows_count != 2 * std::size_t(sim->width))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'peak_rows_count' = %zu, but the frame needs 2 x width "
                        "= %zu (a row per laser and column)",
                        fn, peak_rows_count, 2 * std::size_t(sim->width));
        sim->render(sim->frame, frame_out, stride_bytes);
        const double e = sim->encoder_of(sim->frame);
        if (encoder_mm_out)
            *encoder_mm_out = e;
        if (truth_out) {
            const double c = sim->centre_at(sim->walk, e);
            const flt_sim::strip_view views[2] = {sim->view_of(0, e, c), sim->view_of(1, e, c)};
            for (std::size_t k = 0; k < fibers; ++k)
                truth_out[k] = sim->row_truth(sim->fiber_x[k], e, c, views);
        }
        if (peak_rows_out)
            for (unsigned laser = 0; laser < 2; ++laser)
                std::memcpy(peak_rows_out + std::size_t(laser) * sim->width,
                            sim->centre_row[laser].data(), sim->width * sizeof(double));
        ++sim->frame;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_strip_edges(const flt_sim *sim, unsigned laser, size_t count,
                                                const double *encoder_mm, double *left_mm_out,
                                                double *right_mm_out, uint8_t *present_out) {
    const char *fn = "flt_sim_strip_edges";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        if (laser > 2)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'laser' = %u is not 0, 1 or 2 (the row)", fn, laser);
        if (count == 0)
            return FLT_OK;
        FLT_CHECK_NOT_NULL(fn, encoder_mm);
        FLT_CHECK_NOT_NULL(fn, left_mm_out);
        FLT_CHECK_NOT_NULL(fn, right_mm_out);
        for (std::size_t i = 0; i < count; ++i)
            if (!std::isfinite(encoder_mm[i]))
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'encoder_mm[%zu]' = %g is not finite", fn, i,
                            encoder_mm[i]);
        walk_cursor cursor;  // a query must not move the frames' walk
        for (std::size_t i = 0; i < count; ++i) {
            const double e = encoder_mm[i];
            const double c = sim->centre_at(cursor, e);
            const flt_sim::strip_view v0 = sim->view_of(0, e, c), v1 = sim->view_of(1, e, c);
            bool present;
            double left, right;
            if (laser < 2) {
                const flt_sim::strip_view &v = laser == 0 ? v0 : v1;
                present = v.present, left = v.left, right = v.right;
            } else {
                present = v0.present && v1.present;
                left = 0.5 * (v0.left + v1.left), right = 0.5 * (v0.right + v1.right);
            }
            left_mm_out[i] = present ? left : k_nan;
            right_mm_out[i] = present ? right : k_nan;
            if (present_out)
                present_out[i] = present ? 1 : 0;
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_fiber_flags(const flt_sim *sim, double encoder_mm,
                                                size_t fibers, uint8_t *flags_out) {
    const char *fn = "flt_sim_fiber_flags";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        if (flt_status st = check_fibers(fn, sim, fibers))
            return st;
        FLT_CHECK_NOT_NULL(fn, flags_out);
        if (!std::isfinite(encoder_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'encoder_mm' = %g is not finite",
                        fn, encoder_mm);
        walk_cursor cursor;
        const double c = sim->centre_at(cursor, encoder_mm);
        const flt_sim::strip_view v0 = sim->view_of(0, encoder_mm, c),
                                  v1 = sim->view_of(1, encoder_mm, c);
        for (std::size_t k = 0; k < fibers; ++k) {
            const double x = sim->fiber_x[k];
            flags_out[k] = sim->on_strip(v0, x) && sim->on_strip(v1, x) ? 0 : FLT_FLAG_OFF_STRIP;
        }
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_rewind(flt_sim *sim) {
    const char *fn = "flt_sim_rewind";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        sim->frame = 0;
        sim->walk = walk_cursor();
        return FLT_OK;
    });
}

}  // extern "C"
