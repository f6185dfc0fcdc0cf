// SPDX-License-Identifier: Apache-2.0
// Example: calibrates a dual-line-laser sensor and writes its calibration
// file.
//
//   flt_calibrate OUT.json CORRESPONDENCES.csv VIEW.png [VIEW.png ...]
//
// 1. Camera intrinsics from the target images (chessboard / circle grid,
//    described by the "# target" line of the correspondence file).
// 2. One homography per laser from the correspondence rows
//    "laser,u_px,v_px,x_mm,z_mm" (raw image point -> laser-plane point).
// 3. Sensor geometry from the "# frame", "# laser_offset_mm",
//    "# encoder_mm_per_count" and "# fibers" lines.
// Then it checks the file by loading it back.
//
// The library's API is C; this example is C++ only to read PNGs through
// OpenCV's imgcodecs. The dataset in data/ comes from make_dataset.py.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "flatline/flatline.h"

namespace {

int check(flt_status st, const char *what) {
    if (st == FLT_OK)
        return 0;
    std::fprintf(stderr, "flt_calibrate: %s failed: %s: %s\n", what, flt_status_string(st),
                 flt_last_error_message());
    return 1;
}

struct setup {
    flt_calib_target target = FLT_TARGET_CHESSBOARD;
    unsigned columns = 0, rows = 0;
    double pitch_mm = 0;
    unsigned width = 0, height = 0;
    double offset_mm[2] = {NAN, NAN};
    double encoder_mm_per_count = NAN;
    double first_x_mm = NAN, fiber_pitch_mm = NAN;
    std::size_t fibers = 0;
    std::vector<double> image[2], plane[2];  // per laser, n x 2
};

bool read_correspondences(const char *path, setup *s) {
    std::ifstream in(path);
    if (!in) {
        std::fprintf(stderr, "flt_calibrate: cannot open %s\n", path);
        return false;
    }
    std::string line;
    int line_no = 0;
    while (std::getline(in, line)) {
        ++line_no;
        if (line.empty())
            continue;
        std::istringstream ls(line[0] == '#' ? line.substr(1) : line);
        if (line[0] == '#') {
            std::string key;
            ls >> key;
            if (key == "target") {
                std::string kind;
                ls >> kind >> s->columns >> s->rows >> s->pitch_mm;
                s->target = kind == "circles"    ? FLT_TARGET_CIRCLE_GRID
                            : kind == "acircles" ? FLT_TARGET_ASYMMETRIC_CIRCLE_GRID
                                                 : FLT_TARGET_CHESSBOARD;
            } else if (key == "frame") {
                ls >> s->width >> s->height;
            } else if (key == "laser_offset_mm") {
                ls >> s->offset_mm[0] >> s->offset_mm[1];
            } else if (key == "encoder_mm_per_count") {
                ls >> s->encoder_mm_per_count;
            } else if (key == "fibers") {
                ls >> s->first_x_mm >> s->fiber_pitch_mm >> s->fibers;
            }
            continue;
        }
        if (line.rfind("laser,", 0) == 0)
            continue;  // the column header
        int laser;
        double u, v, x, z;
        char c1, c2, c3, c4;
        if (!(ls >> laser >> c1 >> u >> c2 >> v >> c3 >> x >> c4 >> z) ||
            (laser != 0 && laser != 1)) {
            std::fprintf(stderr, "flt_calibrate: %s:%d: cannot read '%s'\n", path, line_no,
                         line.c_str());
            return false;
        }
        s->image[laser].insert(s->image[laser].end(), {u, v});
        s->plane[laser].insert(s->plane[laser].end(), {x, z});
    }
    return true;
}

}  // namespace

int main(int argc, char **argv) {
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s OUT.json CORRESPONDENCES.csv VIEW.png [VIEW.png ...]\n",
                     argv[0]);
        return 2;
    }
    setup s;
    if (!read_correspondences(argv[2], &s))
        return 1;

    std::vector<cv::Mat> views;
    std::vector<const uint8_t *> pixels;
    for (int i = 3; i < argc; ++i) {
        cv::Mat img = cv::imread(argv[i], cv::IMREAD_GRAYSCALE);
        if (img.empty() || img.cols != int(s.width) || img.rows != int(s.height) ||
            !img.isContinuous()) {
            std::fprintf(stderr, "flt_calibrate: %s is not a %ux%u grey image\n", argv[i], s.width,
                         s.height);
            return 1;
        }
        views.push_back(img);
        pixels.push_back(img.data);
    }

    flt_calib *calib = nullptr;
    if (check(flt_calib_create(&calib), "flt_calib_create"))
        return 1;
    int bad = check(flt_calib_set_frame_size(calib, s.width, s.height), "frame size");

    // 1. intrinsics
    std::vector<double> view_rms(views.size());
    double rms = NAN;
    if (!bad)
        bad = check(flt_calib_estimate_intrinsics(calib, views.size(), pixels.data(), s.width,
                                                  s.target, s.columns, s.rows, s.pitch_mm, nullptr,
                                                  &rms, view_rms.data()),
                    "intrinsics");
    if (!bad) {
        double cam[4], dist[8];
        bad = check(flt_calib_get_intrinsics(calib, cam, FLT_CALIB_CAMERA_VALUES, dist,
                                             FLT_CALIB_DISTORTION_COEFFS),
                    "get intrinsics");
        std::printf("intrinsics: fx %.3f fy %.3f cx %.3f cy %.3f px; k1 %.5f k2 %.5f "
                    "p1 %.2e p2 %.2e k3 %.5f\n",
                    cam[0], cam[1], cam[2], cam[3], dist[0], dist[1], dist[2], dist[3], dist[4]);
        std::printf("  reprojection RMS %.4f px over %zu views:", rms, views.size());
        for (double e : view_rms)
            std::printf(" %.3f", e);
        std::printf("\n");
    }

    // 2. laser planes, with RANSAC against mis-read target points
    flt_options *opts = nullptr;
    if (!bad)
        bad = check(flt_options_create(&opts), "options");
    if (!bad)
        bad = check(flt_options_set(opts, FLT_OPT_CALIB_RANSAC, 1), "options");
    for (unsigned laser = 0; laser < 2 && !bad; ++laser) {
        const std::size_t n = s.image[laser].size() / 2;
        std::vector<double> res_px(n), res_mm(n);
        std::vector<uint8_t> inlier(n);
        double rms_px = NAN, rms_mm = NAN;
        bad = check(flt_calib_estimate_homography(calib, laser, n, s.image[laser].data(),
                                                  s.plane[laser].data(), opts, res_px.data(),
                                                  res_mm.data(), inlier.data(), &rms_px, &rms_mm),
                    "homography");
        if (bad)
            break;
        std::size_t inliers = 0;
        double worst_mm = 0;
        for (std::size_t i = 0; i < n; ++i)
            if (inlier[i])
                ++inliers, worst_mm = std::fmax(worst_mm, res_mm[i]);
        std::printf("laser %u: %zu/%zu inliers, RMS %.4f px = %.4f mm, worst %.4f mm\n", laser,
                    inliers, n, rms_px, rms_mm, worst_mm);
        bad = check(flt_calib_set_laser_offset(calib, laser, s.offset_mm[laser]), "laser offset");
    }
    flt_options_destroy(opts);

    // 3. geometry, finish, save, and read back
    if (!bad)
        bad = check(flt_calib_set_encoder_scale(calib, s.encoder_mm_per_count), "encoder");
    if (!bad)
        bad = check(flt_calib_set_fiber_grid(calib, s.first_x_mm, s.fiber_pitch_mm, s.fibers),
                    "fiber grid");
    if (!bad)
        bad = check(flt_calib_finish(calib), "finish");
    if (!bad)
        bad = check(flt_calib_save(calib, argv[1]), "save");
    flt_calib *loaded = nullptr;
    if (!bad)
        bad = check(flt_calib_load(argv[1], &loaded), "load back");
    if (!bad) {
        double spacing = NAN;
        bad = check(flt_calib_laser_spacing(loaded, &spacing), "laser spacing");
        std::printf("wrote %s (laser spacing %.1f mm)\n", argv[1], spacing);
    }
    flt_calib_destroy(loaded);
    flt_calib_destroy(calib);
    return bad;
}
