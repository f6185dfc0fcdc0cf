// SPDX-License-Identifier: Apache-2.0
// Camera intrinsics from images of a planar target, through OpenCV:
// detection, sub-pixel refinement, calibrateCamera.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "calibration/calib_model.hpp"
#include "core/error.hpp"

namespace flt {
namespace {

// The target's points in its own plane (mm, z = 0), OpenCV's ordering.
std::vector<cv::Point3f> target_points(flt_calib_target target, std::uint32_t columns,
                                       std::uint32_t rows, double pitch_mm) {
    std::vector<cv::Point3f> pts;
    pts.reserve(std::size_t(columns) * rows);
    for (std::uint32_t i = 0; i < rows; ++i)
        for (std::uint32_t j = 0; j < columns; ++j) {
            const double x = target == FLT_TARGET_ASYMMETRIC_CIRCLE_GRID
                                 ? double(2 * j + i % 2) * pitch_mm
                                 : double(j) * pitch_mm;
            pts.emplace_back(float(x), float(double(i) * pitch_mm), 0.0f);
        }
    return pts;
}

// Half-size of the cornerSubPix window: 40% of the smallest distance between
// neighbouring corners, so the window never reaches the next corner.
int subpix_half_window(const std::vector<cv::Point2f> &corners, std::uint32_t columns) {
    double nearest = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i + 1 < corners.size(); ++i)
        if ((i + 1) % columns != 0)
            nearest = std::min(nearest, double(cv::norm(corners[i + 1] - corners[i])));
    const int half = int(nearest * 0.4);
    return std::clamp(half, 2, 15);
}

}  // namespace

intrinsics_fit estimate_intrinsics(std::uint32_t width, std::uint32_t height, std::size_t views,
                                   const std::uint8_t *const *images, std::size_t stride,
                                   flt_calib_target target, std::uint32_t columns,
                                   std::uint32_t rows, double pitch_mm, bool rational) {
    const cv::Size pattern{int(columns), int(rows)};
    const std::vector<cv::Point3f> object = target_points(target, columns, rows, pitch_mm);
    std::vector<std::vector<cv::Point3f>> object_points;
    std::vector<std::vector<cv::Point2f>> image_points;
    std::vector<std::size_t> used;  // view index of each detected target

    for (std::size_t v = 0; v < views; ++v) {
        // A header over the caller's pixels: nothing is copied or written.
        const cv::Mat img(int(height), int(width), CV_8UC1, const_cast<std::uint8_t *>(images[v]),
                          stride);
        std::vector<cv::Point2f> found;
        bool ok;
        if (target == FLT_TARGET_CHESSBOARD) {
            ok = cv::findChessboardCorners(img, pattern, found,
                                           cv::CALIB_CB_ADAPTIVE_THRESH |
                                               cv::CALIB_CB_NORMALIZE_IMAGE |
                                               cv::CALIB_CB_FAST_CHECK);
            if (ok) {
                const int half = subpix_half_window(found, columns);
                cv::cornerSubPix(
                    img, found, cv::Size(half, half), cv::Size(-1, -1),
                    cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 100, 1e-4));
            }
        } else {
            // Blob centroids are sub-pixel already.
            ok = cv::findCirclesGrid(img, pattern, found,
                                     target == FLT_TARGET_CIRCLE_GRID
                                         ? cv::CALIB_CB_SYMMETRIC_GRID
                                         : cv::CALIB_CB_ASYMMETRIC_GRID);
        }
        if (!ok || found.size() != object.size())
            continue;
        object_points.push_back(object);
        image_points.push_back(found);
        used.push_back(v);
    }
    if (used.size() < 3)
        throw error(FLT_ERR_NUMERIC,
                    ("the target was found in " + std::to_string(used.size()) + " of " +
                     std::to_string(views) + " views; at least 3 are needed")
                        .c_str());

    cv::Mat camera_matrix, dist_coeffs, std_intrinsics, std_extrinsics, per_view;
    std::vector<cv::Mat> rvecs, tvecs;
    const int flags = rational ? cv::CALIB_RATIONAL_MODEL : 0;
    const double rms = cv::calibrateCamera(
        object_points, image_points, cv::Size(int(width), int(height)), camera_matrix, dist_coeffs,
        rvecs, tvecs, std_intrinsics, std_extrinsics, per_view, flags,
        cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));

    intrinsics_fit fit;
    fit.rms_px = rms;
    fit.camera.fx = camera_matrix.at<double>(0, 0);
    fit.camera.fy = camera_matrix.at<double>(1, 1);
    fit.camera.cx = camera_matrix.at<double>(0, 2);
    fit.camera.cy = camera_matrix.at<double>(1, 2);
    const int ncoef = int(dist_coeffs.total());
    for (int k = 0; k < FLT_CALIB_DISTORTION_COEFFS && k < ncoef; ++k)
        fit.camera.distortion[k] = dist_coeffs.at<double>(k);
    fit.view_rms_px.assign(views, std::numeric_limits<double>::quiet_NaN());
    for (std::size_t i = 0; i < used.size(); ++i)
        fit.view_rms_px[used[i]] = per_view.at<double>(int(i));
    const bool finite = std::isfinite(rms) && std::isfinite(fit.camera.fx) &&
                        std::isfinite(fit.camera.fy) && fit.camera.fx > 0 && fit.camera.fy > 0;
    if (!finite)
        throw error(FLT_ERR_NUMERIC, "calibrateCamera did not converge");
    return fit;
}

}  // namespace flt
