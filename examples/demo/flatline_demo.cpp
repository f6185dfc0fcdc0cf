// SPDX-License-Identifier: Apache-2.0
/*
 * The simulated line, end to end, on the gauge: camera frames and the
 * shear's cuts in, measured sheets out.
 *
 * A strip with a centre buckle and wavy edges (the reference's defects)
 * passes under the reference sensor (two lasers 100 mm apart, a 2048-column
 * camera read out over rows 892..1147, a frame every 3 mm). The strip bounces
 * (rigid heave), a leveler roll's eccentricity adds a 50 mm ripple, the
 * shear station rings after every cut (every 3000 mm), and the peak detector
 * adds 1/16 px per laser. The simulator renders every camera frame; one
 * flt_gauge turns them into sheets: its workers extract profile rows, the
 * reconstructor streams the strip's shape on across the cuts, and each
 * sheet's shape becomes I-Units, a shape class, bow and crossbow. The
 * pipeline is the block under "the gauge" in main(): what a vendor writes.
 *
 * It prints progress, then a summary: sheets, real-time factor at the line
 * speed (library time only: rendering frames is the simulator's work, a real
 * line gets them from the camera), accuracy against the ground truth, and per
 * sheet its class and zone profile. The report directory gets PNG height
 * maps (raw and reconstructed, with a colour scale), one fiber's profile, the
 * zone profiles as bar charts, and CSV and JSON files.
 *
 * The quality record (flatline/record.h, docs/record.md): the strip is one
 * coil with its identity (--coil); the gauge judges its sheets against a
 * rule file (--rules), records its rows (--record FILE) and archives every
 * sheet (--archive FILE, an SQLite file or a PostgreSQL connection
 * string). A recording is replayed at the end through a second gauge with
 * the recording's options, and its sheets are compared with the live ones
 * value for value. sheets.csv and report.json name the coil and give each
 * sheet's verdict as the gauge judged it ("none" without --rules); coil.png
 * is the coil on one page: its identity, a run chart per rule (each
 * sheet's worst value and the rule's limit; without rules the largest
 * zone I-Units and the flat limit), the disposition per run of sheets with
 * the same verdict and the sign-off. The full coil report is printed from
 * the archive by `python -m flatline.report ARCHIVE --out DIR`.
 *
 * Run with --help for the options.
 */
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include <sys/stat.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <flatline/flatline.h>

namespace {

constexpr uint32_t k_roi_first = 892, k_roi_rows = 256;  // both lines, +-50 mm
constexpr uint32_t k_camera_width = 2048;
constexpr double k_frame_spacing = 3.0;  // mm of strip between frames

struct settings {
    int sheets = 3;
    double sheet_length = 3000.0;  // mm
    double width = 1500.0;         // mm, strip width (fibers cover it)
    double pitch = 2.0;            // mm between fibers
    double speed = 120.0;          // m/min
    double centre_buckle = 6.0;    // mm amplitude (half peak to peak)
    double wavy_edges = 6.0;       // mm amplitude
    double quarter_buckle = 0.0;   // mm amplitude
    double period = 1800.0;        // mm along travel
    double vibration = 2.5;        // mm rigid heave sigma
    double eccentricity = 0.5;     // mm
    double shear = 5.0;            // mm initial envelope
    double peak_noise = 1.0 / 16;  // px
    unsigned seed = 1;
    std::string out = "flatline_report";
    std::string coil = "DEMO-1";  // the coil's id
    double thickness = 3.0;       // mm, the coil's nominal thickness
    std::string rules;            // rule file, or none
    std::string record;           // recording to write, or none
    std::string archive;          // archive to write, or none
};

void usage() {
    std::printf(
        "flatline_demo: the simulated line end to end (frames -> extractor -> streaming\n"
        "reconstructor -> flatness), with a report directory of pictures, CSV and JSON.\n\n"
        "  --sheets N            sheets to run (default 3)\n"
        "  --sheet-length MM     sheet length along travel (default 3000; sheets are cut\n"
        "                        where the shear station cuts, every 3000 mm)\n"
        "  --width MM            strip width, covered by fibers (default 1500)\n"
        "  --pitch MM            fiber pitch across the width (default 2)\n"
        "  --speed M_PER_MIN     line speed for the real-time factor (default 120)\n"
        "  --centre-buckle MM    centre buckle amplitude, half peak to peak (default 6)\n"
        "  --wavy-edges MM       wavy edges amplitude, both edges (default 6)\n"
        "  --quarter-buckle MM   quarter buckle amplitude (default 0)\n"
        "  --period MM           defect period along travel (default 1800)\n"
        "  --vibration MM        rigid heave of the strip per frame, sigma (default 2.5)\n"
        "  --eccentricity MM     roll eccentricity amplitude at 50 mm period (default 0.5)\n"
        "  --shear MM            shear-station ringing, initial envelope (default 5; the\n"
        "                        reference's 50 mm moves a line by 24 px, past the 48 px\n"
        "                        between the two lines of this sensor geometry)\n"
        "  --peak-noise PX       laser peak detection noise (default 0.0625 = 1/16 px)\n"
        "  --seed N              random seed (default 1)\n"
        "  --out DIR             report directory (default flatline_report)\n"
        "  --coil ID             the coil's id (default DEMO-1); its nominal width is\n"
        "                        --width and its nominal thickness --thickness\n"
        "  --thickness MM        the coil's nominal thickness (default 3)\n"
        "  --rules FILE          judge every sheet by this rule file (flatline-tolerances\n"
        "                        JSON; tools/coil_report/example_rules.json is an example)\n"
        "  --record FILE         record the gauge's rows (a new file), then replay it\n"
        "                        through a second gauge and compare the sheets\n"
        "  --archive LOCATION    archive every sheet: an SQLite file, or a PostgreSQL\n"
        "                        connection string (postgresql://... or pg:key=value);\n"
        "                        python -m flatline.report LOCATION prints the coil\n"
        "  --help                this text\n");
}

[[noreturn]] void die(const char *what) {
    std::fprintf(stderr, "flatline_demo: %s failed: %s (%s)\n", what, flt_last_error_message(),
                 flt_status_string(flt_last_error_status()));
    std::exit(1);
}
#define CHECK(call)       \
  do {                    \
    if ((call) != FLT_OK) \
      die(#call);         \
  } while (0)

// CPU seconds of this thread, and of the whole process (every thread).
double thread_cpu_s() {
    timespec t{};
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

double process_cpu_s() {
    timespec t{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return double(t.tv_sec) + 1e-9 * double(t.tv_nsec);
}

// One sheet's rows: positions, extractor heights (raw), reconstruction,
// ground truth, [rows * fibers].
struct sheet_data {
    std::vector<double> s, raw, z, truth;
    std::vector<uint8_t> flags;
    void clear() {
        s.clear();
        raw.clear();
        z.clear();
        truth.clear();
        flags.clear();
    }
};

struct sheet_result {
    int index;
    double s_first, s_last;
    flt_shape shape;
    double confidence, bow, crossbow;
    unsigned components;
    double rms_error, max_error;  // mm, after removing the sheet's mean level
    double zone_error;            // largest |I - I_true| over the zones
    std::vector<double> zone_i, zone_true;
    std::string coil_id;  // the coil the gauge says the sheet is of
    int verdict;          // flt_verdict_state (FLT_SHEET_VERDICT)
    int rules_failed;
    // Per rule of the gauge's rule set: the worst value the gauge found and
    // the limit of the band that applied (NaN where it did not judge).
    std::vector<double> rule_worst, rule_limit;
};

// The sheet's verdict as the reports write it.
const char *verdict_word(int verdict) {
    return verdict == FLT_VERDICT_PASS   ? "pass"
           : verdict == FLT_VERDICT_FAIL ? "fail"
                                         : "not judged";
}

// A text as one CSV field (RFC 4180: quoted, quotes doubled).
std::string csv_quoted(const std::string &in) {
    std::string out = "\"";
    for (const char c : in)
        out += c == '"' ? std::string("\"\"") : std::string(1, c);
    return out + "\"";
}

// A text as a JSON string's content (the coil id is the user's).
std::string json_escaped(const std::string &in) {
    std::string out;
    for (const char c : in) {
        if (c == '"' || c == '\\')
            out += '\\';
        if (static_cast<unsigned char>(c) < 0x20) {
            char u[8];
            std::snprintf(u, sizeof u, "\\u%04x", unsigned(c));
            out += u;
        } else {
            out += c;
        }
    }
    return out;
}

// ---------------------------------------------------------------- pictures

const cv::Scalar k_black(0, 0, 0), k_grey(150, 150, 150), k_white(255, 255, 255);

void text(cv::Mat &img, const std::string &s, cv::Point at, double scale = 0.5,
          cv::Scalar colour = k_black, int thickness = 1) {
    cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, thickness, cv::LINE_AA);
}

int text_width(const std::string &s, double scale = 0.5) {
    int base = 0;
    return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, scale, 1, &base).width;
}

std::string fmt(const char *f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

// A "nice" tick step for a span (1, 2 or 5 times a power of ten).
double tick_step(double span, int target) {
    const double raw = span / target, p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * p >= raw)
            return m * p;
    return 10 * p;
}

// Height map: x across the width to the right, s along travel downwards,
// colour = height (mm) on a symmetric scale, with axes and a colour bar.
void height_map_png(const std::string &path, const std::string &title, const sheet_data &d,
                    const std::vector<double> &values, const std::vector<double> &x,
                    double scale_mm) {
    const int fibers = int(x.size()), rows = int(d.s.size());
    const int left = 90, top = 50, right = 150, bottom = 70;
    // One pixel per fiber across, rows resampled so the picture keeps the
    // sheet's proportions (mm per pixel equal on both axes).
    const double mm_per_px = (x.back() - x.front()) / (fibers - 1);
    const int h = int((d.s.back() - d.s.front()) / mm_per_px) + 1;
    cv::Mat map(h, fibers, CV_8UC1), valid(h, fibers, CV_8UC1);
    int r = 0;
    for (int py = 0; py < h; ++py) {
        const double s = d.s.front() + py * mm_per_px;
        while (r + 1 < rows && d.s[r + 1] <= s)
            ++r;
        for (int k = 0; k < fibers; ++k) {
            const double v = values[size_t(r) * fibers + k];
            valid.at<uint8_t>(py, k) = std::isfinite(v);
            const double t = std::isfinite(v) ? (v + scale_mm) / (2 * scale_mm) : 0.5;
            map.at<uint8_t>(py, k) = uint8_t(std::lround(255 * std::clamp(t, 0.0, 1.0)));
        }
    }
    cv::Mat coloured;
    cv::applyColorMap(map, coloured, cv::COLORMAP_VIRIDIS);
    coloured.setTo(cv::Scalar(255, 255, 255), valid == 0);  // invalid: white
    cv::Mat img(h + top + bottom, fibers + left + right, CV_8UC3, k_white);
    coloured.copyTo(img(cv::Rect(left, top, fibers, h)));
    cv::rectangle(img, cv::Rect(left - 1, top - 1, fibers + 2, h + 2), k_black);
    text(img, title, {left, 30}, 0.6);
    // x ticks (mm)
    const double xs = tick_step(x.back() - x.front(), 6);
    for (double v = std::ceil(x.front() / xs) * xs; v <= x.back(); v += xs) {
        const int px = left + int(std::lround((v - x.front()) / mm_per_px));
        cv::line(img, {px, top + h}, {px, top + h + 5}, k_black);
        const std::string l = fmt("%.0f", v);
        text(img, l, {px - text_width(l) / 2, top + h + 22});
    }
    text(img, "x across the width (mm)", {left + fibers / 2 - 90, top + h + 50});
    // s ticks (m)
    const double ss = tick_step(d.s.back() - d.s.front(), 6);
    for (double v = std::ceil(d.s.front() / ss) * ss; v <= d.s.back(); v += ss) {
        const int py = top + int(std::lround((v - d.s.front()) / mm_per_px));
        cv::line(img, {left - 5, py}, {left, py}, k_black);
        const std::string l = fmt("%.1f", v / 1000);
        text(img, l, {left - 10 - text_width(l), py + 5});
    }
    cv::Mat label(20, 200, CV_8UC3, k_white);
    text(label, "s along travel (m)", {5, 15});
    cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
    if (h > 200)
        label.copyTo(img(cv::Rect(15, top + h / 2 - 100, 20, 200)));
    // colour bar
    const int bx = left + fibers + 30, bw = 25;
    for (int py = 0; py < h; ++py) {
        cv::Mat px(1, 1, CV_8UC1, cv::Scalar(255 - 255 * py / std::max(1, h - 1)));
        cv::Mat c;
        cv::applyColorMap(px, c, cv::COLORMAP_VIRIDIS);
        cv::line(img, {bx, top + py}, {bx + bw, top + py}, c.at<cv::Vec3b>(0, 0));
    }
    cv::rectangle(img, cv::Rect(bx, top, bw, h), k_black);
    const double zs = tick_step(2 * scale_mm, 8);
    for (double v = std::ceil(-scale_mm / zs) * zs; v <= scale_mm + 1e-9; v += zs) {
        const int py = top + int(std::lround((scale_mm - v) / (2 * scale_mm) * (h - 1)));
        cv::line(img, {bx + bw, py}, {bx + bw + 5, py}, k_black);
        text(img, fmt("%+.0f", v), {bx + bw + 8, py + 5});
    }
    text(img, "z (mm)", {bx - 5, top - 10});
    if (!cv::imwrite(path, img))
        std::fprintf(stderr, "could not write %s\n", path.c_str());
}

struct series {
    std::string name;
    std::vector<double> x, y;
    cv::Scalar colour;
    int thickness;
};

// A line plot with axes, ticks, grid and a legend.
void line_plot_png(const std::string &path, const std::string &title, const std::string &xlabel,
                   const std::string &ylabel, const std::vector<series> &all) {
    const int W = 1100, H = 520, left = 80, right = 20, top = 50, bottom = 60;
    const int pw = W - left - right, ph = H - top - bottom;
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (const series &s : all)
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!std::isfinite(s.y[i]))
                continue;
            x0 = std::min(x0, s.x[i]);
            x1 = std::max(x1, s.x[i]);
            y0 = std::min(y0, s.y[i]);
            y1 = std::max(y1, s.y[i]);
        }
    const double pad = 0.05 * (y1 - y0 + 1e-9);
    y0 -= pad;
    y1 += pad;
    cv::Mat img(H, W, CV_8UC3, k_white);
    auto X = [&](double v) {
        return left + int(std::lround((v - x0) / (x1 - x0) * pw));
    };
    auto Y = [&](double v) {
        return top + int(std::lround((y1 - v) / (y1 - y0) * ph));
    };
    const double xs = tick_step(x1 - x0, 8), ys = tick_step(y1 - y0, 8);
    for (double v = std::ceil(x0 / xs) * xs; v <= x1; v += xs) {
        cv::line(img, {X(v), top}, {X(v), top + ph}, cv::Scalar(230, 230, 230));
        const std::string l = fmt(xs < 1 ? "%.1f" : "%.0f", v);
        text(img, l, {X(v) - text_width(l) / 2, top + ph + 20});
    }
    for (double v = std::ceil(y0 / ys) * ys; v <= y1; v += ys) {
        cv::line(img, {left, Y(v)}, {left + pw, Y(v)}, cv::Scalar(230, 230, 230));
        const std::string l = fmt(ys < 1 ? "%.1f" : "%.0f", v);
        text(img, l, {left - 8 - text_width(l), Y(v) + 5});
    }
    cv::rectangle(img, cv::Rect(left, top, pw, ph), k_black);
    for (const series &s : all) {
        std::vector<cv::Point> pts;
        for (size_t i = 0; i < s.x.size(); ++i) {
            if (!std::isfinite(s.y[i])) {
                if (pts.size() > 1)
                    cv::polylines(img, pts, false, s.colour, s.thickness, cv::LINE_AA);
                pts.clear();
                continue;
            }
            pts.emplace_back(X(s.x[i]), Y(s.y[i]));
        }
        if (pts.size() > 1)
            cv::polylines(img, pts, false, s.colour, s.thickness, cv::LINE_AA);
    }
    text(img, title, {left, 30}, 0.6);
    text(img, xlabel, {left + pw / 2 - text_width(xlabel) / 2, H - 15});
    cv::Mat label(20, 260, CV_8UC3, k_white);
    text(label, ylabel, {5, 15});
    cv::rotate(label, label, cv::ROTATE_90_COUNTERCLOCKWISE);
    label.copyTo(img(cv::Rect(10, top + ph / 2 - 130, 20, 260)));
    int ly = top + 20;
    for (const series &s : all) {
        cv::line(img, {left + pw - 260, ly - 5}, {left + pw - 225, ly - 5}, s.colour, 3,
                 cv::LINE_AA);
        text(img, s.name, {left + pw - 215, ly});
        ly += 22;
    }
    if (!cv::imwrite(path, img))
        std::fprintf(stderr, "could not write %s\n", path.c_str());
}

// " (centre + edges + ...)" for a mix's components, else "".
std::string components_text(unsigned c) {
    std::string s;
    auto add = [&](unsigned bit, const char *name) {
        if (c & bit)
            s += (s.empty() ? " (" : " + ") + std::string(name);
    };
    add(FLT_SHAPE_HAS_CENTRE, "centre");
    add(FLT_SHAPE_HAS_QUARTER, "quarters");
    add(FLT_SHAPE_HAS_EDGE_LEFT, "left edge");
    add(FLT_SHAPE_HAS_EDGE_RIGHT, "right edge");
    add(FLT_SHAPE_HAS_BOW, "bow");
    add(FLT_SHAPE_HAS_CROSSBOW, "crossbow");
    return s.empty() ? s : s + ")";
}

// The zone profiles as bar charts, one panel per sheet, with the true
// profile as black ticks and the flat limit as a dashed line.
void zone_chart_png(const std::string &path, const std::vector<sheet_result> &sheets,
                    const std::vector<double> &zone_x, double zone_width, double flat_limit) {
    const int W = 1100, panel = 260, left = 80, right = 20, top = 50;
    const int H = top + int(sheets.size()) * panel + 30, pw = W - left - right, ph = panel - 70;
    double ymax = flat_limit;
    for (const sheet_result &r : sheets)
        for (size_t j = 0; j < r.zone_i.size(); ++j)
            ymax = std::max({ymax, std::isfinite(r.zone_i[j]) ? r.zone_i[j] : 0.0, r.zone_true[j]});
    ymax *= 1.1;
    cv::Mat img(H, W, CV_8UC3, k_white);
    text(img, "I-Unit profile across the width, per sheet (bars: measured, black ticks: true)",
         {left, 30}, 0.6);
    const double x0 = zone_x.front() - zone_width / 2, x1 = zone_x.back() + zone_width / 2;
    auto X = [&](double v) {
        return left + int(std::lround((v - x0) / (x1 - x0) * pw));
    };
    for (size_t p = 0; p < sheets.size(); ++p) {
        const sheet_result &r = sheets[p];
        const int py = top + int(p) * panel + 20;
        auto Y = [&](double v) {
            return py + ph - int(std::lround(v / ymax * ph));
        };
        const double ys = tick_step(ymax, 5);
        for (double v = 0; v <= ymax; v += ys) {
            cv::line(img, {left, Y(v)}, {left + pw, Y(v)}, cv::Scalar(230, 230, 230));
            const std::string l = fmt("%.0f", v);
            text(img, l, {left - 8 - text_width(l), Y(v) + 5});
        }
        for (size_t j = 0; j < zone_x.size(); ++j) {
            const int a = X(zone_x[j] - 0.42 * zone_width), b = X(zone_x[j] + 0.42 * zone_width);
            if (std::isfinite(r.zone_i[j]))
                cv::rectangle(img, cv::Point(a, Y(std::max(0.0, r.zone_i[j]))), cv::Point(b, Y(0)),
                              cv::Scalar(180, 120, 40), cv::FILLED);
            cv::line(img, {a, Y(r.zone_true[j])}, {b, Y(r.zone_true[j])}, k_black, 2);
        }
        for (int xx = left; xx < left + pw; xx += 12)
            cv::line(img, {xx, Y(flat_limit)}, {xx + 6, Y(flat_limit)}, cv::Scalar(0, 0, 200), 1);
        cv::rectangle(img, cv::Rect(left, py, pw, ph), k_black);
        char head[200];
        std::snprintf(head, sizeof head, "sheet %d (%.1f-%.1f m): %s%s, confidence %.2f", r.index,
                      r.s_first / 1000, r.s_last / 1000, flt_shape_string(r.shape),
                      components_text(r.components).c_str(), r.confidence);
        text(img, head, {left + 5, py - 5});
        const double xs = tick_step(x1 - x0, 8);
        for (double v = std::ceil(x0 / xs) * xs; v <= x1; v += xs) {
            const std::string l = fmt("%.0f", v);
            text(img, l, {X(v) - text_width(l) / 2, py + ph + 18}, 0.45);
        }
        text(img, "I-Units", {10, py + ph / 2});
    }
    text(img, "zone centre x across the width (mm); red dashes: flat limit",
         {left + pw / 2 - 220, H - 12});
    if (!cv::imwrite(path, img))
        std::fprintf(stderr, "could not write %s\n", path.c_str());
}

// The coil on one page, as a quality engineer reads it: the coil's
// identity at the top; a run chart per rule of the worst value the gauge
// found on each sheet, with the limit that applied (red dashes; failed
// sheets red), and one of the largest zone I-Units with the flat limit;
// then the disposition, one line per run of sheets with the same verdict
// (the engineer ticks accept, downgrade or reject and gives a reason),
// and the sign-off. The gauge's verdicts, never computed again here.
struct coil_identity {
    std::string id, grade, customer;
    double thickness, width;
};

void coil_chart_png(const std::string &path, const coil_identity &coil, bool judged,
                    const std::vector<sheet_result> &sheets,
                    const std::vector<std::string> &rule_names,
                    const std::vector<flt_measure> &rule_measures, double flat_limit) {
    const int W = 1100, left = 90, right = 30, panel = 190, ph = 130, pw = W - left - right;
    // The largest zone I-Units get a panel of their own (with the flat
    // limit) unless a rule already judges them.
    const bool iu_rule = std::find(rule_measures.begin(), rule_measures.end(),
                                   FLT_MEASURE_ZONE_I_UNITS) != rule_measures.end();
    const size_t panels = rule_names.size() + (iu_rule ? 0 : 1);
    // Runs of sheets with the same verdict: the disposition's lines.
    struct run {
        size_t first, last;
        int verdict;
    };
    std::vector<run> runs;
    for (size_t i = 0; i < sheets.size(); ++i) {
        const int v = judged ? sheets[i].verdict : -1;
        if (runs.empty() || runs.back().verdict != v)
            runs.push_back({i, i, v});
        else
            runs.back().last = i;
    }
    const int head = 110, disp_top = head + int(panels) * panel + 20;
    const int H = disp_top + 70 + 28 * int(runs.size()) + 90;
    cv::Mat img(H, W, CV_8UC3, k_white);
    const cv::Scalar red(40, 40, 210), blue(180, 110, 30), green(60, 150, 60);
    size_t pass = 0, fail = 0, not_judged = 0;
    for (const sheet_result &r : sheets)
        (r.verdict == FLT_VERDICT_PASS   ? pass
         : r.verdict == FLT_VERDICT_FAIL ? fail
                                         : not_judged)++;
    text(img, "Coil " + coil.id, {left, 38}, 0.9, k_black, 2);
    char line[300];
    std::snprintf(line, sizeof line,
                  "grade %s   customer %s   nominal %.2f mm x %.0f mm   %zu sheets, %.1f m",
                  coil.grade.c_str(), coil.customer.c_str(), coil.thickness, coil.width,
                  sheets.size(), sheets.empty() ? 0.0 : sheets.back().s_last / 1000);
    text(img, line, {left, 66}, 0.55);
    if (judged)
        std::snprintf(line, sizeof line, "the gauge's verdicts: %zu pass, %zu fail, %zu not judged",
                      pass, fail, not_judged);
    else
        std::snprintf(line, sizeof line, "no rule file: the gauge judged no sheet");
    text(img, line, {left, 92}, 0.55, fail ? red : k_black);
    const double n = double(std::max<size_t>(1, sheets.size()));
    auto X = [&](double i) {  // sheet i (0-based) at the centre of its slot
        return left + int(std::lround((i + 0.5) / n * pw));
    };
    for (size_t p = 0; p < panels; ++p) {
        const bool iu = p == rule_names.size();
        const int top = head + int(p) * panel + 25;
        std::vector<double> y(sheets.size()), lim(sheets.size());
        double y1 = 0;
        for (size_t i = 0; i < sheets.size(); ++i) {
            const sheet_result &r = sheets[i];
            if (iu) {
                double m = NAN;
                for (double z : r.zone_i)
                    if (std::isfinite(z))
                        m = std::isfinite(m) ? std::max(m, z) : z;
                y[i] = m;
                lim[i] = flat_limit;
            } else {
                y[i] = p < r.rule_worst.size() ? r.rule_worst[p] : NAN;
                lim[i] = p < r.rule_limit.size() ? r.rule_limit[p] : NAN;
            }
            for (double v : {y[i], lim[i]})
                if (std::isfinite(v))
                    y1 = std::max(y1, v);
        }
        y1 = y1 > 0 ? 1.15 * y1 : 1.0;
        auto Y = [&](double v) {
            return top + ph - int(std::lround(v / y1 * ph));
        };
        const double ys = tick_step(y1, 4);
        for (double v = 0; v <= y1; v += ys) {
            cv::line(img, {left, Y(v)}, {left + pw, Y(v)}, cv::Scalar(230, 230, 230));
            const std::string l = fmt(ys < 0.1 ? "%.2f" : ys < 1 ? "%.1f" : "%.0f", v);
            text(img, l, {left - 8 - text_width(l, 0.45), Y(v) + 5}, 0.45);
        }
        cv::rectangle(img, cv::Rect(left, top, pw, ph), k_black);
        // The limit per sheet (a band may differ from sheet to sheet).
        for (size_t i = 0; i < sheets.size(); ++i)
            if (std::isfinite(lim[i])) {
                const int a = X(double(i) - 0.5), b = X(double(i) + 0.5);
                for (int xx = a; xx < b; xx += 10)
                    cv::line(img, {xx, Y(lim[i])}, {std::min(b, xx + 5), Y(lim[i])}, red, 1);
            }
        std::vector<cv::Point> pts;
        for (size_t i = 0; i <= sheets.size(); ++i) {
            if (i == sheets.size() || !std::isfinite(y[i])) {
                if (pts.size() > 1)
                    cv::polylines(img, pts, false, blue, 2, cv::LINE_AA);
                pts.clear();
                continue;
            }
            pts.emplace_back(X(double(i)), Y(y[i]));
        }
        for (size_t i = 0; i < sheets.size(); ++i) {
            if (!std::isfinite(y[i]))
                continue;  // not judged: no point, the disposition says so
            const bool over = std::isfinite(lim[i]) && y[i] > lim[i];
            cv::circle(img, {X(double(i)), Y(y[i])}, 4, over ? red : blue, cv::FILLED, cv::LINE_AA);
        }
        const flt_measure m = iu ? FLT_MEASURE_ZONE_I_UNITS : rule_measures[p];
        const char *unit = m == FLT_MEASURE_ZONE_I_UNITS     ? "I-Units"
                           : m == FLT_MEASURE_WAVE_STEEPNESS ? "%"
                                                             : "mm";
        const std::string name =
            iu ? "largest zone I-Units (red dashes: the flat limit)"
               : rule_names[p] + " (" + unit + "; red dashes: the rule's limit)";
        text(img, name, {left, top - 8}, 0.5);
        const size_t every = std::max<size_t>(1, sheets.size() / 15 + 1);
        for (size_t i = 0; i < sheets.size(); i += every) {
            const std::string l = std::to_string(sheets[i].index);
            text(img, l, {X(double(i)) - text_width(l, 0.4) / 2, top + ph + 16}, 0.4);
        }
    }
    text(img, "sheet (along the coil, head first)",
         {left + pw / 2 - text_width("sheet (along the coil, head first)") / 2, disp_top - 8});
    // Disposition and sign-off.
    int y = disp_top + 30;
    text(img, "Disposition", {left, y}, 0.7, k_black, 2);
    y += 28;
    const int c1 = left, c2 = left + 150, c3 = left + 300, c4 = left + 650;
    text(img, "sheets", {c1, y}, 0.5, k_black, 2);
    text(img, "verdict", {c2, y}, 0.5, k_black, 2);
    text(img, "disposition (tick one)", {c3, y}, 0.5, k_black, 2);
    text(img, "reason", {c4, y}, 0.5, k_black, 2);
    cv::line(img, {left, y + 8}, {left + pw, y + 8}, k_black);
    for (const run &r : runs) {
        y += 28;
        const std::string range = r.first == r.last ? std::to_string(sheets[r.first].index)
                                                    : std::to_string(sheets[r.first].index) + "-" +
                                                          std::to_string(sheets[r.last].index);
        text(img, range, {c1, y});
        const char *word = r.verdict < 0 ? "none" : verdict_word(r.verdict);
        text(img, word, {c2, y}, 0.5,
             r.verdict == FLT_VERDICT_FAIL   ? red
             : r.verdict == FLT_VERDICT_PASS ? green
                                             : k_black);
        int bx = c3;
        for (const char *choice : {"accept", "downgrade", "reject"}) {
            cv::rectangle(img, cv::Rect(bx, y - 12, 13, 13), k_black);
            text(img, choice, {bx + 19, y});
            bx += 40 + text_width(choice);
        }
        cv::line(img, {c4, y + 3}, {left + pw, y + 3}, k_grey);
    }
    y += 60;
    text(img, "Quality engineer (name, signature):", {left, y});
    cv::line(img, {left + 300, y + 3}, {left + 640, y + 3}, k_black);
    text(img, "Date:", {left + 680, y});
    cv::line(img, {left + 730, y + 3}, {left + pw, y + 3}, k_black);
    if (!cv::imwrite(path, img))
        std::fprintf(stderr, "could not write %s\n", path.c_str());
}

// ---------------------------------------------------------------- the line

bool parse(int argc, char **argv, settings &st) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            usage();
            std::exit(0);
        }
        if (i + 1 >= argc)
            return false;
        const char *v = argv[++i];
        char *end = nullptr;
        const double d = std::strtod(v, &end);
        const bool number = end && *end == '\0' && std::isfinite(d);
        if (a == "--out" || a == "--coil" || a == "--rules" || a == "--record" ||
            a == "--archive") {
            (a == "--out"      ? st.out
             : a == "--coil"   ? st.coil
             : a == "--rules"  ? st.rules
             : a == "--record" ? st.record
                               : st.archive) = v;
            continue;
        }
        if (!number)
            return false;
        if (a == "--sheets")
            st.sheets = int(d);
        else if (a == "--sheet-length")
            st.sheet_length = d;
        else if (a == "--width")
            st.width = d;
        else if (a == "--pitch")
            st.pitch = d;
        else if (a == "--speed")
            st.speed = d;
        else if (a == "--centre-buckle")
            st.centre_buckle = d;
        else if (a == "--wavy-edges")
            st.wavy_edges = d;
        else if (a == "--quarter-buckle")
            st.quarter_buckle = d;
        else if (a == "--period")
            st.period = d;
        else if (a == "--vibration")
            st.vibration = d;
        else if (a == "--eccentricity")
            st.eccentricity = d;
        else if (a == "--shear")
            st.shear = d;
        else if (a == "--peak-noise")
            st.peak_noise = d;
        else if (a == "--seed")
            st.seed = unsigned(d);
        else if (a == "--thickness")
            st.thickness = d;
        else
            return false;
    }
    return st.sheets >= 1 && st.sheet_length >= 600 && st.width >= 100 && st.width <= 2000 &&
           st.pitch > 0 && st.width / st.pitch <= 4000 && st.speed > 0 && st.period > 0 &&
           st.vibration >= 0 && st.eccentricity >= 0 && st.shear >= 0 && st.peak_noise >= 0 &&
           st.thickness > 0 && !st.coil.empty();
}

flt_options *make_options(std::initializer_list<std::pair<flt_option, double>> kv) {
    flt_options *o = nullptr;
    CHECK(flt_options_create(&o));
    for (auto &p : kv)
        CHECK(flt_options_set(o, p.first, p.second));
    return o;
}

// Everything a sheet says that a replay must give again: its values (but
// when it was finished) and its zone profile.
std::vector<double> sheet_fingerprint(const flt_sheet *sh, size_t zones) {
    std::vector<double> v(FLT_SHEET_FINISHED_TIME + zones);
    for (int k = 0; k < FLT_SHEET_FINISHED_TIME; ++k)
        CHECK(flt_sheet_get(sh, flt_sheet_value(k), &v[size_t(k)]));
    CHECK(
        flt_sheet_get_array(sh, FLT_SHEET_ZONE_I_UNITS, zones, v.data() + FLT_SHEET_FINISHED_TIME));
    return v;
}

// The recording through a second gauge with the recording's options (and
// the same rules): the same sheets, compared bit for bit with the live ones.
std::string replay(const std::string &path, const std::string &rules_path, double thickness,
                   double width, size_t zones, const std::vector<std::vector<double>> &live) {
    flt_recording *recording = nullptr;
    flt_options *options = nullptr;
    flt_calib *calib = nullptr;
    CHECK(flt_recording_open(path.c_str(), &recording));
    CHECK(flt_recording_options(recording, &options));
    CHECK(flt_recording_calib(recording, &calib));
    flt_recording_destroy(recording);
    flt_gauge *gauge = nullptr;
    CHECK(flt_gauge_create(calib, options, &gauge));
    flt_rules *rules = nullptr;
    if (!rules_path.empty()) {
        CHECK(flt_rules_load(rules_path.c_str(), &rules));
        CHECK(flt_gauge_set_rules(gauge, rules, thickness, width));
    }
    flt_source *source = nullptr;
    CHECK(flt_source_open_recording(path.c_str(), nullptr, &source));
    CHECK(flt_gauge_attach_source(gauge, source));
    const double t0 = process_cpu_s();
    CHECK(flt_gauge_start(gauge));
    CHECK(flt_gauge_wait(gauge, FLT_GAUGE_WAIT_FOREVER));
    const double cpu = process_cpu_s() - t0;
    size_t sheets = 0, differ = 0;
    for (;;) {
        flt_sheet *sh = nullptr;
        CHECK(flt_gauge_next_sheet(gauge, 0, &sh));
        if (!sh)
            break;
        const std::vector<double> v = sheet_fingerprint(sh, zones);
        flt_sheet_destroy(sh);
        if (sheets >= live.size() ||
            std::memcmp(v.data(), live[sheets].data(), v.size() * sizeof(double)) != 0)
            ++differ;
        ++sheets;
    }
    CHECK(flt_gauge_attach_source(gauge, nullptr));
    flt_source_destroy(source);
    flt_gauge_destroy(gauge);
    flt_rules_destroy(rules);
    flt_calib_destroy(calib);
    flt_options_destroy(options);
    char line[300];
    std::snprintf(
        line, sizeof line, "  replayed              %zu sheets in %.1f s of CPU: %s\n", sheets, cpu,
        differ == 0 && sheets == live.size() ? "every value identical to the live ones, bit for bit"
                                             : "SOME SHEETS DIFFER from the live ones");
    return line;
}

}  // namespace

int main(int argc, char **argv) {
    settings st;
    if (!parse(argc, argv, st)) {
        usage();
        std::fprintf(stderr, "\nflatline_demo: bad or missing option value (sheets >= 1, "
                             "sheet length >= 600 mm, width 100..2000 mm)\n");
        return 2;
    }
    const size_t fibers = size_t(st.width / st.pitch) + 1;
    const double first_x = -0.5 * st.pitch * double(fibers - 1);
    std::vector<double> x(fibers);
    for (size_t k = 0; k < fibers; ++k)
        x[k] = first_x + st.pitch * double(k);

    flt_calib *calib = nullptr;
    CHECK(flt_calib_create_reference(k_roi_first, k_roi_rows, first_x, st.pitch, fibers, &calib));
    flt_options *sim_opt = make_options({{FLT_OPT_SIM_SEED, st.seed},
                                         {FLT_OPT_SIM_FRAME_SPACING, k_frame_spacing},
                                         {FLT_OPT_SIM_STRIP_WIDTH, st.width},
                                         {FLT_OPT_SIM_HEAVE_SIGMA, st.vibration},
                                         {FLT_OPT_SIM_ECCENTRICITY_AMPLITUDE, st.eccentricity},
                                         {FLT_OPT_SIM_SHEAR_AMPLITUDE, st.shear},
                                         {FLT_OPT_SIM_PEAK_SIGMA, st.peak_noise}});
    flt_sim *sim = nullptr;
    CHECK(flt_sim_create(calib, sim_opt, &sim));
    if (st.centre_buckle != 0)
        CHECK(flt_sim_add_defect(sim, FLT_SIM_CENTRE_BUCKLE, st.centre_buckle, st.period));
    // Opposite phase to the centre: the edges are long where the centre is
    // short, as on the reference's sheet.
    if (st.wavy_edges != 0)
        CHECK(flt_sim_add_defect(sim, FLT_SIM_WAVY_EDGE_BOTH, -st.wavy_edges, st.period));
    if (st.quarter_buckle != 0)
        CHECK(flt_sim_add_defect(sim, FLT_SIM_QUARTER_BUCKLE, st.quarter_buckle, st.period));

    // ---------------------------------------------------------- the gauge
    // What a vendor writes: one handle from the calibration and options,
    // frames and cuts in, sheets out.
    //   rigid_motion: the heave moves every fiber of a frame together; the
    //   reconstructor takes it out of the shape. robust (Huber): the shear
    //   station's ringing after each cut is an outlier, not shape
    //   (tests/c/test_recon.c; examples/python/compare_filters.py).
    //   gauge_overflow = 1: rendered frames can wait for the gauge (a
    //   camera's cannot: leave it 0 and watch FLT_GAUGE_COUNT_DROPPED).
    //   gauge_keep_maps = 2: the report draws each sheet's reconstructed and
    //   measured heights.
    flt_options *gauge_opt = make_options({{FLT_OPT_RIGID_MOTION, 1},
                                           {FLT_OPT_ROBUST, FLT_ROBUST_HUBER},
                                           {FLT_OPT_GAUGE_FRAME_SPACING, 0.8 * k_frame_spacing},
                                           {FLT_OPT_GAUGE_OVERFLOW, 1},
                                           {FLT_OPT_GAUGE_MAX_SHEET_LENGTH, st.sheet_length + 1000},
                                           {FLT_OPT_GAUGE_KEEP_MAPS, 2},
                                           {FLT_OPT_GAUGE_SHEET_SLOTS, 4}});
    flt_gauge *gauge = nullptr;
    CHECK(flt_gauge_create(calib, gauge_opt, &gauge));
    // The shear cuts every sheet_length mm (given before the strip gets
    // there; a cut signal that comes late works as well).
    for (int i = 1; i < st.sheets; ++i)
        CHECK(flt_gauge_cut(gauge, st.sheet_length * i));

    // The quality record: the coil's identity (its nominal thickness and
    // width choose the rule bands), the rules, a recorder and an archive,
    // all before the first frame.
    flt_coil_info *coil = nullptr;
    CHECK(flt_coil_info_create(st.coil.c_str(), &coil));
    CHECK(flt_coil_info_set_text(coil, FLT_COIL_FIELD_GRADE, "S355MC"));
    CHECK(flt_coil_info_set_text(coil, FLT_COIL_FIELD_CUSTOMER, "simulated line"));
    CHECK(flt_coil_info_set_nominal(coil, st.thickness, st.width));
    CHECK(flt_gauge_set_coil(gauge, coil));
    flt_coil_info_destroy(coil);
    flt_rules *rules = nullptr;
    if (!st.rules.empty()) {
        CHECK(flt_rules_load(st.rules.c_str(), &rules));
        CHECK(flt_gauge_set_rules(gauge, rules, st.thickness, st.width));
    }
    flt_recorder *recorder = nullptr;
    if (!st.record.empty()) {
        CHECK(flt_recorder_create(st.record.c_str(), calib, nullptr, &recorder));
        CHECK(flt_gauge_attach_recorder(gauge, recorder));
    }
    flt_archive *archive = nullptr;
    if (!st.archive.empty()) {
        CHECK(flt_archive_open(st.archive.c_str(), "demo line", nullptr, &archive));
        CHECK(flt_gauge_attach_archive(gauge, archive));
    }

    // The report compares each sheet with the ground truth, evaluated by a
    // flatness handle of its own.
    flt_options *flat_opt = make_options({{FLT_OPT_FLAT_WINDOW_LENGTH, 0}});
    flt_flatness *truth_flatness = nullptr;
    CHECK(flt_flatness_create(fibers, x.data(), flat_opt, &truth_flatness));
    double flat_limit = 0, zone_width = 0;
    CHECK(flt_gauge_get_option(gauge, FLT_OPT_FLAT_FLAT_LIMIT, &flat_limit));
    CHECK(flt_gauge_get_option(gauge, FLT_OPT_FLAT_ZONE_WIDTH, &zone_width));
    size_t zones = 0;
    CHECK(flt_flatness_zones(truth_flatness, &zones));
    std::vector<double> zone_x(zones);
    CHECK(flt_flatness_zone_layout(truth_flatness, zones, nullptr, zone_x.data(), nullptr));

    std::printf(
        "libflatline %s demo: %d sheets of %.0f mm x %.0f mm, %zu fibers every %.1f mm\n"
        "defects: centre buckle %.1f mm, wavy edges %.1f mm, quarter buckle %.1f mm, "
        "period %.0f mm\nnoise: heave %.2f mm, eccentricity %.2f mm, shear ringing %.1f mm, "
        "peak noise %.3f px\n",
        flt_version_string(), st.sheets, st.sheet_length, st.width, fibers, st.pitch,
        st.centre_buckle, st.wavy_edges, st.quarter_buckle, st.period, st.vibration,
        st.eccentricity, st.shear, st.peak_noise);
    std::fflush(stdout);
    ::mkdir(st.out.c_str(), 0755);

    const size_t frame_bytes = size_t(k_camera_width) * k_roi_rows;
    std::vector<uint8_t> frame(frame_bytes);
    std::vector<double> truth;  // every frame's true heights, [frame * fibers]
    std::vector<sheet_result> results;
    std::vector<std::string> rule_names;           // the gauge's rules, from its first verdict
    std::vector<flt_measure> rule_measures;        // ... and what each measures
    std::vector<std::vector<double>> live_values;  // each sheet's values and zone I-Units
    std::vector<double> fiber_plot_raw, fiber_plot_z, fiber_plot_truth, fiber_plot_s;
    const size_t plot_fiber = fibers / 2;  // the centre, where the buckle is
    double render = 0.0, report_time = 0.0;
    size_t frames = 0, rows_done = 0;
    double invalid_samples = 0;
    double max_error_all = 0, sq_all = 0;
    size_t n_all = 0;

    // A sheet from the gauge: its results, and the report's comparison with
    // the ground truth.
    auto take_sheet = [&](flt_sheet *sh) {
        const double t0 = thread_cpu_s();
        auto value = [&](flt_sheet_value key) {
            double v = 0;
            CHECK(flt_sheet_get(sh, key, &v));
            return v;
        };
        sheet_result r{};
        r.index = int(value(FLT_SHEET_ID));
        r.s_first = value(FLT_SHEET_S_START);
        r.s_last = value(FLT_SHEET_S_END);
        r.shape = flt_shape(int(value(FLT_SHEET_SHAPE)));
        r.confidence = value(FLT_SHEET_CONFIDENCE);
        r.components = unsigned(value(FLT_SHEET_COMPONENTS));
        r.bow = value(FLT_SHEET_BOW);
        r.crossbow = value(FLT_SHEET_CROSSBOW);
        r.verdict = int(value(FLT_SHEET_VERDICT));
        r.rules_failed = int(value(FLT_SHEET_RULES_FAILED));
        const flt_rules *sheet_rules = nullptr;
        const flt_verdict *sheet_verdict = nullptr;
        // FLT_ERR_STATE: the gauge has no rules (no --rules): nothing judged.
        if (flt_sheet_verdict(sh, &sheet_rules, &sheet_verdict) == FLT_OK) {
            size_t n = 0;
            CHECK(flt_rules_count(sheet_rules, &n));
            for (size_t i = 0; i < n; ++i) {
                double worst = NAN, limit = NAN;
                CHECK(flt_verdict_get(sheet_verdict, i, FLT_VERDICT_WORST, &worst));
                CHECK(flt_verdict_get(sheet_verdict, i, FLT_VERDICT_LIMIT, &limit));
                r.rule_worst.push_back(worst);
                r.rule_limit.push_back(limit);
                if (rule_names.size() < n) {
                    const char *name = nullptr;
                    flt_measure measure = FLT_MEASURE_STRAIGHTEDGE_ALONG;
                    CHECK(flt_rules_rule(sheet_rules, i, &name, &measure, nullptr));
                    rule_names.push_back(name ? name : "");
                    rule_measures.push_back(measure);
                }
            }
        }
        const flt_coil_info *sheet_coil = nullptr;
        const char *coil_id = nullptr;
        // FLT_ERR_NOT_FOUND: a sheet of a coil without identity (not here:
        // the demo names its coil before the first frame).
        if (flt_sheet_coil(sh, &sheet_coil) == FLT_OK) {
            CHECK(flt_coil_info_get_text(sheet_coil, FLT_COIL_FIELD_ID, &coil_id));
            r.coil_id = coil_id ? coil_id : "";
        }
        r.zone_i.resize(zones);
        r.zone_true.resize(zones);
        CHECK(flt_sheet_get_array(sh, FLT_SHEET_ZONE_I_UNITS, zones, r.zone_i.data()));
        invalid_samples += value(FLT_SHEET_INVALID);
        live_values.push_back(sheet_fingerprint(sh, zones));
        // The sheet's rows: reconstructed and measured heights, and the
        // truth of the frames they came from (a frame every 3 mm from 0).
        const size_t rows = size_t(value(FLT_SHEET_ROWS));
        rows_done += rows;
        sheet_data sheet;
        sheet.s.resize(rows);
        sheet.z.resize(rows * fibers);
        sheet.raw.resize(rows * fibers);
        sheet.flags.resize(rows * fibers);
        CHECK(flt_sheet_height_map(sh, rows, fibers, sheet.s.data(), sheet.z.data(),
                                   sheet.flags.data()));
        CHECK(flt_sheet_measured_map(sh, rows, fibers, sheet.raw.data()));
        flt_sheet_destroy(sh);
        for (size_t i = 0; i < rows; ++i) {
            const size_t f = size_t(std::lround(sheet.s[i] / k_frame_spacing));
            sheet.truth.insert(sheet.truth.end(), &truth[f * fibers], &truth[(f + 1) * fibers]);
        }
        if (rows >= 2) {
            CHECK(flt_flatness_evaluate(truth_flatness, rows, fibers, sheet.s.data(),
                                        sheet.truth.data(), nullptr));
            CHECK(flt_flatness_zone_results(truth_flatness, zones, r.zone_true.data(), nullptr));
        }
        for (size_t j = 0; j < zones; ++j)
            if (std::isfinite(r.zone_i[j]))
                r.zone_error = std::max(r.zone_error, std::fabs(r.zone_i[j] - r.zone_true[j]));
        // Shape error: the absolute level of a bouncing strip is only known as
        // an average and flatness does not depend on it, so the sheet's mean
        // offset is removed first.
        double sum = 0;
        size_t n = 0;
        for (size_t i = 0; i < sheet.z.size(); ++i)
            if (std::isfinite(sheet.z[i])) {
                sum += sheet.z[i] - sheet.truth[i];
                ++n;
            }
        const double mean = n ? sum / double(n) : 0.0;
        double sq = 0;
        for (size_t i = 0; i < sheet.z.size(); ++i) {
            if (!std::isfinite(sheet.z[i]))
                continue;
            const double e = sheet.z[i] - sheet.truth[i] - mean;
            sq += e * e;
            r.max_error = std::max(r.max_error, std::fabs(e));
        }
        r.rms_error = n ? std::sqrt(sq / double(n)) : NAN;
        sq_all += sq;
        n_all += n;
        max_error_all = std::max(max_error_all, r.max_error);
        results.push_back(r);
        std::fprintf(stderr, "\r%78s\r", "");
        std::printf("sheet %d  %5.1f-%5.1f m  %-15s conf %.2f  peak %6.1f I-Units  "
                    "error rms %.3f max %.3f mm\n",
                    r.index, r.s_first / 1000, r.s_last / 1000, flt_shape_string(r.shape),
                    r.confidence, *std::max_element(r.zone_i.begin(), r.zone_i.end()), r.rms_error,
                    r.max_error);
        std::fflush(stdout);
        const std::string base = st.out + "/sheet" + std::to_string(r.index);
        // Colour scale: the true surface's range plus a fifth, so the true
        // and reconstructed maps use most of it (raw heights, which carry
        // the heave, may clip at its ends).
        double true_max = 0;
        for (double v : sheet.truth)
            true_max = std::max(true_max, std::fabs(v));
        const double scale = std::max(1.0, std::ceil(1.2 * true_max));
        char title[160];
        if (rows >= 2) {
            std::snprintf(title, sizeof title, "Sheet %d: raw heights from the extractor (mm)",
                          r.index);
            height_map_png(base + "_raw.png", title, sheet, sheet.raw, x, scale);
            std::snprintf(title, sizeof title, "Sheet %d: reconstructed heights (mm)", r.index);
            height_map_png(base + "_reconstructed.png", title, sheet, sheet.z, x, scale);
            std::snprintf(title, sizeof title, "Sheet %d: true heights (mm)", r.index);
            height_map_png(base + "_true.png", title, sheet, sheet.truth, x, scale);
        }
        if (r.index == 1) {
            for (size_t i = 0; i < sheet.s.size(); ++i) {
                fiber_plot_s.push_back(sheet.s[i]);
                fiber_plot_raw.push_back(sheet.raw[i * fibers + plot_fiber]);
                fiber_plot_z.push_back(sheet.z[i * fibers + plot_fiber]);
                fiber_plot_truth.push_back(sheet.truth[i * fibers + plot_fiber]);
            }
        }
        report_time += thread_cpu_s() - t0;
    };
    auto take_sheets = [&]() {
        for (;;) {
            flt_sheet *sh = nullptr;
            CHECK(flt_gauge_next_sheet(gauge, 0, &sh));
            if (!sh)
                return;
            take_sheet(sh);
        }
    };

    const double total_length = st.sheets * st.sheet_length;
    const double cpu0 = process_cpu_s();
    for (;;) {
        double e = 0;
        const double t0 = thread_cpu_s();
        truth.resize((frames + 1) * fibers);
        CHECK(flt_sim_next_frame(sim, frame.data(), frame_bytes, k_camera_width, &e, fibers,
                                 &truth[frames * fibers], nullptr, 0));
        render += thread_cpu_s() - t0;
        if (e >= total_length)
            break;
        CHECK(flt_gauge_push_frame(gauge, frame.data(), FLT_PIXEL_MONO8, k_camera_width, k_roi_rows,
                                   k_camera_width, e));
        ++frames;
        take_sheets();
        if (frames % 50 == 0)
            std::fprintf(stderr, "\r  frame %6zu  s = %7.1f m  %5.1f%% of the strip", frames,
                         e / 1000, 100 * e / total_length);
    }
    // The end of the strip: its last sheet ends at its last row.
    CHECK(flt_gauge_flush(gauge));
    take_sheets();
    // Library time: every thread's CPU time but the rendering and the
    // report's, which a real line does not have.
    const double busy = process_cpu_s() - cpu0 - render - report_time;
    std::fprintf(stderr, "\r%78s\r", "");
    CHECK(flt_gauge_attach_recorder(gauge, nullptr));
    CHECK(flt_gauge_attach_archive(gauge, nullptr));
    std::string record_summary;
    if (recorder) {
        uint64_t rows = 0, lost = 0, bytes = 0, samples = 0;
        CHECK(flt_recorder_sync(recorder, 60000));
        CHECK(flt_recorder_count(recorder, FLT_RECORDER_COUNT_ROWS_STORED, &rows));
        CHECK(flt_recorder_count(recorder, FLT_RECORDER_COUNT_ROWS_LOST, &lost));
        CHECK(flt_recorder_count(recorder, FLT_RECORDER_COUNT_BYTES, &bytes));
        CHECK(flt_recorder_count(recorder, FLT_RECORDER_COUNT_SAMPLES, &samples));
        flt_recorder_destroy(recorder);
        char line[300];
        std::snprintf(
            line, sizeof line,
            "  recorded              %llu rows (%llu lost) in %s, %.2f bytes per sample\n",
            (unsigned long long)rows, (unsigned long long)lost, st.record.c_str(),
            samples ? double(bytes) / double(samples) : 0.0);
        record_summary += line;
        record_summary += replay(st.record, st.rules, st.thickness, st.width, zones, live_values);
    }
    if (archive) {
        uint64_t stored = 0, lost = 0;
        const flt_status flushed = flt_archive_flush(archive, 60000);
        CHECK(flt_archive_count(archive, FLT_ARCHIVE_COUNT_STORED, &stored));
        CHECK(flt_archive_count(archive, FLT_ARCHIVE_COUNT_LOST, &lost));
        char line[400];
        std::snprintf(
            line, sizeof line, "  archived              %llu sheets (%llu lost) in %s%s%s\n",
            (unsigned long long)stored, (unsigned long long)lost, st.archive.c_str(),
            flushed == FLT_OK ? "" : ": ", flushed == FLT_OK ? "" : flt_last_error_message());
        record_summary += line;
        flt_archive_destroy(archive);
    }

    // ---------------------------------------------------------- summary
    const double strip_s = total_length / 1000.0 / (st.speed / 60.0);
    std::printf("\nSummary\n");
    std::printf("  sheets processed      %zu (%zu frames, %zu rows; %.2f%% of samples invalid)\n",
                results.size(), frames, rows_done,
                100.0 * invalid_samples / double(std::max<size_t>(1, rows_done * fibers)));
    std::printf("  real-time factor      %.1fx at %.0f m/min (library %.2f s of CPU on all "
                "threads for %.1f s of strip;\n"
                "                        rendering the frames took another %.1f s)\n",
                strip_s / busy, st.speed, busy, strip_s, render);
    std::printf("  shape accuracy        rms %.3f mm, max %.3f mm against the true surface\n",
                std::sqrt(sq_all / double(std::max<size_t>(1, n_all))), max_error_all);
    std::printf("%s", record_summary.c_str());
    for (const sheet_result &r : results) {
        std::printf("  sheet %d: %s%s (confidence %.2f)  bow %+.2f mm  crossbow %+.2f mm  "
                    "zones within %.2f I-Units of the truth\n    I-Units:",
                    r.index, flt_shape_string(r.shape), components_text(r.components).c_str(),
                    r.confidence, r.bow, r.crossbow, r.zone_error);
        const size_t step = std::max<size_t>(1, zones / 15);
        for (size_t j = 0; j < zones; j += step)
            std::printf(" %5.1f", r.zone_i[j]);
        std::printf("  (zones of %.0f mm across, every %zu shown)\n", zone_width, step);
    }

    // ---------------------------------------------------------- report
    zone_chart_png(st.out + "/zones.png", results, zone_x, zone_width, flat_limit);
    coil_chart_png(st.out + "/coil.png",
                   {st.coil, "S355MC", "simulated line", st.thickness, st.width}, !st.rules.empty(),
                   results, rule_names, rule_measures, flat_limit);
    {
        char title[160];
        std::snprintf(title, sizeof title,
                      "Sheet 1, fiber at x = %.0f mm: one longitudinal profile", x[plot_fiber]);
        std::vector<double> s_m(fiber_plot_s.size());
        for (size_t i = 0; i < s_m.size(); ++i)
            s_m[i] = fiber_plot_s[i] / 1000;
        line_plot_png(
            st.out + "/fiber_profile.png", title, "s along travel (m)", "height z (mm)",
            {{"raw (extractor heights)", s_m, fiber_plot_raw, cv::Scalar(170, 170, 170), 1},
             {"true surface", s_m, fiber_plot_truth, cv::Scalar(40, 40, 220), 3},
             {"reconstructed", s_m, fiber_plot_z, cv::Scalar(180, 100, 20), 2}});
    }
    FILE *csv = std::fopen((st.out + "/sheets.csv").c_str(), "w");
    FILE *zcsv = std::fopen((st.out + "/zones.csv").c_str(), "w");
    FILE *json = std::fopen((st.out + "/report.json").c_str(), "w");
    if (!csv || !zcsv || !json) {
        std::fprintf(stderr, "flatline_demo: cannot write to %s\n", st.out.c_str());
        return 1;
    }
    std::fprintf(csv, "sheet,s_first_mm,s_last_mm,shape,confidence,bow_mm,crossbow_mm,"
                      "rms_error_mm,max_error_mm,max_zone_error_iu,coil_id,verdict,"
                      "rules_failed\n");
    std::fprintf(zcsv, "sheet,zone,x_centre_mm,i_units,true_i_units\n");
    std::fprintf(json,
                 "{\n  \"version\": \"%s\",\n  \"fibers\": %zu,\n  \"pitch_mm\": %g,\n"
                 "  \"zone_width_mm\": %g,\n  \"real_time_factor\": %.3f,\n"
                 "  \"line_speed_m_per_min\": %g,\n  \"rms_error_mm\": %.4f,\n"
                 "  \"max_error_mm\": %.4f,\n"
                 "  \"coil\": {\"id\": \"%s\", \"grade\": \"S355MC\", "
                 "\"nominal_thickness_mm\": %g, \"nominal_width_mm\": %g},\n"
                 "  \"rules\": %s,\n  \"sheets\": [\n",
                 flt_version_string(), fibers, st.pitch, zone_width, strip_s / busy, st.speed,
                 std::sqrt(sq_all / double(std::max<size_t>(1, n_all))), max_error_all,
                 json_escaped(st.coil).c_str(), st.thickness, st.width,
                 st.rules.empty() ? "null" : ("\"" + json_escaped(st.rules) + "\"").c_str());
    for (size_t p = 0; p < results.size(); ++p) {
        const sheet_result &r = results[p];
        // Without a rule file the gauge judges nothing: "none", as the archive.
        const char *verdict = st.rules.empty() ? "none" : verdict_word(r.verdict);
        std::fprintf(csv, "%d,%.1f,%.1f,%s,%.3f,%.3f,%.3f,%.4f,%.4f,%.3f,%s,%s,%d\n", r.index,
                     r.s_first, r.s_last, flt_shape_string(r.shape), r.confidence, r.bow,
                     r.crossbow, r.rms_error, r.max_error, r.zone_error,
                     csv_quoted(r.coil_id).c_str(), verdict, r.rules_failed);
        std::fprintf(json,
                     "    {\"sheet\": %d, \"s_first_mm\": %.1f, \"s_last_mm\": %.1f, "
                     "\"shape\": \"%s\", \"confidence\": %.3f, \"bow_mm\": %.3f, "
                     "\"crossbow_mm\": %.3f, \"rms_error_mm\": %.4f, \"max_error_mm\": %.4f,\n"
                     "     \"coil_id\": \"%s\", \"verdict\": \"%s\", \"rules_failed\": %d,\n"
                     "     \"zones\": [",
                     r.index, r.s_first, r.s_last, flt_shape_string(r.shape), r.confidence, r.bow,
                     r.crossbow, r.rms_error, r.max_error, json_escaped(r.coil_id).c_str(), verdict,
                     r.rules_failed);
        for (size_t j = 0; j < zones; ++j) {
            // JSON has no NaN: a zone without data is null.
            if (std::isfinite(r.zone_i[j]))
                std::fprintf(json, "%s{\"x_mm\": %.1f, \"i_units\": %.3f, \"true\": %.3f}",
                             j ? ", " : "", zone_x[j], r.zone_i[j], r.zone_true[j]);
            else
                std::fprintf(json, "%s{\"x_mm\": %.1f, \"i_units\": null, \"true\": %.3f}",
                             j ? ", " : "", zone_x[j], r.zone_true[j]);
            std::fprintf(zcsv, "%d,%zu,%.1f,%s,%.3f\n", r.index, j, zone_x[j],
                         std::isfinite(r.zone_i[j]) ? fmt("%.3f", r.zone_i[j]).c_str() : "",
                         r.zone_true[j]);
        }
        std::fprintf(json, "]}%s\n", p + 1 < results.size() ? "," : "");
    }
    std::fprintf(json, "  ]\n}\n");
    std::fclose(csv);
    std::fclose(zcsv);
    std::fclose(json);
    std::printf(
        "\nreport written to %s/: sheet<N>_raw.png, sheet<N>_reconstructed.png, "
        "sheet<N>_true.png,\n  fiber_profile.png, zones.png, coil.png, sheets.csv, zones.csv, "
        "report.json\n",
        st.out.c_str());

    flt_gauge_destroy(gauge);
    flt_rules_destroy(rules);
    flt_flatness_destroy(truth_flatness);
    flt_sim_destroy(sim);
    flt_calib_destroy(calib);
    flt_options_destroy(sim_opt);
    flt_options_destroy(gauge_opt);
    flt_options_destroy(flat_opt);
    return results.size() == size_t(st.sheets) ? 0 : 1;
}
