// SPDX-License-Identifier: Apache-2.0
// The leveler advisor (flatline/advisor.h) closing the loop on a simulated
// line: a hidden leveler (flatline/testing.h, flt_leveler_sim) with 8
// actuators shapes the strip; the simulator renders each 3 m sheet's
// profile rows with the sensor's noise, the reconstructor and the flatness
// metrics measure its 20-zone I-Unit profile, and the advisor proposes the
// next settings.
//
//   1. Identification: each actuator is stepped by its step limit and back,
//      one sheet at a time (16 steps), and G is identified from the logged
//      (setting change, profile change) pairs.
//   2. Three coils of 16 sheets each, each coil with another incoming
//      shape: after every sheet the advisor advises and the operator (this
//      program) applies the advice. The leveler is one sheet ahead of the
//      gauge.
//   3. The same three coils again with G known exactly, 30 % too small
//      (0.7 G) and 30 % too large (1.3 G), without identification.
//
// It prints, per coil, the sheets it took until the largest zone I-Units
// stayed within the tolerance, and writes advisor_loop.png (the zone
// profile of every sheet, the largest zone I-Units per sheet, the
// settings).
//
//   advisor_loop [output directory]     (default: the current directory)
//
// It exits with 1 when a coil never stays within the tolerance.
#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flatline/flatline.h"
#include "flatline/testing.h"

namespace {

constexpr double k_pi = 3.14159265358979323846;
constexpr std::size_t k_zones = 20, k_actuators = 8;
constexpr double k_zone_width = 100.0;                // mm; fibers -999 .. 999 every 2 mm: 20 zones
constexpr double k_sheet = 3000.0, k_period = 500.0;  // mm
constexpr double k_noise = 0.3;                       // I-Units per zone, sheet to sheet
// The tolerance: a sheet is flat enough when its largest zone I-Units (the
// flatness reading, relative to its shortest zone) is at most 5 I-Units.
constexpr double k_tolerance = 5.0;
constexpr int k_coils = 3, k_coil_sheets = 16;

void check(flt_status st, const char *what) {
    if (st != FLT_OK) {
        std::fprintf(stderr, "%s: %s\n", what, flt_last_error_message());
        std::exit(1);
    }
}

struct actuator_def {
    const char *name;
    double min, max, step;
};
const actuator_def k_act[k_actuators] = {
    {"entry gap", -2, 2, 0.5},    {"exit gap", -2, 2, 0.5},     {"tilt", -2, 2, 0.4},
    {"flight 1", -1.5, 1.5, 0.3}, {"flight 2", -1.5, 1.5, 0.3}, {"flight 3", -1.5, 1.5, 0.3},
    {"flight 4", -1.5, 1.5, 0.3}, {"flight 5", -1.5, 1.5, 0.3},
};

double zone_u(std::size_t z) {  // -1 .. 1 across the width
    return ((double(z) + 0.5) / double(k_zones)) * 2.0 - 1.0;
}

// The true leveler: I-Units per mm of each actuator, per zone.
std::vector<double> true_g() {
    std::vector<double> g(k_zones * k_actuators);
    const double centres[5] = {-0.8, -0.4, 0.0, 0.4, 0.8};
    for (std::size_t z = 0; z < k_zones; ++z) {
        const double u = zone_u(z);
        double *row = &g[z * k_actuators];
        row[0] = 12.0 * u * u;         // entry gap: edges against centre
        row[1] = 6.0 * u * u * u * u;  // exit gap: the edges mostly
        row[2] = 10.0 * u;             // tilt: drive side against operator side
        for (int f = 0; f < 5; ++f)
            row[3 + f] = 15.0 * std::exp(-std::pow((u - centres[f]) / 0.25, 2));
    }
    return g;
}

// The incoming shape of coil c (I-Units with every setting at 0).
std::vector<double> incoming(int c) {
    std::vector<double> e(k_zones);
    for (std::size_t z = 0; z < k_zones; ++z) {
        const double u = zone_u(z);
        const double buckle = std::pow(std::cos(k_pi * u / 2), 2);
        const double right = std::pow(std::max(0.0, u), 4), left = std::pow(std::max(0.0, -u), 4);
        // a little the actuators cannot reach (a short wave across)
        const double rest = 0.8 * std::cos(5 * k_pi * u);
        if (c == 0)
            e[z] = 25 * buckle + 15 * right + rest;
        else if (c == 1)
            e[z] = 20 * (left + right) + 6 * u + rest;
        else
            e[z] = 15 * std::exp(-std::pow((std::fabs(u) - 0.4) / 0.25, 2)) + 8 * left + rest;
    }
    return e;
}

struct line {
    flt_sim *sim = nullptr;
    flt_flatness *flat = nullptr;
    flt_options *recon = nullptr;
    flt_leveler_sim *leveler = nullptr;
    std::size_t fibers = 0;
    double s0 = 0;  // where the next sheet starts
    std::vector<double> s, height, slope, z;
    std::vector<uint8_t> valid, flags;

    explicit line(std::uint64_t seed) {
        flt_calib *calib = nullptr;
        check(flt_calib_create_reference(0, 2048, -999.0, 2.0, 1000, &calib), "calibration");
        flt_options *o = nullptr;
        check(flt_options_create(&o), "options");
        check(flt_options_set(o, FLT_OPT_SIM_SEED, double(seed)), "sim_seed");
        check(flt_sim_create(calib, o, &sim), "simulator");
        flt_options_destroy(o);
        check(flt_sim_fibers(sim, &fibers), "fibers");
        check(flt_options_create(&o), "options");
        check(flt_options_set(o, FLT_OPT_FLAT_ZONE_WIDTH, k_zone_width), "flat_zone_width");
        check(flt_flatness_create_from_calib(calib, o, &flat), "flatness");
        flt_options_destroy(o);
        flt_calib_destroy(calib);
        std::size_t zones = 0;
        check(flt_flatness_zones(flat, &zones), "zones");
        if (zones != k_zones) {
            std::fprintf(stderr, "the flatness layout has %zu zones, not %zu\n", zones, k_zones);
            std::exit(1);
        }
        std::vector<double> centres(zones);
        check(flt_flatness_zone_layout(flat, zones, nullptr, centres.data(), nullptr),
              "zone layout");
        const std::vector<double> g = true_g(), e0 = incoming(0);
        check(flt_leveler_sim_create(k_zones, k_actuators, centres[0], k_zone_width, g.data(),
                                     g.size(), e0.data(), e0.size(), k_noise, seed, &leveler),
              "leveler");
        check(flt_options_create(&recon), "options");
        // Rows come every 3 mm (sim_frame_spacing); s of row 0 is 0.
        const std::size_t rows = std::size_t(k_sheet / 3.0);
        s.resize(rows);
        height.resize(rows * fibers);
        slope.resize(rows * fibers);
        z.resize(rows * fibers);
        valid.resize(rows * fibers);
        flags.resize(rows * fibers);
    }
    ~line() {
        flt_leveler_sim_destroy(leveler);
        flt_options_destroy(recon);
        flt_flatness_destroy(flat);
        flt_sim_destroy(sim);
    }

    // Levels, renders, reconstructs and measures the next sheet: its zone
    // profile (I-Units) and the settings it went through.
    void next_sheet(double *profile, double *settings) {
        check(flt_leveler_sim_next_sheet(leveler, sim, s0, k_sheet, k_period, nullptr, 0, settings,
                                         k_actuators),
              "next sheet");
        const std::size_t rows = s.size();
        check(flt_sim_next_rows(sim, rows, fibers, nullptr, s.data(), height.data(), slope.data(),
                                valid.data(), nullptr),
              "rows");
        check(flt_reconstruct(recon, rows, fibers, s.data(), height.data(), slope.data(),
                              valid.data(), z.data(), flags.data()),
              "reconstruction");
        // The lasers read 50 mm either side of a row: the first and last
        // rows of a sheet see its neighbours. Measure between them.
        std::size_t first = 0, last = rows;
        while (first < rows && s[first] < s0 + 100)
            ++first;
        while (last > first && s[last - 1] > s0 + k_sheet - 100)
            --last;
        check(flt_flatness_evaluate(flat, last - first, fibers, &s[first], &z[first * fibers],
                                    &flags[first * fibers]),
              "flatness");
        check(flt_flatness_zone_results(flat, k_zones, profile, nullptr), "zone profile");
        s0 += k_sheet;
    }
};

flt_advisor *make_advisor() {
    flt_advisor *a = nullptr;
    check(flt_advisor_create(k_zones, k_actuators, nullptr, &a), "advisor");
    for (std::size_t j = 0; j < k_actuators; ++j)
        check(flt_advisor_set_actuator(a, j, k_act[j].name, "mm", k_act[j].min, k_act[j].max,
                                       k_act[j].step),
              "actuator");
    return a;
}

double largest(const double *p) {
    double lo = p[0], hi = p[0];
    for (std::size_t z = 1; z < k_zones; ++z) {
        lo = std::min(lo, p[z]);
        hi = std::max(hi, p[z]);
    }
    return hi - lo;
}

struct run_result {
    std::vector<std::vector<double>> profiles, settings;  // per sheet
    std::vector<double> peak;                             // largest zone I-Units per sheet
    std::vector<int> coil_start;
    int identification_sheets = 0;
    double r2 = NAN, rms = NAN;
    std::vector<int> sheets_to_tolerance;  // per coil; -1: never
};

// Sheets from the coil's first until the largest zone I-Units stay within
// the tolerance for the rest of the coil; -1 if they never do.
int settle(const std::vector<double> &peak, int from, int to) {
    int last_out = from - 1;
    for (int k = from; k < to; ++k)
        if (peak[std::size_t(k)] > k_tolerance)
            last_out = k;
    return last_out + 1 < to ? last_out + 1 - from + 1 : -1;
}

// scale > 0: G = scale * true G (rotated by `rotate` radians between
// neighbouring flights' columns); scale = 0: identify G first.
run_result run(double scale, double rotate, std::uint64_t seed, bool progress) {
    line ln(seed);
    flt_advisor *adv = make_advisor();
    run_result out;
    std::vector<double> u_now(k_actuators, 0.0), p(k_zones), u_sheet(k_actuators);
    auto record = [&] {
        out.profiles.push_back(p);
        out.settings.push_back(u_sheet);
        out.peak.push_back(largest(p.data()));
    };
    if (scale > 0) {
        std::vector<double> g = true_g();
        for (std::size_t z = 0; z < k_zones; ++z) {
            double *row = &g[z * k_actuators];
            for (int f = 0; f + 1 < 5; f += 2) {  // mix pairs of flight columns
                const double a = row[3 + f], b = row[4 + f];
                row[3 + f] = std::cos(rotate) * a - std::sin(rotate) * b;
                row[4 + f] = std::sin(rotate) * a + std::cos(rotate) * b;
            }
            for (std::size_t j = 0; j < k_actuators; ++j)
                row[j] *= scale;
        }
        check(flt_advisor_set_influence(adv, g.data(), g.size()), "set G");
    } else {
        // Identification: step each actuator by its step limit and back.
        std::vector<double> du, dp, prev_p, prev_u;
        const int steps = int(2 * k_actuators) + 2;  // + 2: the delay
        for (int k = 0; k < steps; ++k) {
            ln.next_sheet(p.data(), u_sheet.data());
            record();
            if (k > 0) {
                bool moved = false;
                for (std::size_t j = 0; j < k_actuators; ++j)
                    moved = moved || u_sheet[j] != prev_u[j];
                if (moved) {
                    for (std::size_t j = 0; j < k_actuators; ++j)
                        du.push_back(u_sheet[j] - prev_u[j]);
                    for (std::size_t z = 0; z < k_zones; ++z)
                        dp.push_back(p[z] - prev_p[z]);
                }
            }
            prev_p = p;
            prev_u = u_sheet;
            std::fill(u_now.begin(), u_now.end(), 0.0);
            if (k < int(2 * k_actuators) && k % 2 == 0)
                u_now[std::size_t(k / 2)] = k_act[k / 2].step;
            check(flt_leveler_sim_set_settings(ln.leveler, u_now.data(), k_actuators), "settings");
        }
        out.identification_sheets = steps;
        const std::size_t n = du.size() / k_actuators;
        check(flt_advisor_identify(adv, n, du.data(), du.size(), dp.data(), dp.size(), 1e-3),
              "identification");
        std::size_t used = 0;
        check(flt_advisor_fit(adv, &out.r2, &out.rms, &used), "fit");
        if (progress)
            std::printf("identified G from %zu steps over %d sheets: R^2 = %.3f, RMS residual "
                        "%.2f I-Units\n",
                        used, steps, out.r2, out.rms);
    }
    for (int c = 0; c < k_coils; ++c) {
        const std::vector<double> e0 = incoming(c);
        check(flt_leveler_sim_set_incoming(ln.leveler, e0.data(), e0.size()), "coil");
        out.coil_start.push_back(int(out.peak.size()));
        for (int k = 0; k < k_coil_sheets; ++k) {
            ln.next_sheet(p.data(), u_sheet.data());
            record();
            std::vector<double> d(k_actuators);
            double confidence = 0;
            check(flt_advisor_advise(adv, p.data(), k_zones, u_sheet.data(), k_actuators,
                                     u_now.data(), k_actuators, d.data(), k_actuators, nullptr, 0,
                                     &confidence),
                  "advice");
            for (std::size_t j = 0; j < k_actuators; ++j)
                u_now[j] += d[j];
            check(flt_leveler_sim_set_settings(ln.leveler, u_now.data(), k_actuators), "settings");
            if (progress) {
                std::printf("\r  coil %d sheet %2d: largest zone %5.1f I-Units, confidence %.2f",
                            c + 1, k + 1, out.peak.back(), confidence);
                std::fflush(stdout);
            }
        }
        const int from = out.coil_start.back();
        out.sheets_to_tolerance.push_back(settle(out.peak, from, int(out.peak.size())));
        if (progress)
            std::printf("\n");
    }
    flt_advisor_destroy(adv);
    return out;
}

// ---------------------------------------------------------------- the plot

void text(cv::Mat &img, const std::string &s, cv::Point at, double scale = 0.45) {
    cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
}

std::string fmt(const char *f, ...) {
    char buf[256];
    va_list a;
    va_start(a, f);
    std::vsnprintf(buf, sizeof buf, f, a);
    va_end(a);
    return buf;
}

cv::Scalar colour(double t) {  // 0 .. 1: red -> blue
    return cv::Scalar(255 * t, 60, 255 * (1 - t));
}

void plot(const std::string &path, const run_result &r, const std::vector<run_result> &others,
          const char *const *other_names) {
    const int W = 1400, H = 1000;
    cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
    text(img,
         "Leveler advisor in a closed loop (simulated leveler, 8 actuators, 20 zones, 3 m sheets)",
         {20, 28}, 0.6);
    // Panel 1: the largest zone I-Units per sheet, every run.
    const int l1 = 70, t1 = 60, w1 = 1300, h1 = 280;
    const std::size_t sheets = r.peak.size();
    double ymax = 0;
    for (double v : r.peak)
        ymax = std::max(ymax, v);
    ymax = std::ceil(ymax / 10) * 10;
    auto X = [&](double k) {
        return l1 + int(w1 * k / double(sheets - 1));
    };
    auto Y = [&](double v) {
        return t1 + h1 - int(h1 * std::min(v, ymax) / ymax);
    };
    cv::rectangle(img, {l1, t1}, {l1 + w1, t1 + h1}, cv::Scalar(0, 0, 0));
    for (double v = 0; v <= ymax; v += 10) {
        cv::line(img, {l1, Y(v)}, {l1 + w1, Y(v)}, cv::Scalar(225, 225, 225));
        text(img, fmt("%.0f", v), {l1 - 30, Y(v) + 5});
    }
    cv::line(img, {l1, Y(k_tolerance)}, {l1 + w1, Y(k_tolerance)}, cv::Scalar(0, 160, 0), 1);
    text(img, fmt("tolerance %.0f I-Units", k_tolerance), {l1 + 5, Y(k_tolerance) - 4});
    for (std::size_t c = 0; c < r.coil_start.size(); ++c) {
        const int x = X(r.coil_start[c]);
        cv::line(img, {x, t1}, {x, t1 + h1}, cv::Scalar(120, 120, 120), 1);
        text(img, fmt("coil %zu", c + 1), {x + 4, t1 + 15});
    }
    if (r.identification_sheets)
        text(img, "identification steps", {l1 + 4, t1 + 15});
    const cv::Scalar run_colours[5] = {cv::Scalar(0, 0, 0), cv::Scalar(200, 120, 0),
                                       cv::Scalar(0, 0, 220), cv::Scalar(0, 150, 0),
                                       cv::Scalar(200, 0, 200)};
    auto draw_series = [&](const run_result &run, std::size_t offset, cv::Scalar col) {
        for (std::size_t k = 1; k < run.peak.size(); ++k)
            cv::line(img, {X(double(k - 1 + offset)), Y(run.peak[k - 1])},
                     {X(double(k + offset)), Y(run.peak[k])}, col, 2, cv::LINE_AA);
    };
    draw_series(r, 0, run_colours[0]);
    for (std::size_t i = 0; i < others.size(); ++i)
        draw_series(others[i], std::size_t(r.identification_sheets), run_colours[1 + i]);
    // The legend, on white, where coil 1 has already settled.
    const int lx = X(r.coil_start.empty() ? 0 : r.coil_start[0]) + 110;
    int ly = t1 + 40;
    cv::rectangle(img, {lx - 10, ly - 18}, {lx + 170, ly + 18 * int(others.size()) + 8},
                  cv::Scalar(255, 255, 255), cv::FILLED);
    cv::rectangle(img, {lx - 10, ly - 18}, {lx + 170, ly + 18 * int(others.size()) + 8},
                  cv::Scalar(160, 160, 160));
    text(img, "identified G", {lx + 40, ly});
    cv::line(img, {lx, ly - 5}, {lx + 30, ly - 5}, run_colours[0], 2);
    for (std::size_t i = 0; i < others.size(); ++i) {
        ly += 18;
        text(img, other_names[i], {lx + 40, ly});
        cv::line(img, {lx, ly - 5}, {lx + 30, ly - 5}, run_colours[1 + i], 2);
    }
    text(img, "largest zone I-Units per sheet (flatness reading relative to the shortest zone)",
         {l1, t1 + h1 + 20});

    // Panel 2: the zone profiles of the identified run's sheets, coloured
    // by sheet within each coil (red: first sheet, blue: last).
    const int t2 = 400, h2 = 250, w2 = 410;
    for (std::size_t c = 0; c < r.coil_start.size(); ++c) {
        const int l2 = 70 + int(c) * 445;
        cv::rectangle(img, {l2, t2}, {l2 + w2, t2 + h2}, cv::Scalar(0, 0, 0));
        const int from = r.coil_start[c];
        const int to = c + 1 < r.coil_start.size() ? r.coil_start[c + 1] : int(sheets);
        double pmax = 0;
        for (int k = from; k < to; ++k)
            for (double v : r.profiles[std::size_t(k)])
                pmax = std::max(pmax, v);
        pmax = std::max(10.0, std::ceil(pmax / 10) * 10);
        auto PX = [&](double z) {
            return l2 + int(w2 * (z + 0.5) / double(k_zones));
        };
        auto PY = [&](double v) {
            return t2 + h2 - int(h2 * v / pmax);
        };
        for (int k = from; k < to; ++k) {
            const auto &pr = r.profiles[std::size_t(k)];
            const cv::Scalar col = colour(double(k - from) / double(std::max(1, to - from - 1)));
            for (std::size_t z = 1; z < k_zones; ++z)
                cv::line(img, {PX(double(z - 1)), PY(pr[z - 1])}, {PX(double(z)), PY(pr[z])}, col,
                         1, cv::LINE_AA);
        }
        text(img, fmt("coil %zu: zone profile per sheet (0 .. %.0f I-Units)", c + 1, pmax),
             {l2, t2 - 8});
        text(img, "zone 1 .. 20 across the width; red first, blue last sheet", {l2, t2 + h2 + 18},
             0.4);
    }

    // Panel 3: the settings of the identified run.
    const int l3 = 70, t3 = 720, w3 = 1300, h3 = 230;
    cv::rectangle(img, {l3, t3}, {l3 + w3, t3 + h3}, cv::Scalar(0, 0, 0));
    auto SX = [&](double k) {
        return l3 + int(w3 * k / double(sheets - 1));
    };
    auto SY = [&](double v) {
        return t3 + h3 / 2 - int(h3 / 2 * v / 2.0);
    };
    for (double v = -2; v <= 2; v += 1) {
        cv::line(img, {l3, SY(v)}, {l3 + w3, SY(v)}, cv::Scalar(225, 225, 225));
        text(img, fmt("%+.0f", v), {l3 - 30, SY(v) + 5});
    }
    for (std::size_t j = 0; j < k_actuators; ++j) {
        const cv::Scalar palette[k_actuators] = {cv::Scalar(0, 0, 0),     cv::Scalar(128, 128, 128),
                                                 cv::Scalar(0, 140, 255), cv::Scalar(0, 0, 220),
                                                 cv::Scalar(0, 160, 0),   cv::Scalar(220, 120, 0),
                                                 cv::Scalar(200, 0, 200), cv::Scalar(140, 70, 20)};
        const cv::Scalar col = palette[j];
        for (std::size_t k = 1; k < sheets; ++k)
            cv::line(img, {SX(double(k - 1)), SY(r.settings[k - 1][j])},
                     {SX(double(k)), SY(r.settings[k][j])}, col, 2, cv::LINE_AA);
        text(img, k_act[j].name, {l3 + 10 + int(j) * 130, t3 + h3 + 20});
        cv::line(img, {l3 + int(j) * 130 - 15, t3 + h3 + 15}, {l3 + int(j) * 130 + 5, t3 + h3 + 15},
                 col, 2);
    }
    text(img, "actuator settings (mm) of each sheet, identified G", {l3, t3 - 8});
    if (!cv::imwrite(path, img)) {
        std::fprintf(stderr, "cannot write %s\n", path.c_str());
        std::exit(1);
    }
}

void report(const char *name, const run_result &r) {
    std::printf("  %-14s sheets to stay within %.0f I-Units, per coil:", name, k_tolerance);
    for (int n : r.sheets_to_tolerance)
        std::printf(n < 0 ? "  never" : "  %d", n);
    double worst_end = 0;
    for (std::size_t c = 0; c < r.coil_start.size(); ++c) {
        const std::size_t end =
            c + 1 < r.coil_start.size() ? std::size_t(r.coil_start[c + 1]) : r.peak.size();
        worst_end = std::max(worst_end, r.peak[end - 1]);
    }
    std::printf("   (last sheets at most %.1f I-Units)\n", worst_end);
}

}  // namespace

int main(int argc, char **argv) {
    const std::string dir = argc > 1 ? argv[1] : ".";
    std::printf("advisor_loop: %zu zones, %zu actuators, %.0f mm sheets, noise %.1f I-Units per "
                "zone, the leveler one sheet ahead of the gauge\n",
                k_zones, k_actuators, k_sheet, k_noise);
    const run_result identified = run(0, 0, 1, true);
    std::printf("with G exact, 0.7 G, 1.3 G and 1.3 G with flight columns mixed by 0.3 rad:\n");
    const char *names[] = {"G exact", "0.7 G", "1.3 G", "1.3 G rotated"};
    std::vector<run_result> others = {run(1.0, 0, 1, false), run(0.7, 0, 1, false),
                                      run(1.3, 0, 1, false), run(1.3, 0.3, 1, false)};
    std::printf("results:\n");
    report("identified G", identified);
    for (std::size_t i = 0; i < others.size(); ++i)
        report(names[i], others[i]);
    const std::string path = dir + "/advisor_loop.png";
    plot(path, identified, others, names);
    std::printf("wrote %s\n", path.c_str());
    // A run that never settles within the tolerance is a failure (the
    // example runs as a test).
    int never = 0;
    for (int n : identified.sheets_to_tolerance)
        never += n < 0;
    for (const run_result &o : others)
        for (int n : o.sheets_to_tolerance)
            never += n < 0;
    if (never) {
        std::fprintf(stderr, "%d coil(s) never stayed within %.0f I-Units\n", never, k_tolerance);
        return 1;
    }
    return 0;
}
