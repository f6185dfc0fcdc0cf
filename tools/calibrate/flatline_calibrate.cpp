// SPDX-License-Identifier: Apache-2.0
// flatline-calibrate: a dual-line-laser sensor's calibration file from
// folders of photos (README.md beside this file has the procedure):
//
//   flatline-calibrate --boards DIR --target chessboard:9x6:25
//       --laser0 DIR [--laser0-boards DIR] --laser1 DIR [--laser1-boards DIR]
//       --encoder-mm-per-count 0.01 -o sensor.json [--report DIR]
//
// 1. Camera intrinsics from the board photos (the library's
//    flt_calib_estimate_intrinsics: OpenCV's detection and calibrateCamera).
// 2. Per laser photo, the board's pose (the board detected in the photo, or
//    in the photo of the same number in --laserL-boards taken without the
//    laser) and the laser line's points on it (brightest pixel per column
//    or row, sub-pixel centroid, inside the board, straight after
//    undistortion): 3D points on the laser plane, in the camera's frame.
// 3. A plane per laser through those points (least squares), and the
//    sensor frame from the reference board (the first laser-0 photo's, or
//    --reference): x along the board's x axis, z up from its plane; the
//    lasers' offsets along travel are where their planes cross the board.
// 4. Per laser, a homography from points of that plane (x, z) projected
//    into the image (flt_calib_estimate_homography), the offsets, the
//    encoder scale and the fiber grid; flt_calib_finish, flt_calib_save.
//
// It refuses, with every reason, when the photos cannot give a good
// calibration: too few board views, boards that leave much of the image
// uncovered, reprojection errors too large, too few laser photos or
// photos too alike to fix a plane, points too far from their plane, laser
// spacing other than the one given. The report (index.html and PNG
// figures) is written either way.
//
// Exit status: 0 written, 1 failed (a file, an error of the library),
// 2 usage, 3 refused (the report says why).
#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <numeric>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "flatline/flatline.h"

namespace fs = std::filesystem;

namespace {

constexpr int k_exit_written = 0, k_exit_failed = 1, k_exit_usage = 2, k_exit_refused = 3;
const double k_nan = std::numeric_limits<double>::quiet_NaN();

const char k_usage[] = R"(usage: flatline-calibrate --boards DIR --target KIND:COLSxROWS:PITCH
                         --laser0 DIR --laser1 DIR --encoder-mm-per-count MM
                         -o sensor.json [options]

  --boards DIR             photos of the board for the camera's intrinsics (8-bit
                           PNG, JPEG, TIFF, BMP; colour is converted to grey)
  --target SPEC            chessboard:9x6:25 (inner corners, square mm),
                           circles:7x7:37.5 (symmetric grid, spacing mm),
                           acircles:4x11:20 (OpenCV's asymmetric grid, half spacing)
  --laser-target SPEC      the board under the lasers, when it is another (default
                           --target): a larger one spans more of the field
  --laser0 DIR, --laser1 DIR   photos of the board with laser 0 (1) on
  --laser0-boards DIR, --laser1-boards DIR
                           the same poses without the laser (paired by the number
                           in the file name): the board is found there and the line
                           in the difference
  --reference FILE         the photo whose board defines the sensor frame: lying on
                           the pass line, x axis across the strip, y along travel
                           (default: the first laser-0 photo)
  --laser-offsets A,B      the lasers' offsets along travel, mm; checked against the
                           spacing the photos show (default: from the photos)
  --encoder-mm-per-count MM   the encoder scale (required)
  --fibers FIRST,PITCH,COUNT  the fiber grid, mm (default: across what the lines
                           cover on the boards, --fiber-pitch apart)
  --fiber-pitch MM         default 2
  --z-range MM             heights the homographies are fitted over, +-MM (default 100)
  -o, --output FILE        the calibration file
  --report DIR             the report (default: the output's name + "_report")
  --min-views N            fewest usable board views (default 8)
  --min-coverage F         share of the image's 6x6 cells the boards must reach
                           (default 0.5)
  --max-rms PX             largest reprojection RMS of the intrinsics (default 0.5)
  --max-plane-rms MM       largest RMS distance of the laser points from their
                           plane (default 0.5)
  --min-laser-photos N     fewest laser photos with a line per laser (default 3)
  -h, --help               this text

exit status: 0 written, 1 failed, 2 usage, 3 refused (the report says why)
)";

struct target_spec {
    flt_calib_target kind = FLT_TARGET_CHESSBOARD;
    int columns = 0, rows = 0;
    double pitch_mm = 0;
    std::string text;
};

struct settings {
    std::string boards, laser_dir[2], laser_boards[2], reference, output, report;
    target_spec target, laser_target;  // laser_target.columns 0: --target's
    bool offsets_given = false, fibers_given = false;
    double offsets[2] = {0, 0};
    double encoder = k_nan;
    double fiber_first = 0, fiber_pitch = 2.0;
    std::size_t fiber_count = 0;
    double z_range = 100.0;
    int min_views = 8;
    double min_coverage = 0.5, max_rms = 0.5, max_plane_rms = 0.5;
    int min_laser_photos = 3;
};

// Numbers from the command line are read with std::strtod in the "C"
// locale (the tool never calls setlocale).
bool parse_number(const std::string &text, double &out) {
    if (text.empty())
        return false;
    char *end = nullptr;
    errno = 0;
    out = std::strtod(text.c_str(), &end);
    return errno == 0 && end && *end == '\0' && std::isfinite(out);
}

bool parse_list(const std::string &text, std::vector<double> &out, std::size_t n) {
    out.clear();
    std::stringstream ss(text);
    std::string part;
    while (std::getline(ss, part, ',')) {
        double v;
        if (!parse_number(part, v))
            return false;
        out.push_back(v);
    }
    return out.size() == n;
}

bool parse_target(const std::string &text, target_spec &t) {
    t.text = text;
    const auto c1 = text.find(':'), x = text.find('x', c1 + 1),
               c2 = text.find(':', c1 == std::string::npos ? 0 : c1 + 1);
    if (c1 == std::string::npos || x == std::string::npos || c2 == std::string::npos || x > c2)
        return false;
    const std::string kind = text.substr(0, c1);
    if (kind == "chessboard")
        t.kind = FLT_TARGET_CHESSBOARD;
    else if (kind == "circles")
        t.kind = FLT_TARGET_CIRCLE_GRID;
    else if (kind == "acircles")
        t.kind = FLT_TARGET_ASYMMETRIC_CIRCLE_GRID;
    else
        return false;
    double c, r;
    if (!parse_number(text.substr(c1 + 1, x - c1 - 1), c) ||
        !parse_number(text.substr(x + 1, c2 - x - 1), r) ||
        !parse_number(text.substr(c2 + 1), t.pitch_mm))
        return false;
    t.columns = int(c);
    t.rows = int(r);
    return c == t.columns && r == t.rows && t.columns >= 3 && t.rows >= 3 && t.columns <= 100 &&
           t.rows <= 100 && t.pitch_mm > 0 && t.pitch_mm <= 1000;
}

// The board's corner or circle centres in its own frame, mm (z = 0), in
// the order OpenCV's detectors return them (the library's own layout).
std::vector<cv::Point3f> object_points(const target_spec &t) {
    std::vector<cv::Point3f> pts;
    for (int r = 0; r < t.rows; ++r)
        for (int c = 0; c < t.columns; ++c) {
            if (t.kind == FLT_TARGET_ASYMMETRIC_CIRCLE_GRID)
                pts.emplace_back(float((2 * c + r % 2) * t.pitch_mm), float(r * t.pitch_mm), 0.f);
            else
                pts.emplace_back(float(c * t.pitch_mm), float(r * t.pitch_mm), 0.f);
        }
    return pts;
}

// ---------------------------------------------------------------------------
// Photos
// ---------------------------------------------------------------------------

struct photo {
    std::string path, name;
    cv::Mat grey;  // 8-bit
};

bool is_image(const fs::path &p) {
    std::string e = p.extension().string();
    std::transform(e.begin(), e.end(), e.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return e == ".png" || e == ".jpg" || e == ".jpeg" || e == ".tif" || e == ".tiff" || e == ".bmp";
}

// The number in a file name ("light10.jpg" -> 10), -1 without one.
long number_in(const std::string &name) {
    long v = -1;
    for (std::size_t i = 0; i < name.size(); ++i)
        if (std::isdigit(static_cast<unsigned char>(name[i]))) {
            std::size_t j = i;
            v = 0;
            while (j < name.size() && std::isdigit(static_cast<unsigned char>(name[j])))
                v = v * 10 + (name[j++] - '0');
            i = j;
        }
    return v;
}

// Photos of a folder, in the order of the number in their names (then by
// name), read as 8-bit grey.
bool read_folder(const std::string &dir, std::vector<photo> &out, std::string &why) {
    std::error_code ec;
    if (!fs::is_directory(fs::u8path(dir), ec)) {
        why = "'" + dir + "' is not a folder";
        return false;
    }
    std::vector<fs::path> files;
    for (const auto &e : fs::directory_iterator(fs::u8path(dir), ec))
        if (e.is_regular_file() && is_image(e.path()))
            files.push_back(e.path());
    std::sort(files.begin(), files.end(), [](const fs::path &a, const fs::path &b) {
        const long na = number_in(a.filename().string()), nb = number_in(b.filename().string());
        return na != nb ? na < nb : a.filename() < b.filename();
    });
    if (files.empty()) {
        why = "no photo (PNG, JPEG, TIFF, BMP) in '" + dir + "'";
        return false;
    }
    for (const auto &f : files) {
        photo p;
        p.path = f.u8string();
        p.name = f.filename().u8string();
        // imread takes a narrow path: on Windows read the bytes ourselves
        std::ifstream in(f, std::ios::binary);
        std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
        if (!bytes.empty())
            p.grey = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
        if (p.grey.empty() || p.grey.depth() != CV_8U) {
            why = "cannot read '" + p.path + "' as an 8-bit image";
            return false;
        }
        out.push_back(std::move(p));
    }
    return true;
}

// ---------------------------------------------------------------------------
// Boards
// ---------------------------------------------------------------------------

struct camera_model {
    cv::Mat k = cv::Mat::eye(3, 3, CV_64F);
    cv::Mat dist = cv::Mat::zeros(1, 8, CV_64F);
};

struct board_pose {
    bool found = false;
    std::vector<cv::Point2f> corners;  // raw image points
    cv::Mat r, t;                      // board -> camera (3x3, 3x1)
    double rms_px = k_nan;             // this tool's reprojection of the pose
};

bool detect(const cv::Mat &grey, const target_spec &t, std::vector<cv::Point2f> &found) {
    const cv::Size pattern{t.columns, t.rows};
    if (t.kind == FLT_TARGET_CHESSBOARD) {
        if (!cv::findChessboardCorners(grey, pattern, found,
                                       cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE |
                                           cv::CALIB_CB_FAST_CHECK))
            return false;
        // the library's sub-pixel window: 40 % of the nearest corner spacing
        double nearest = std::numeric_limits<double>::infinity();
        for (std::size_t i = 0; i + 1 < found.size(); ++i)
            if ((i + 1) % std::size_t(t.columns) != 0)
                nearest = std::min(nearest, double(cv::norm(found[i + 1] - found[i])));
        const int half = std::clamp(int(nearest * 0.4), 2, 15);
        cv::cornerSubPix(
            grey, found, cv::Size(half, half), cv::Size(-1, -1),
            cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
        return true;
    }
    return cv::findCirclesGrid(grey, pattern, found,
                               t.kind == FLT_TARGET_CIRCLE_GRID ? cv::CALIB_CB_SYMMETRIC_GRID
                                                                : cv::CALIB_CB_ASYMMETRIC_GRID);
}

board_pose pose_of(const cv::Mat &grey, const target_spec &t, const camera_model &cam) {
    board_pose p;
    if (!detect(grey, t, p.corners))
        return p;
    const std::vector<cv::Point3f> obj = object_points(t);
    if (p.corners.size() != obj.size())
        return p;
    cv::Mat rvec, tvec;
    if (!cv::solvePnP(obj, p.corners, cam.k, cam.dist, rvec, tvec, false, cv::SOLVEPNP_ITERATIVE))
        return p;
    cv::Rodrigues(rvec, p.r);
    p.t = tvec;
    std::vector<cv::Point2f> back;
    cv::projectPoints(obj, rvec, tvec, cam.k, cam.dist, back);
    double sum = 0;
    for (std::size_t i = 0; i < back.size(); ++i)
        sum += std::pow(cv::norm(back[i] - p.corners[i]), 2);
    p.rms_px = std::sqrt(sum / double(back.size()));
    p.found = true;
    return p;
}

// ---------------------------------------------------------------------------
// Laser lines
// ---------------------------------------------------------------------------

// Sub-pixel centres of the brightest stripe along one direction: per
// column (along_rows = false: the line runs across the columns) the
// brightest pixel, where it rises `threshold` grey levels above the
// column's median, refined by the Gaussian through it and its neighbours
// (or, saturated or wide, the centroid of the part above half its rise).
std::vector<cv::Point2d> line_points(const cv::Mat &img, bool along_rows, double threshold) {
    std::vector<cv::Point2d> pts;
    const int lines = along_rows ? img.rows : img.cols, length = along_rows ? img.cols : img.rows;
    std::vector<int> v(std::size_t(length), 0), sorted;
    for (int line = 0; line < lines; ++line) {
        for (int i = 0; i < length; ++i)
            v[std::size_t(i)] = along_rows ? img.at<uchar>(line, i) : img.at<uchar>(i, line);
        const auto peak_it = std::max_element(v.begin(), v.end());
        const int peak = *peak_it, at = int(peak_it - v.begin());
        sorted = v;
        std::nth_element(sorted.begin(), sorted.begin() + length / 2, sorted.end());
        const int median = sorted[std::size_t(length / 2)];
        if (peak - median < threshold)
            continue;
        const double half = median + 0.5 * (peak - median);
        int lo = at, hi = at;
        while (lo > 0 && v[std::size_t(lo - 1)] >= half)
            --lo;
        while (hi + 1 < length && v[std::size_t(hi + 1)] >= half)
            ++hi;
        if (hi - lo > 40)  // a bright patch, not a line
            continue;
        double centre;
        const double left = at > 0 ? v[std::size_t(at - 1)] - median : 0,
                     right = at + 1 < length ? v[std::size_t(at + 1)] - median : 0,
                     top = peak - median;
        if (peak < 255 && left > 0 && right > 0 && left < top && right < top) {
            // A line a pixel or two wide: the Gaussian through the peak and
            // its neighbours (a centroid of so few pixels leans towards the
            // peak's row by up to a third of a pixel).
            const double a = std::log(left), b = std::log(top), c = std::log(right);
            centre = at + 0.5 * (a - c) / (a - 2 * b + c);
        } else {
            // saturated or wide: the centroid of the part above half
            double sw = 0, sum = 0;
            for (int k = lo; k <= hi; ++k) {
                const double w = v[std::size_t(k)] - median;
                sw += w;
                sum += w * k;
            }
            centre = sum / sw;
        }
        pts.push_back(along_rows ? cv::Point2d(centre, line) : cv::Point2d(line, centre));
    }
    return pts;
}

struct laser_photo {
    std::string name;
    board_pose pose;
    std::vector<cv::Point2d> raw;        // line points on the board, raw px
    std::vector<cv::Point3d> camera;     // the same on the board plane, camera frame, mm
    std::vector<double> plane_distance;  // from the fitted plane, mm
    std::string skipped;                 // why it gave no points
};

struct plane {
    cv::Vec3d n, p;  // unit normal, a point (camera frame, mm)
    double rms = k_nan;
    double spread_mm = 0;  // the points' spread across their lines (conditioning)
    std::size_t points = 0;
};

// Least-squares plane through points: the normal is the direction of the
// smallest spread (SVD of the centred points).
plane fit_plane(const std::vector<cv::Point3d> &pts) {
    plane pl;
    pl.points = pts.size();
    if (pts.size() < 3)
        return pl;
    cv::Vec3d c(0, 0, 0);
    for (const auto &q : pts)
        c += cv::Vec3d(q.x, q.y, q.z);
    c *= 1.0 / double(pts.size());
    cv::Mat a(int(pts.size()), 3, CV_64F);
    for (int i = 0; i < a.rows; ++i) {
        a.at<double>(i, 0) = pts[std::size_t(i)].x - c[0];
        a.at<double>(i, 1) = pts[std::size_t(i)].y - c[1];
        a.at<double>(i, 2) = pts[std::size_t(i)].z - c[2];
    }
    cv::SVD svd(a, cv::SVD::MODIFY_A);
    pl.n = cv::Vec3d(svd.vt.at<double>(2, 0), svd.vt.at<double>(2, 1), svd.vt.at<double>(2, 2));
    pl.p = c;
    pl.rms = svd.w.at<double>(2) / std::sqrt(double(pts.size()));
    // the second direction's RMS spread: points of one line only have none
    pl.spread_mm = svd.w.at<double>(1) / std::sqrt(double(pts.size()));
    return pl;
}

// ---------------------------------------------------------------------------
// The report's pictures (OpenCV drawing; BGR)
// ---------------------------------------------------------------------------

const cv::Scalar k_ink(40, 40, 40), k_grid(220, 220, 220), k_good(60, 150, 60),
    k_bad(40, 40, 200), k_laser[2] = {cv::Scalar(0, 200, 0), cv::Scalar(255, 170, 0)};

void text(cv::Mat &img, const std::string &s, cv::Point at, double scale = 0.45,
          const cv::Scalar &colour = k_ink) {
    cv::putText(img, s, at, cv::FONT_HERSHEY_SIMPLEX, scale, colour, 1, cv::LINE_AA);
}

std::string fmt(const char *f, double v) {
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

// A bar per board photo: its reprojection RMS (px), the limit dashed.
cv::Mat residual_chart(const std::vector<std::string> &names, const std::vector<double> &rms,
                       double limit) {
    const int w = 60 + 40 * int(names.size()) + 20, h = 320, x0 = 60, y0 = 260;
    cv::Mat img(h, std::max(w, 400), CV_8UC3, cv::Scalar(255, 255, 255));
    double top = limit * 1.5;
    for (double v : rms)
        if (std::isfinite(v))
            top = std::max(top, v * 1.1);
    auto y_of = [&](double v) {
        return int(y0 - 220 * v / top);
    };
    for (int k = 0; k <= 4; ++k) {
        const double v = top * k / 4;
        cv::line(img, {x0, y_of(v)}, {img.cols - 10, y_of(v)}, k_grid);
        text(img, fmt("%.2f", v), {5, y_of(v) + 4}, 0.4);
    }
    for (int x = x0; x < img.cols - 10; x += 12)
        cv::line(img, {x, y_of(limit)}, {x + 6, y_of(limit)}, k_bad, 1);
    text(img, "limit " + fmt("%.2f px", limit), {img.cols - 120, y_of(limit) - 5}, 0.4, k_bad);
    for (std::size_t i = 0; i < names.size(); ++i) {
        const int x = x0 + 10 + 40 * int(i);
        if (std::isfinite(rms[i])) {
            cv::rectangle(img, {x, y_of(rms[i])}, {x + 24, y0}, rms[i] <= limit ? k_good : k_bad,
                          cv::FILLED);
        } else {
            text(img, "not", {x, y0 - 20}, 0.35, k_bad);
            text(img, "found", {x - 4, y0 - 8}, 0.35, k_bad);
        }
        cv::Mat label(16, 80, CV_8UC3, cv::Scalar(255, 255, 255));
        text(label, names[i].substr(0, 12), {0, 12}, 0.35);
        cv::Mat turned;
        cv::rotate(label, turned, cv::ROTATE_90_COUNTERCLOCKWISE);
        const int rows = std::min(turned.rows, h - y0 - 2);
        turned(cv::Rect(0, turned.rows - rows, 16, rows))
            .copyTo(img(cv::Rect(x + 4, y0 + 2, 16, rows)));
    }
    cv::line(img, {x0, y0}, {img.cols - 10, y0}, k_ink);
    text(img, "reprojection RMS per board photo, px", {x0, 18}, 0.5);
    return img;
}

// The boards' corners over the image, and the 6 x 6 cells they reach.
cv::Mat coverage_map(cv::Size frame, const std::vector<std::vector<cv::Point2f>> &corners,
                     const std::vector<std::vector<bool>> &cells) {
    const double scale = 640.0 / std::max(frame.width, frame.height);
    cv::Mat img(int(frame.height * scale) + 30, int(frame.width * scale), CV_8UC3,
                cv::Scalar(255, 255, 255));
    const int ch = int(frame.height * scale), cw = img.cols;
    for (int r = 0; r < 6; ++r)
        for (int c = 0; c < 6; ++c) {
            const cv::Rect cell(c * cw / 6, r * ch / 6, cw / 6, ch / 6);
            cv::rectangle(img, cell,
                          cells[std::size_t(r)][std::size_t(c)] ? cv::Scalar(225, 245, 225)
                                                                : cv::Scalar(225, 225, 250),
                          cv::FILLED);
            cv::rectangle(img, cell, k_grid);
        }
    for (std::size_t v = 0; v < corners.size(); ++v) {
        const cv::Scalar colour((37 * v) % 200, (91 * v + 60) % 200, (151 * v + 30) % 200);
        for (const auto &p : corners[v])
            cv::circle(img, {int(p.x * scale), int(p.y * scale)}, 2, colour, cv::FILLED);
    }
    cv::rectangle(img, {0, 0}, {cw - 1, ch - 1}, k_ink);
    text(img, "board corners of every view over the frame (green cells reached)", {4, ch + 20},
         0.45);
    return img;
}

// Distance of each laser point from its plane, by photo.
cv::Mat plane_chart(int laser, const std::vector<laser_photo> &photos, const plane &pl,
                    double limit) {
    const int w = 640, h = 300, x0 = 60, y0 = 150;
    cv::Mat img(h, w, CV_8UC3, cv::Scalar(255, 255, 255));
    double top = std::max(limit * 2, 0.05);
    for (const auto &p : photos)
        for (double d : p.plane_distance)
            top = std::max(top, std::abs(d) * 1.1);
    auto y_of = [&](double d) {
        return int(y0 - 110 * d / top);
    };
    for (int k = -2; k <= 2; ++k) {
        const double v = top * k / 2;
        cv::line(img, {x0, y_of(v)}, {w - 10, y_of(v)}, k_grid);
        text(img, fmt("%+.2f", v), {5, y_of(v) + 4}, 0.4);
    }
    std::size_t total = 0;
    for (const auto &p : photos)
        total += p.plane_distance.size();
    std::size_t i = 0;
    for (std::size_t k = 0; k < photos.size(); ++k) {
        const cv::Scalar colour = k % 2 ? k_laser[laser] : k_laser[laser] * 0.6;
        for (double d : photos[k].plane_distance) {
            const int x = x0 + int(double(w - x0 - 20) * double(i++) /
                                   double(std::max<std::size_t>(total, 1)));
            cv::circle(img, {x, y_of(d)}, 1, colour, cv::FILLED);
        }
    }
    text(img,
         "laser " + std::to_string(laser) +
             ": distance of the line points from the plane, mm "
             "(photo after photo)",
         {x0, 18}, 0.45);
    text(img,
         "RMS " + fmt("%.3f mm", pl.rms) + " over " + std::to_string(pl.points) +
             " points, limit " + fmt("%.2f mm", limit),
         {x0, h - 12}, 0.45, pl.rms <= limit ? k_good : k_bad);
    return img;
}

// ---------------------------------------------------------------------------
// The run
// ---------------------------------------------------------------------------

struct run {
    settings s;
    std::vector<std::string> refusals, notes;
    cv::Size frame;
    camera_model cam;
    std::vector<photo> boards;
    std::vector<double> view_rms;
    double intrinsics_rms = k_nan;
    double coverage = 0;
    std::vector<std::vector<cv::Point2f>> board_corners;
    std::vector<std::vector<bool>> cells = std::vector<std::vector<bool>>(6, std::vector<bool>(6));
    std::vector<laser_photo> lasers[2];
    std::vector<photo> laser_images[2];
    plane planes[2];
    bool have_plane[2] = {false, false};
    // the sensor frame, from the reference board (camera frame): origin,
    // x (across), y (along travel), z (up, towards the camera)
    cv::Vec3d origin, ex, ey, ez;
    bool have_frame = false;
    std::string reference_name;
    double measured_offset[2] = {k_nan, k_nan};
    double offsets[2] = {k_nan, k_nan};
    double homography_rms_mm[2] = {k_nan, k_nan};
    double check_rms_mm[2] = {k_nan, k_nan};  // the lines' heights through the calibration
    double x_extent[2] = {k_nan, k_nan};
    flt_calib *calib = nullptr;
    bool written = false;
    run() = default;
    run(const run &) = delete;
    run &operator=(const run &) = delete;
    ~run() { flt_calib_destroy(calib); }
};

cv::Vec3d col(const cv::Mat &m, int c) {
    return {m.at<double>(0, c), m.at<double>(1, c), m.at<double>(2, c)};
}

cv::Vec3d vec(const cv::Mat &m) {
    return {m.at<double>(0), m.at<double>(1), m.at<double>(2)};
}

int lib_failed(const char *what, flt_status st) {
    std::fprintf(stderr, "flatline-calibrate: %s: %s (%s)\n", what, flt_last_error_message(),
                 flt_status_string(st));
    return k_exit_failed;
}

int intrinsics(run &r) {
    std::string why;
    if (!read_folder(r.s.boards, r.boards, why)) {
        std::fprintf(stderr, "flatline-calibrate: --boards: %s\n", why.c_str());
        return k_exit_failed;
    }
    r.frame = r.boards[0].grey.size();
    for (const auto &b : r.boards)
        if (b.grey.size() != r.frame) {
            std::fprintf(stderr, "flatline-calibrate: %s is %dx%d, the first board photo %dx%d\n",
                         b.path.c_str(), b.grey.cols, b.grey.rows, r.frame.width, r.frame.height);
            return k_exit_failed;
        }
    std::printf("board photos: %zu of %dx%d px in %s\n", r.boards.size(), r.frame.width,
                r.frame.height, r.s.boards.c_str());
    flt_status st = flt_calib_create(&r.calib);
    if (st == FLT_OK)
        st = flt_calib_set_frame_size(r.calib, uint32_t(r.frame.width), uint32_t(r.frame.height));
    if (st != FLT_OK)
        return lib_failed("the calibration", st);
    std::vector<cv::Mat> continuous;
    std::vector<const uint8_t *> images;
    for (const auto &b : r.boards) {
        continuous.push_back(b.grey.isContinuous() ? b.grey : b.grey.clone());
        images.push_back(continuous.back().data);
    }
    r.view_rms.assign(r.boards.size(), k_nan);
    std::printf("finding the board in each photo and fitting the camera (OpenCV)...\n");
    std::fflush(stdout);
    st = flt_calib_estimate_intrinsics(r.calib, images.size(), images.data(), size_t(r.frame.width),
                                       r.s.target.kind, uint32_t(r.s.target.columns),
                                       uint32_t(r.s.target.rows), r.s.target.pitch_mm, nullptr,
                                       &r.intrinsics_rms, r.view_rms.data());
    std::size_t used = 0;
    for (double v : r.view_rms)
        used += std::isfinite(v);
    if (st == FLT_ERR_NUMERIC) {
        r.refusals.push_back(std::string("the camera could not be fitted: ") +
                             flt_last_error_message());
        return 0;
    }
    if (st != FLT_OK)
        return lib_failed("the intrinsics", st);
    double cam[4], dist[8];
    st = flt_calib_get_intrinsics(r.calib, cam, 4, dist, 8);
    if (st != FLT_OK)
        return lib_failed("the intrinsics", st);
    r.cam.k.at<double>(0, 0) = cam[0];
    r.cam.k.at<double>(1, 1) = cam[1];
    r.cam.k.at<double>(0, 2) = cam[2];
    r.cam.k.at<double>(1, 2) = cam[3];
    for (int i = 0; i < 8; ++i)
        r.cam.dist.at<double>(i) = dist[i];
    std::printf("camera: fx %.2f fy %.2f cx %.2f cy %.2f px; k1 %.4f k2 %.4f p1 %.5f p2 %.5f "
                "k3 %.4f; reprojection RMS %.3f px over %zu of %zu photos\n",
                cam[0], cam[1], cam[2], cam[3], dist[0], dist[1], dist[2], dist[3], dist[4],
                r.intrinsics_rms, used, r.boards.size());
    if (int(used) < r.s.min_views)
        r.refusals.push_back("too few views: the board was found in " + std::to_string(used) +
                             " of " + std::to_string(r.boards.size()) + " board photos; " +
                             std::to_string(r.s.min_views) +
                             " or more are needed (--min-views), tilted in different directions");
    if (!(r.intrinsics_rms <= r.s.max_rms))
        r.refusals.push_back("residuals too large: the reprojection RMS is " +
                             fmt("%.3f px", r.intrinsics_rms) + ", above " +
                             fmt("%.3g px", r.s.max_rms) +
                             " (--max-rms): blurred or bent boards, or a wrong --target");
    for (std::size_t i = 0; i < r.boards.size(); ++i)
        if (std::isfinite(r.view_rms[i]) && r.view_rms[i] > 2 * r.s.max_rms)
            r.notes.push_back("board photo " + r.boards[i].name + " reprojects with " +
                              fmt("%.2f px", r.view_rms[i]) + ": leave it out if it is blurred");
    // coverage: the corners of the detected boards over a 6 x 6 grid
    for (std::size_t i = 0; i < r.boards.size(); ++i) {
        if (!std::isfinite(r.view_rms[i]))
            continue;
        std::vector<cv::Point2f> found;
        if (!detect(r.boards[i].grey, r.s.target, found))
            continue;
        for (const auto &p : found) {
            const int c = std::clamp(int(6 * p.x / r.frame.width), 0, 5),
                      rr = std::clamp(int(6 * p.y / r.frame.height), 0, 5);
            r.cells[std::size_t(rr)][std::size_t(c)] = true;
        }
        r.board_corners.push_back(std::move(found));
    }
    int reached = 0;
    for (const auto &row : r.cells)
        reached += int(std::count(row.begin(), row.end(), true));
    r.coverage = reached / 36.0;
    std::printf("coverage: the boards reach %d of the image's 36 cells (%.0f %%)\n", reached,
                100 * r.coverage);
    if (r.coverage < r.s.min_coverage)
        r.refusals.push_back("poor coverage: the boards reach " + fmt("%.0f %%", 100 * r.coverage) +
                             " of the image (6 x 6 cells), less than " +
                             fmt("%.0f %%", 100 * r.s.min_coverage) +
                             " (--min-coverage): the lens's distortion is only known where "
                             "boards were; show the board near the edges and corners too");
    return 0;
}

int laser_points(run &r, int laser) {
    if (r.s.laser_dir[laser].empty()) {
        r.refusals.push_back("laser " + std::to_string(laser) + ": no photos (--laser" +
                             std::to_string(laser) + "): a calibration needs both laser planes");
        return 0;
    }
    std::string why;
    std::vector<photo> photos, boards;
    if (!read_folder(r.s.laser_dir[laser], photos, why)) {
        std::fprintf(stderr, "flatline-calibrate: --laser%d: %s\n", laser, why.c_str());
        return k_exit_failed;
    }
    if (!r.s.laser_boards[laser].empty() && !read_folder(r.s.laser_boards[laser], boards, why)) {
        std::fprintf(stderr, "flatline-calibrate: --laser%d-boards: %s\n", laser, why.c_str());
        return k_exit_failed;
    }
    std::map<long, const photo *> by_number;
    for (const auto &b : boards)
        by_number[number_in(b.name)] = &b;
    int with_line = 0;
    for (const auto &p : photos) {
        laser_photo lp;
        lp.name = p.name;
        if (p.grey.size() != r.frame) {
            lp.skipped = "its size differs from the board photos'";
            r.lasers[laser].push_back(lp);
            continue;
        }
        const photo *board = nullptr;
        if (!boards.empty()) {
            auto it = by_number.find(number_in(p.name));
            if (it == by_number.end() && boards.size() == photos.size())
                board = &boards[std::size_t(&p - photos.data())];
            else if (it != by_number.end())
                board = it->second;
            if (!board) {
                lp.skipped = "no board photo of the same number";
                r.lasers[laser].push_back(lp);
                continue;
            }
        }
        lp.pose = pose_of(board ? board->grey : p.grey, r.s.laser_target, r.cam);
        if (!lp.pose.found) {
            lp.skipped = "the board was not found";
            r.lasers[laser].push_back(lp);
            continue;
        }
        // A pose that does not reproject its own corners (a corner found in
        // the wrong place, a bent or moving board) would put the whole
        // line at the wrong depth: left out. The bound: 4 times the RMS
        // with which the camera's fit reprojects its boards, at least
        // 0.5 px (a pose is fitted to one board; the camera to all).
        const double pose_limit = std::max(0.5, 4 * r.intrinsics_rms);
        if (!(lp.pose.rms_px <= pose_limit)) {
            lp.skipped = "the board's pose reprojects its corners with " +
                         fmt("%.2f px", lp.pose.rms_px) + " RMS (more than " +
                         fmt("%.2f px", pose_limit) + "): left out";
            r.lasers[laser].push_back(lp);
            continue;
        }
        // the line: in the difference from the board photo when there is one
        cv::Mat img;
        if (board)
            cv::subtract(p.grey, board->grey, img);  // saturates at 0
        else
            img = p.grey;
        std::vector<cv::Point2d> across = line_points(img, false, 30),
                                 down = line_points(img, true, 30);
        std::vector<cv::Point2d> &pts = across.size() >= down.size() ? across : down;
        // only points on the board: inside the hull of its corners
        std::vector<cv::Point2f> hull;
        cv::convexHull(lp.pose.corners, hull);
        std::vector<cv::Point2d> on;
        for (const auto &q : pts)
            if (cv::pointPolygonTest(hull, cv::Point2f(float(q.x), float(q.y)), false) > 0)
                on.push_back(q);
        if (on.size() < 10) {
            lp.skipped = "no laser line on the board (" + std::to_string(on.size()) + " points)";
            r.lasers[laser].push_back(lp);
            continue;
        }
        // undistort, and keep what lies on one straight line (the board is
        // flat): two rounds of dropping points beyond 3 robust sigmas
        std::vector<double> raw(on.size() * 2), und(on.size() * 2);
        for (std::size_t i = 0; i < on.size(); ++i) {
            raw[2 * i] = on[i].x;
            raw[2 * i + 1] = on[i].y;
        }
        flt_status st = flt_calib_undistort(r.calib, on.size(), raw.data(), und.data());
        if (st != FLT_OK)
            return lib_failed("undistorting the line", st);
        std::vector<bool> keep(on.size(), true);
        for (int round = 0; round < 2; ++round) {
            std::vector<cv::Point2f> kept;
            for (std::size_t i = 0; i < on.size(); ++i)
                if (keep[i] && std::isfinite(und[2 * i]))
                    kept.emplace_back(float(und[2 * i]), float(und[2 * i + 1]));
            if (kept.size() < 10)
                break;
            cv::Vec4f l;
            cv::fitLine(kept, l, cv::DIST_HUBER, 0, 0.01, 0.01);
            std::vector<double> d(on.size());
            std::vector<double> abs_d;
            for (std::size_t i = 0; i < on.size(); ++i) {
                d[i] = std::abs((und[2 * i] - l[2]) * l[1] - (und[2 * i + 1] - l[3]) * l[0]);
                if (keep[i])
                    abs_d.push_back(d[i]);
            }
            std::nth_element(abs_d.begin(), abs_d.begin() + long(abs_d.size() / 2), abs_d.end());
            const double sigma = std::max(1.4826 * abs_d[abs_d.size() / 2], 0.1);
            for (std::size_t i = 0; i < on.size(); ++i)
                keep[i] = keep[i] && std::isfinite(d[i]) && d[i] <= 3 * sigma;
        }
        const cv::Vec3d n = col(lp.pose.r, 2), t0 = vec(lp.pose.t);
        const double fx = r.cam.k.at<double>(0, 0), fy = r.cam.k.at<double>(1, 1),
                     cx = r.cam.k.at<double>(0, 2), cy = r.cam.k.at<double>(1, 2);
        for (std::size_t i = 0; i < on.size(); ++i) {
            if (!keep[i])
                continue;
            // the ray through the undistorted point meets the board's plane
            const cv::Vec3d ray((und[2 * i] - cx) / fx, (und[2 * i + 1] - cy) / fy, 1.0);
            const double s = n.dot(t0) / n.dot(ray);
            const cv::Vec3d q = s * ray;
            lp.raw.push_back(on[i]);
            lp.camera.emplace_back(q[0], q[1], q[2]);
        }
        ++with_line;
        r.lasers[laser].push_back(lp);
        r.laser_images[laser].push_back(p);
    }
    std::printf("laser %d: a line on the board in %d of %zu photos\n", laser, with_line,
                photos.size());
    for (const auto &lp : r.lasers[laser])
        if (!lp.skipped.empty())
            r.notes.push_back("laser " + std::to_string(laser) + " photo " + lp.name + ": " +
                              lp.skipped);
    if (with_line < r.s.min_laser_photos) {
        r.refusals.push_back("laser " + std::to_string(laser) + ": a line on the board in " +
                             std::to_string(with_line) + " photos; " +
                             std::to_string(r.s.min_laser_photos) +
                             " or more are needed (--min-laser-photos), the board at different "
                             "heights and tilts");
        return 0;
    }
    std::vector<cv::Point3d> all;
    for (const auto &lp : r.lasers[laser])
        all.insert(all.end(), lp.camera.begin(), lp.camera.end());
    r.planes[laser] = fit_plane(all);
    plane &pl = r.planes[laser];
    for (auto &lp : r.lasers[laser])
        for (const auto &q : lp.camera)
            lp.plane_distance.push_back((cv::Vec3d(q.x, q.y, q.z) - pl.p).dot(pl.n));
    r.have_plane[laser] = true;
    std::printf("laser %d plane: normal (%.5f, %.5f, %.5f), %.2f mm from the camera; %zu points, "
                "RMS %.3f mm, spread %.1f mm\n",
                laser, pl.n[0], pl.n[1], pl.n[2], std::abs(pl.n.dot(pl.p)), pl.points, pl.rms,
                pl.spread_mm);
    if (pl.rms > r.s.max_plane_rms)
        r.refusals.push_back("laser " + std::to_string(laser) +
                             ": residuals too large: the line points lie " +
                             fmt("%.3f mm", pl.rms) + " RMS from their plane, above " +
                             fmt("%.3g mm", r.s.max_plane_rms) +
                             " (--max-plane-rms): a board that moved between its two photos, "
                             "a bent board, or another light taken for the line");
    // a plane needs lines at different heights: one pose gives one line
    if (pl.spread_mm < 10.0)
        r.refusals.push_back("laser " + std::to_string(laser) +
                             ": poor coverage: the lines lie within " +
                             fmt("%.1f mm", pl.spread_mm) +
                             " of one line (the photos are too alike); raise and tilt the "
                             "board between the photos");
    return 0;
}

// The sensor frame from the reference board, the offsets along travel.
void sensor_frame(run &r) {
    const board_pose *ref = nullptr;
    if (r.s.reference.empty()) {
        for (const auto &lp : r.lasers[0])
            if (lp.pose.found) {
                ref = &lp.pose;
                r.reference_name = lp.name;
                break;
            }
    } else {
        const std::string want = fs::u8path(r.s.reference).filename().u8string();
        for (int l = 0; l < 2 && !ref; ++l)
            for (const auto &lp : r.lasers[l])
                if (lp.name == want && lp.pose.found) {
                    ref = &lp.pose;
                    r.reference_name = lp.name;
                    break;
                }
        for (std::size_t i = 0; i < r.boards.size() && !ref; ++i)
            if (r.boards[i].name == want) {
                static board_pose found;
                found = pose_of(r.boards[i].grey, r.s.target, r.cam);  // an intrinsics board
                if (found.found) {
                    ref = &found;
                    r.reference_name = want;
                }
            }
        if (!ref) {
            r.refusals.push_back("--reference " + r.s.reference +
                                 ": no photo of that name shows the board");
            return;
        }
    }
    if (!ref) {
        if (!r.s.laser_dir[0].empty())
            r.refusals.push_back("no reference board: no laser-0 photo shows the board");
        return;
    }
    r.origin = vec(ref->t);
    r.ex = col(ref->r, 0);
    cv::Vec3d n = col(ref->r, 2);
    // z up: towards the camera (at the camera frame's origin)
    r.ez = n.dot(-r.origin) > 0 ? n : -n;
    r.ey = r.ez.cross(r.ex);
    r.have_frame = true;
    for (int l = 0; l < 2; ++l) {
        if (!r.have_plane[l])
            continue;
        const plane &pl = r.planes[l];
        // where the plane crosses the board's y axis (x = z = 0)
        const double ny = pl.n.dot(r.ey);
        if (std::abs(ny) < 0.2) {
            r.refusals.push_back("laser " + std::to_string(l) +
                                 ": its plane runs along the reference board's y axis: lay the "
                                 "reference board with its x axis across the strip");
            r.have_plane[l] = false;
            continue;
        }
        r.measured_offset[l] = pl.n.dot(pl.p - r.origin) / ny;
    }
}

// The plane point at sensor (x, z) of laser l, camera frame.
cv::Vec3d plane_point(const run &r, int l, double x, double z) {
    const plane &pl = r.planes[l];
    const cv::Vec3d base = r.origin + x * r.ex + z * r.ez;
    const double y = pl.n.dot(pl.p - base) / pl.n.dot(r.ey);
    return base + y * r.ey;
}

int build(run &r) {
    if (!r.have_frame || !r.have_plane[0] || !r.have_plane[1])
        return 0;
    const double spacing = r.measured_offset[1] - r.measured_offset[0];
    std::printf("laser offsets along the reference board's y axis: %.2f and %.2f mm "
                "(spacing %.2f mm)\n",
                r.measured_offset[0], r.measured_offset[1], spacing);
    if (r.s.offsets_given) {
        const double given = r.s.offsets[1] - r.s.offsets[0];
        if (std::abs(std::abs(given) - std::abs(spacing)) > std::max(2.0, 0.02 * std::abs(given)))
            r.refusals.push_back("the photos show the lasers " + fmt("%.2f mm", std::abs(spacing)) +
                                 " apart, --laser-offsets " + fmt("%.2f mm", std::abs(given)) +
                                 " (more than 2 mm or 2 %): check the offsets and that the "
                                 "photos are of these lasers");
        else if (given * spacing < 0)
            r.notes.push_back("the reference board's y axis points against --laser-offsets' "
                              "direction of travel: the given offsets are used");
        r.offsets[0] = r.s.offsets[0];
        r.offsets[1] = r.s.offsets[1];
    } else {
        // centred on the middle between the lasers, as the reference sensor's
        const double mid = 0.5 * (r.measured_offset[0] + r.measured_offset[1]);
        r.offsets[0] = r.measured_offset[0] - mid;
        r.offsets[1] = r.measured_offset[1] - mid;
    }
    // what x the lines covered on the boards
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int l = 0; l < 2; ++l)
        for (const auto &lp : r.lasers[l])
            for (const auto &q : lp.camera) {
                const double x = (cv::Vec3d(q.x, q.y, q.z) - r.origin).dot(r.ex);
                lo = std::min(lo, x);
                hi = std::max(hi, x);
            }
    r.x_extent[0] = lo;
    r.x_extent[1] = hi;
    if (!r.s.fibers_given) {
        r.s.fiber_first = std::ceil(lo / r.s.fiber_pitch) * r.s.fiber_pitch;
        r.s.fiber_count = std::size_t(std::floor((hi - r.s.fiber_first) / r.s.fiber_pitch)) + 1;
    }
    // per laser: points of its plane over the field, projected into the
    // image with the lens, give the homography's correspondences
    for (int l = 0; l < 2; ++l) {
        std::vector<cv::Point3d> world;
        std::vector<double> plane_mm;
        const double margin = 0.1 * (hi - lo);
        for (int i = 0; i <= 40; ++i)
            for (int k = 0; k <= 10; ++k) {
                const double x = lo - margin + (hi - lo + 2 * margin) * i / 40.0;
                const double z = -r.s.z_range + 2 * r.s.z_range * k / 10.0;
                const cv::Vec3d p = plane_point(r, l, x, z);
                if (p[2] <= 1.0)
                    continue;  // behind the camera
                world.emplace_back(p[0], p[1], p[2]);
                plane_mm.push_back(x);
                plane_mm.push_back(z);
            }
        std::vector<cv::Point2d> image;
        cv::projectPoints(world, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), r.cam.k, r.cam.dist,
                          image);
        std::vector<double> image_px, kept_mm;
        for (std::size_t i = 0; i < image.size(); ++i)
            if (image[i].x >= 0 && image[i].y >= 0 && image[i].x <= r.frame.width - 1 &&
                image[i].y <= r.frame.height - 1) {
                image_px.push_back(image[i].x);
                image_px.push_back(image[i].y);
                kept_mm.push_back(plane_mm[2 * i]);
                kept_mm.push_back(plane_mm[2 * i + 1]);
            }
        const std::size_t n = kept_mm.size() / 2;
        if (n < 8) {
            r.refusals.push_back("laser " + std::to_string(l) +
                                 ": its plane hardly crosses the image within the heights of "
                                 "--z-range");
            return 0;
        }
        double rms_px = k_nan;
        flt_status st = flt_calib_estimate_homography(r.calib, unsigned(l), n, image_px.data(),
                                                      kept_mm.data(), nullptr, nullptr, nullptr,
                                                      nullptr, &rms_px, &r.homography_rms_mm[l]);
        if (st == FLT_OK)
            st = flt_calib_set_laser_offset(r.calib, unsigned(l), r.offsets[l]);
        if (st != FLT_OK)
            return lib_failed("the laser plane's homography", st);
    }
    flt_status st = flt_calib_set_encoder_scale(r.calib, r.s.encoder);
    if (st == FLT_OK)
        st = flt_calib_set_fiber_grid(r.calib, r.s.fiber_first, r.s.fiber_pitch, r.s.fiber_count);
    if (st == FLT_OK)
        st = flt_calib_finish(r.calib);
    if (st != FLT_OK) {
        r.refusals.push_back(std::string("the calibration is incomplete: ") +
                             flt_last_error_message());
        return 0;
    }
    // End to end: each photo's line through the finished calibration, its
    // height against the board's height there (mm).
    for (int l = 0; l < 2; ++l) {
        double sum = 0;
        std::size_t n = 0;
        for (const auto &lp : r.lasers[l]) {
            if (lp.raw.empty())
                continue;
            std::vector<double> px, mm(lp.raw.size() * 2);
            for (const auto &q : lp.raw) {
                px.push_back(q.x);
                px.push_back(q.y);
            }
            if (flt_calib_image_to_plane(r.calib, unsigned(l), lp.raw.size(), px.data(),
                                         mm.data()) != FLT_OK)
                continue;
            for (std::size_t i = 0; i < lp.camera.size(); ++i) {
                const cv::Vec3d q(lp.camera[i].x, lp.camera[i].y, lp.camera[i].z);
                const double z_board = (q - r.origin).dot(r.ez);
                if (std::isfinite(mm[2 * i + 1])) {
                    sum += std::pow(mm[2 * i + 1] - z_board, 2);
                    ++n;
                }
            }
        }
        r.check_rms_mm[l] = n ? std::sqrt(sum / double(n)) : k_nan;
    }
    std::printf("through the calibration, the photos' lines lie %.3f / %.3f mm RMS from their "
                "boards' heights (laser 0 / 1)\n",
                r.check_rms_mm[0], r.check_rms_mm[1]);
    return 0;
}

// The fiber grid drawn on a frame (a laser photo): each laser's fibers at
// z = 0 as a line, a tick every few fibers from z = -10 to +10 mm, the
// frame cropped to the grid and enlarged.
cv::Mat fiber_picture(const run &r) {
    const cv::Mat &base = !r.laser_images[0].empty() ? r.laser_images[0][0].grey : r.boards[0].grey;
    double first = 0, pitch = 0;
    size_t count = 0;
    cv::Mat img;
    if (flt_calib_get_fiber_grid(r.calib, &first, &pitch, &count) != FLT_OK || count == 0) {
        cv::cvtColor(base, img, cv::COLOR_GRAY2BGR);
        return img;
    }
    std::vector<double> image[2];
    double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
    for (int l = 0; l < 2; ++l) {
        std::vector<double> plane;
        for (std::size_t k = 0; k < count; ++k)
            for (double z : {-10.0, 0.0, 10.0}) {
                plane.push_back(first + pitch * double(k));
                plane.push_back(z);
            }
        image[l].resize(plane.size());
        if (flt_calib_plane_to_image(r.calib, unsigned(l), plane.size() / 2, plane.data(),
                                     image[l].data()) != FLT_OK) {
            image[l].clear();
            continue;
        }
        for (std::size_t i = 0; i + 1 < image[l].size(); i += 2)
            if (std::isfinite(image[l][i]) && std::isfinite(image[l][i + 1])) {
                x0 = std::min(x0, image[l][i]);
                x1 = std::max(x1, image[l][i]);
                y0 = std::min(y0, image[l][i + 1]);
                y1 = std::max(y1, image[l][i + 1]);
            }
    }
    cv::Rect crop(0, 0, base.cols, base.rows);
    if (x1 >= x0) {
        const double m = 0.15 * std::max(x1 - x0, y1 - y0) + 10;
        crop = cv::Rect(cv::Point(int(x0 - m), int(y0 - m)), cv::Point(int(x1 + m), int(y1 + m))) &
               crop;
        if (crop.width < 2 || crop.height < 2)
            crop = cv::Rect(0, 0, base.cols, base.rows);
    }
    const double scale = 1200.0 / std::max(crop.width, 1);
    cv::Mat grey;
    cv::resize(base(crop), grey, cv::Size(), scale, scale, cv::INTER_LINEAR);
    cv::cvtColor(grey, img, cv::COLOR_GRAY2BGR);
    img = img * 0.6;
    auto at = [&](const double *p) {
        return cv::Point(int((p[0] - crop.x) * scale), int((p[1] - crop.y) * scale));
    };
    const std::size_t step = std::max<std::size_t>(1, count / 60);  // at most ~60 ticks
    for (int l = 0; l < 2; ++l) {
        if (image[l].empty())
            continue;
        for (std::size_t k = 0; k + 1 < count; ++k) {
            const double *a = &image[l][6 * k + 2], *b = &image[l][6 * (k + 1) + 2];
            if (std::isfinite(a[0]) && std::isfinite(b[0]))
                cv::line(img, at(a), at(b), k_laser[l], 2, cv::LINE_AA);
        }
        for (std::size_t k = 0; k < count; k += step) {
            const double *lo = &image[l][6 * k], *hi = &image[l][6 * k + 4];
            if (std::isfinite(lo[0]) && std::isfinite(hi[0]))
                cv::line(img, at(lo), at(hi), k_laser[l], 1, cv::LINE_AA);
        }
    }
    cv::rectangle(img, {0, 0}, {img.cols, 30}, cv::Scalar(0, 0, 0), cv::FILLED);
    text(img,
         "fiber grid at z = 0 on " +
             (!r.laser_images[0].empty() ? r.laser_images[0][0].name : r.boards[0].name) +
             ": laser 0 green, laser 1 blue; a tick (z -10..+10 mm) every " + std::to_string(step) +
             " fibers of " + fmt("%.3g mm", pitch),
         {8, 20}, 0.5, cv::Scalar(255, 255, 255));
    return img;
}

std::string html_escape(const std::string &s) {
    std::string o;
    for (char c : s) {
        switch (c) {
            case '&':
                o += "&amp;";
                break;
            case '<':
                o += "&lt;";
                break;
            case '>':
                o += "&gt;";
                break;
            case '"':
                o += "&quot;";
                break;
            default:
                o += c;
        }
    }
    return o;
}

std::string json_number(double v) {
    if (!std::isfinite(v))
        return "null";
    char b[40];
    std::snprintf(b, sizeof b, "%.10g", v);
    return b;
}

bool write_png(const fs::path &path, const cv::Mat &img) {
    std::vector<unsigned char> bytes;
    if (!cv::imencode(".png", img, bytes))
        return false;
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char *>(bytes.data()), std::streamsize(bytes.size()));
    return bool(out);
}

int report(const run &r) {
    const fs::path dir = fs::u8path(r.s.report);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) {
        std::fprintf(stderr, "flatline-calibrate: cannot create '%s': %s\n", r.s.report.c_str(),
                     ec.message().c_str());
        return k_exit_failed;
    }
    std::vector<std::string> names;
    for (const auto &b : r.boards)
        names.push_back(b.name);
    bool ok = write_png(dir / "residuals.png", residual_chart(names, r.view_rms, r.s.max_rms));
    ok = ok && write_png(dir / "coverage.png", coverage_map(r.frame, r.board_corners, r.cells));
    for (int l = 0; l < 2; ++l)
        if (r.planes[l].points > 0)
            ok = ok && write_png(dir / ("laser" + std::to_string(l) + "_plane.png"),
                                 plane_chart(l, r.lasers[l], r.planes[l], r.s.max_plane_rms));
    if (r.written)
        ok = ok && write_png(dir / "fiber_grid.png", fiber_picture(r));
    std::ofstream html(dir / "index.html");
    html << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
            "<title>flatline-calibrate report</title><style>body{font:14px sans-serif;"
            "margin:16px;max-width:1100px}td,th{padding:2px 8px;text-align:left}"
            ".refused{color:#b00}.ok{color:#060}img{max-width:100%;border:1px solid #ccc}"
            "</style></head><body>\n<h1>Sensor calibration</h1>\n";
    if (r.written)
        html << "<p class=\"ok\"><b>Written:</b> " << html_escape(r.s.output) << "</p>\n";
    else
        html << "<p class=\"refused\"><b>Refused:</b> no calibration file was written.</p>\n";
    if (!r.refusals.empty()) {
        html << "<h2>Why not</h2><ul class=\"refused\">\n";
        for (const auto &why : r.refusals)
            html << "<li>" << html_escape(why) << "</li>\n";
        html << "</ul>\n";
    }
    html << "<h2>Camera</h2><table>\n";
    html << "<tr><th>board photos</th><td>" << r.boards.size() << " in " << html_escape(r.s.boards)
         << ", target " << html_escape(r.s.target.text) << "</td></tr>\n";
    html << "<tr><th>frame</th><td>" << r.frame.width << " x " << r.frame.height
         << " px</td></tr>\n";
    html << "<tr><th>fx, fy, cx, cy</th><td>" << json_number(r.cam.k.at<double>(0, 0)) << ", "
         << json_number(r.cam.k.at<double>(1, 1)) << ", " << json_number(r.cam.k.at<double>(0, 2))
         << ", " << json_number(r.cam.k.at<double>(1, 2)) << " px</td></tr>\n";
    html << "<tr><th>k1 k2 p1 p2 k3</th><td>";
    for (int i = 0; i < 5; ++i)
        html << json_number(r.cam.dist.at<double>(i)) << " ";
    html << "</td></tr>\n<tr><th>reprojection RMS</th><td>" << fmt("%.3f px", r.intrinsics_rms)
         << " (limit " << fmt("%.3g", r.s.max_rms) << ")</td></tr>\n";
    html << "<tr><th>coverage</th><td>" << fmt("%.0f %%", 100 * r.coverage)
         << " of the image (limit " << fmt("%.0f %%", 100 * r.s.min_coverage)
         << ")</td></tr>\n</table>\n";
    html << "<p><img src=\"residuals.png\" alt=\"reprojection RMS per board photo\"></p>\n";
    html << "<p><img src=\"coverage.png\" alt=\"board corners over the frame\"></p>\n";
    html << "<h2>Laser planes</h2><table><tr><th>laser</th><th>photos with a line</th>"
            "<th>points</th><th>RMS from the plane</th><th>offset along travel</th>"
            "<th>lines through the calibration, height RMS</th></tr>\n";
    for (int l = 0; l < 2; ++l) {
        int with = 0;
        for (const auto &lp : r.lasers[l])
            with += !lp.camera.empty();
        html << "<tr><td>" << l << "</td><td>" << with << " of " << r.lasers[l].size()
             << "</td><td>" << r.planes[l].points << "</td><td>" << fmt("%.3f mm", r.planes[l].rms)
             << "</td><td>" << fmt("%.2f mm", r.offsets[l]) << "</td><td>"
             << fmt("%.3f mm", r.check_rms_mm[l]) << "</td></tr>\n";
    }
    html << "</table>\n";
    for (int l = 0; l < 2; ++l)
        if (fs::exists(dir / ("laser" + std::to_string(l) + "_plane.png")))
            html << "<p><img src=\"laser" << l << "_plane.png\" alt=\"laser " << l
                 << " plane fit\"></p>\n";
    if (r.written) {
        html << "<h2>Fiber grid</h2><p>" << r.s.fiber_count << " fibers from "
             << fmt("%.1f mm", r.s.fiber_first) << ", " << fmt("%.3g mm", r.s.fiber_pitch)
             << " apart; sensor frame from " << html_escape(r.reference_name)
             << ".</p><p><img src=\"fiber_grid.png\" alt=\"fiber grid on a frame\"></p>\n";
    }
    if (!r.notes.empty()) {
        html << "<h2>Notes</h2><ul>\n";
        for (const auto &n : r.notes)
            html << "<li>" << html_escape(n) << "</li>\n";
        html << "</ul>\n";
    }
    html << "</body></html>\n";
    // the same numbers for programs
    std::ofstream js(dir / "report.json");
    js << "{\n  \"written\": " << (r.written ? "true" : "false") << ",\n  \"refusals\": [";
    for (std::size_t i = 0; i < r.refusals.size(); ++i) {
        std::string e;
        for (char c : r.refusals[i])
            e += c == '"' || c == '\\' ? std::string("\\") + c : std::string(1, c);
        js << (i ? ", " : "") << "\"" << e << "\"";
    }
    js << "],\n  \"camera\": {\"fx\": " << json_number(r.cam.k.at<double>(0, 0))
       << ", \"fy\": " << json_number(r.cam.k.at<double>(1, 1))
       << ", \"cx\": " << json_number(r.cam.k.at<double>(0, 2))
       << ", \"cy\": " << json_number(r.cam.k.at<double>(1, 2))
       << ", \"rms_px\": " << json_number(r.intrinsics_rms) << "},\n  \"view_rms_px\": [";
    for (std::size_t i = 0; i < r.view_rms.size(); ++i)
        js << (i ? ", " : "") << json_number(r.view_rms[i]);
    js << "],\n  \"coverage\": " << json_number(r.coverage) << ",\n  \"lasers\": [";
    for (int l = 0; l < 2; ++l) {
        const plane &pl = r.planes[l];
        js << (l ? ", " : "") << "{\"points\": " << pl.points << ", \"normal\": ["
           << json_number(pl.n[0]) << ", " << json_number(pl.n[1]) << ", " << json_number(pl.n[2])
           << "], \"point\": [" << json_number(pl.p[0]) << ", " << json_number(pl.p[1]) << ", "
           << json_number(pl.p[2]) << "], \"rms_mm\": " << json_number(pl.rms)
           << ", \"measured_offset_mm\": " << json_number(r.measured_offset[l])
           << ", \"offset_mm\": " << json_number(r.offsets[l])
           << ", \"check_rms_mm\": " << json_number(r.check_rms_mm[l]) << ", \"photos\": [";
        for (std::size_t k = 0; k < r.lasers[l].size(); ++k) {
            const laser_photo &lp = r.lasers[l][k];
            double mean = 0, sq = 0;
            for (double d : lp.plane_distance) {
                mean += d;
                sq += d * d;
            }
            const double n = double(lp.plane_distance.size());
            js << (k ? ", " : "") << "{\"name\": \"" << lp.name
               << "\", \"points\": " << lp.camera.size()
               << ", \"pose_rms_px\": " << json_number(lp.pose.rms_px)
               << ", \"mean_mm\": " << json_number(n ? mean / n : k_nan)
               << ", \"rms_mm\": " << json_number(n ? std::sqrt(sq / n) : k_nan)
               << ", \"camera_points\": [";
            for (std::size_t i = 0; i < lp.camera.size();
                 i += std::max<std::size_t>(1, lp.camera.size() / 20))
                js << (i ? ", " : "") << "[" << json_number(lp.camera[i].x) << ", "
                   << json_number(lp.camera[i].y) << ", " << json_number(lp.camera[i].z) << "]";
            js << "]}";
        }
        js << "]}";
    }
    js << "]\n}\n";
    if (!ok || !html || !js) {
        std::fprintf(stderr, "flatline-calibrate: cannot write the report in '%s'\n",
                     r.s.report.c_str());
        return k_exit_failed;
    }
    std::printf("report: %s\n", (dir / "index.html").u8string().c_str());
    return 0;
}

int parse_args(int argc, char **argv, settings &s) {
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto value = [&](std::string &out) {
            if (i + 1 >= argc) {
                std::fprintf(stderr, "flatline-calibrate: %s needs a value (see --help)\n",
                             a.c_str());
                return false;
            }
            out = argv[++i];
            return true;
        };
        std::string v;
        double d;
        std::vector<double> list;
        if (a == "-h" || a == "--help") {
            std::fputs(k_usage, stdout);
            std::exit(0);
        } else if (a == "--boards") {
            if (!value(s.boards))
                return k_exit_usage;
        } else if (a == "--laser0" || a == "--laser1") {
            if (!value(s.laser_dir[a.back() - '0']))
                return k_exit_usage;
        } else if (a == "--laser0-boards" || a == "--laser1-boards") {
            if (!value(s.laser_boards[a[7] - '0']))
                return k_exit_usage;
        } else if (a == "--reference") {
            if (!value(s.reference))
                return k_exit_usage;
        } else if (a == "-o" || a == "--output") {
            if (!value(s.output))
                return k_exit_usage;
        } else if (a == "--report") {
            if (!value(s.report))
                return k_exit_usage;
        } else if (a == "--target") {
            if (!value(v))
                return k_exit_usage;
            if (!parse_target(v, s.target)) {
                std::fprintf(stderr,
                             "flatline-calibrate: --target '%s' is not KIND:COLSxROWS:PITCH "
                             "(chessboard, circles or acircles; 3..100 each way; pitch in mm)\n",
                             v.c_str());
                return k_exit_usage;
            }
        } else if (a == "--laser-target") {
            if (!value(v))
                return k_exit_usage;
            if (!parse_target(v, s.laser_target)) {
                std::fprintf(stderr,
                             "flatline-calibrate: --laser-target '%s' is not "
                             "KIND:COLSxROWS:PITCH\n",
                             v.c_str());
                return k_exit_usage;
            }
        } else if (a == "--laser-offsets") {
            if (!value(v))
                return k_exit_usage;
            if (!parse_list(v, list, 2) || list[0] == list[1]) {
                std::fprintf(stderr, "flatline-calibrate: --laser-offsets wants two different "
                                     "numbers A,B (mm)\n");
                return k_exit_usage;
            }
            s.offsets_given = true;
            s.offsets[0] = list[0];
            s.offsets[1] = list[1];
        } else if (a == "--fibers") {
            if (!value(v))
                return k_exit_usage;
            if (!parse_list(v, list, 3) || !(list[1] > 0) || list[2] < 1 ||
                list[2] != std::floor(list[2]) || list[2] > 16384) {
                std::fprintf(stderr, "flatline-calibrate: --fibers wants FIRST,PITCH,COUNT "
                                     "(mm, mm > 0, 1..16384)\n");
                return k_exit_usage;
            }
            s.fibers_given = true;
            s.fiber_first = list[0];
            s.fiber_pitch = list[1];
            s.fiber_count = std::size_t(list[2]);
        } else {
            // the numeric options
            struct num {
                const char *name;
                double *out;
                double lo, hi;
            };
            double min_views = s.min_views, min_laser = s.min_laser_photos;
            num nums[] = {{"--encoder-mm-per-count", &s.encoder, -1e6, 1e6},
                          {"--fiber-pitch", &s.fiber_pitch, 1e-3, 1e4},
                          {"--z-range", &s.z_range, 1, 1e4},
                          {"--min-views", &min_views, 3, 1000},
                          {"--min-coverage", &s.min_coverage, 0, 1},
                          {"--max-rms", &s.max_rms, 1e-3, 100},
                          {"--max-plane-rms", &s.max_plane_rms, 1e-4, 100},
                          {"--min-laser-photos", &min_laser, 2, 1000}};
            bool matched = false;
            for (auto &n : nums)
                if (a == n.name) {
                    matched = true;
                    if (!value(v))
                        return k_exit_usage;
                    if (!parse_number(v, d) || d < n.lo || d > n.hi) {
                        std::fprintf(stderr,
                                     "flatline-calibrate: %s wants a number in "
                                     "[%g, %g], not '%s'\n",
                                     n.name, n.lo, n.hi, v.c_str());
                        return k_exit_usage;
                    }
                    *n.out = d;
                }
            if (!matched) {
                std::fprintf(stderr, "flatline-calibrate: unknown option '%s' (see --help)\n",
                             a.c_str());
                return k_exit_usage;
            }
            s.min_views = int(min_views);
            s.min_laser_photos = int(min_laser);
        }
    }
    const char *missing = s.boards.empty()            ? "--boards"
                          : s.target.columns == 0     ? "--target"
                          : s.output.empty()          ? "-o"
                          : !std::isfinite(s.encoder) ? "--encoder-mm-per-count"
                                                      : nullptr;
    if (missing) {
        std::fprintf(stderr, "flatline-calibrate: %s is required (see --help)\n", missing);
        return k_exit_usage;
    }
    if (std::abs(s.encoder) < 1e-9) {
        std::fprintf(stderr, "flatline-calibrate: --encoder-mm-per-count must not be 0\n");
        return k_exit_usage;
    }
    if (s.laser_target.columns == 0)
        s.laser_target = s.target;
    if (s.report.empty()) {
        fs::path out = fs::u8path(s.output);
        s.report = (out.parent_path() / (out.stem().u8string() + "_report")).u8string();
    }
    return 0;
}

int calibrate(int argc, char **argv) {
    run r;
    if (int rc = parse_args(argc, argv, r.s))
        return rc;
    int rc = intrinsics(r);
    const bool camera_ok = !rc && r.calib && std::isfinite(r.intrinsics_rms);
    for (int l = 0; l < 2 && !rc && camera_ok; ++l)
        rc = laser_points(r, l);
    if (!rc && camera_ok) {
        sensor_frame(r);
        rc = build(r);
    }
    if (rc)
        return rc;
    if (r.refusals.empty()) {
        const fs::path parent = fs::u8path(r.s.output).parent_path();
        std::error_code ec;
        if (!parent.empty())
            fs::create_directories(parent, ec);  // (a failure shows in the save)
        const flt_status st = flt_calib_save(r.calib, r.s.output.c_str());
        if (st != FLT_OK) {
            return lib_failed("saving the calibration", st);
        }
        r.written = true;
        std::printf("wrote %s\n", r.s.output.c_str());
    }
    rc = report(r);
    if (rc)
        return rc;
    if (!r.written) {
        std::fprintf(stderr, "flatline-calibrate: refused: no calibration was written:\n");
        for (const auto &why : r.refusals)
            std::fprintf(stderr, "  - %s\n", why.c_str());
        return k_exit_refused;
    }
    return k_exit_written;
}

}  // namespace

int main(int argc, char **argv) {
    try {
        return calibrate(argc, argv);
    } catch (const std::exception &e) {
        std::fprintf(stderr, "flatline-calibrate: failed: %s\n", e.what());
        return k_exit_failed;
    }
}
