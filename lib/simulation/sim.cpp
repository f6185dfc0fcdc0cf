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

#include "core/error.hpp"
#include "core/options.hpp"
#include "flatline/sim.h"
#include "simulation/sim_random.hpp"

using namespace flt;

namespace {

constexpr std::uint32_t k_sim_magic = 0x464c5453u;  // "FLTS"
constexpr std::size_t k_max_defects = 64;
constexpr double k_pi = 3.14159265358979323846;
constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();

// Random streams of one frame (see sim_random.hpp).
enum stream : std::uint64_t {
    stream_motion = 1,
    stream_row_noise = 2,
    stream_peak_noise = 3,
    stream_pixels = 4,
    stream_reflections = 5
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
    return p;
}

void check(flt_status st) {
    if (st != FLT_OK)
        throw error(st, flt_last_error_message());
}

// A private copy of a finished calibration (through its text form, so the
// simulator never depends on the caller's handle staying alive).
flt_calib *copy_calib(const flt_calib *calib) {
    std::size_t length = 0;
    flt_status st = flt_calib_save_text(calib, nullptr, 0, &length);
    if (st != FLT_OK && st != FLT_ERR_BUFFER_FULL)
        check(st);
    std::string text(length + 1, '\0');
    check(flt_calib_save_text(calib, text.data(), text.size(), &length));
    flt_calib *copy = nullptr;
    check(flt_calib_load_text(text.data(), length, &copy));
    clear_error();  // the size query above left a BUFFER_FULL message
    return copy;
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

    ~flt_sim() { flt_calib_destroy(calib); }

    double full_scale() const { return double((1u << params.bit_depth) - 1u); }

    double sheet(double x, double s) const {
        const double half = 0.5 * params.strip_width;
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
                    const double c = std::cos(k_pi * xc / params.strip_width);
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
                    const double a =
                        (std::fabs(xc) - 0.25 * params.strip_width) / (0.125 * params.strip_width);
                    g = std::exp(-a * a);
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
            const double w = d.period_mm > 0 ? std::sin(2 * k_pi * s / d.period_mm) : 1.0;
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
            z += p.shear_amplitude * std::exp(-p.shear_decay * d) *
                 std::sin(2 * k_pi * d / p.shear_period);
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
            params.ecc_amplitude * std::sin(2 * k_pi * encoder_of(f) / params.ecc_period);
        return m;
    }

    // What laser L sees at x in frame f (mm), before peak noise.
    double laser_z(unsigned laser, double e, const motion &m, double x) const {
        const double s = e - offset_mm[laser];
        return sheet(x, s) + shear(s) + m.heave + m.tilt * x + m.eccentricity;
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
            if (encoder_out)
                encoder_out[r] = e;
            s_out[r] = s_row;
            for (std::size_t k = 0; k < n; ++k) {
                const double x = fiber_x[k];
                double z[2];
                for (unsigned laser = 0; laser < 2; ++laser) {
                    z[laser] = laser_z(laser, e, m, x);
                    if (params.peak_sigma_px > 0)
                        z[laser] += params.peak_sigma_px * dz_dv[laser][k] * rng.gauss();
                }
                height_out[r * n + k] = 0.5 * (z[0] + z[1]);
                slope[r * n + k] = (z[ahead] - z[behind]) / laser_spacing;
                if (valid)
                    valid[r * n + k] = 1;
                if (truth)
                    truth[r * n + k] = sheet(x, s_row);
            }
        }
    }

    // Each column's line centre row for both lasers in frame f.
    void line_centres(std::uint64_t f) {
        const double e = encoder_of(f);
        const motion m = motion_of(f);
        sim_rng rng(params.seed, f, stream_peak_noise);
        for (unsigned laser = 0; laser < 2; ++laser) {
            const std::size_t ns = samples[laser];
            for (std::size_t i = 0; i < ns; ++i) {
                const double x = x_lo[laser] + double(i) * x_step[laser];
                plane_points[2 * i] = x;
                plane_points[2 * i + 1] = laser_z(laser, e, m, x);
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
            for (std::uint32_t u = 0; u < width; ++u) {
                while (j + 2 < ns && !(u_at(j + 1) >= double(u)))
                    ++j;
                const double u0 = u_at(j), u1 = u_at(j + 1);
                double v = k_nan;
                if (u0 <= double(u) && double(u) <= u1 && u1 > u0) {
                    const double t = (double(u) - u0) / (u1 - u0);
                    v = v_at(j) + t * (v_at(j + 1) - v_at(j));
                }
                if (params.peak_sigma_px > 0)
                    v += params.peak_sigma_px * rng.gauss();
                if (!(v >= 0 && v <= double(height - 1)))
                    v = k_nan;
                centre[u] = v;
            }
        }
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
                float(amplitude * std::exp(d * d * inv)) * speckle;
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
                const double envelope = std::cos(0.5 * k_pi * t);
                add_ridge(std::uint32_t(u), v0 + slant * (double(u) - u0), sigma,
                          amplitude * envelope * envelope, pixel_rng);
            }
        }
    }

    template <class Pixel> void quantise(void *frame_out, std::size_t stride, sim_rng &rng) const {
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
        for (std::uint32_t v = 0; v < height; ++v) {
            Pixel *row = reinterpret_cast<Pixel *>(static_cast<unsigned char *>(frame_out) +
                                                   std::size_t(v) * stride);
            const float *in = &intensity[std::size_t(v) * width];
            for (std::uint32_t u = 0; u < width; ++u) {
                float value = in[u];
                if (gain > 0)
                    value += std::sqrt(std::max(value, 0.0f) * gain) * rng.fast_gauss();
                value += 0.5f;
                value = value > 0.0f ? (value < top ? value : top) : 0.0f;  // NaN: 0
                row[u] = Pixel(value);
            }
        }
    }

    void render(std::uint64_t f, void *frame_out, std::size_t stride) {
        line_centres(f);
        const double fs = full_scale();
        std::fill(intensity.begin(), intensity.end(), float(params.background * fs));
        sim_rng rng(params.seed, f, stream_pixels);
        const double amplitude = params.line_peak * fs;
        for (unsigned laser = 0; laser < 2; ++laser)
            for (std::uint32_t u = 0; u < width; ++u)
                add_ridge(u, centre_row[laser][u], params.line_sigma_px, amplitude, rng);
        if (params.reflections > 0)
            add_reflections(f, amplitude, rng);
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
    }
    const std::size_t ns = std::max(sim.samples[0], sim.samples[1]);
    sim.plane_points.assign(2 * ns, 0);
    sim.image_points.assign(2 * ns, 0);
    sim.intensity.assign(std::size_t(sim.width) * sim.height, 0.0f);
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
        for (std::size_t i = 0; i < count; ++i)
            z_out[i] = sim->sheet(x[i], s[i]);
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
            const double s_row = sim->row_position(e);
            for (std::size_t k = 0; k < fibers; ++k)
                truth_out[k] = sim->sheet(sim->fiber_x[k], s_row);
        }
        if (peak_rows_out)
            for (unsigned laser = 0; laser < 2; ++laser)
                std::memcpy(peak_rows_out + std::size_t(laser) * sim->width,
                            sim->centre_row[laser].data(), sim->width * sizeof(double));
        ++sim->frame;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_sim_rewind(flt_sim *sim) {
    const char *fn = "flt_sim_rewind";
    return guard(fn, [&] {
        if (flt_status st = check_handle(fn, sim))
            return st;
        sim->frame = 0;
        return FLT_OK;
    });
}

}  // extern "C"
