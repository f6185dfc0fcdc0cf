// SPDX-License-Identifier: Apache-2.0
// OpenCV's lens distortion model, forward and inverse, written out here so
// that mapping allocates nothing and inverts to 1e-10 px (cv::undistortPoints
// stops after a fixed number of fixed-point steps, which leaves tenths of a
// pixel in the corners of a wide-angle lens).
#include <cmath>
#include <limits>

#include "calibration/calib_model.hpp"

namespace flt {
namespace {

struct distortion_eval {
    double xd, yd;              // distorted normalised point
    double j00, j01, j10, j11;  // d(xd, yd) / d(x, y)
};

distortion_eval distort_normalised(const double *d, double x, double y) {
    const double k1 = d[0], k2 = d[1], p1 = d[2], p2 = d[3], k3 = d[4], k4 = d[5], k5 = d[6],
                 k6 = d[7];
    const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
    const double num = 1 + k1 * r2 + k2 * r4 + k3 * r6;
    const double den = 1 + k4 * r2 + k5 * r4 + k6 * r6;
    const double c = num / den;
    // dc/d(r2)
    const double dnum = k1 + 2 * k2 * r2 + 3 * k3 * r4;
    const double dden = k4 + 2 * k5 * r2 + 3 * k6 * r4;
    const double dc = (dnum * den - num * dden) / (den * den);
    distortion_eval e;
    e.xd = x * c + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
    e.yd = y * c + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
    e.j00 = c + 2 * x * x * dc + 2 * p1 * y + 6 * p2 * x;
    e.j01 = 2 * x * y * dc + 2 * p1 * x + 2 * p2 * y;
    e.j10 = 2 * x * y * dc + 2 * p1 * x + 2 * p2 * y;
    e.j11 = c + 2 * y * y * dc + 6 * p1 * y + 2 * p2 * x;
    return e;
}

}  // namespace

void distort_pixel(const camera_model &cam, double u, double v, double *u_out, double *v_out) {
    const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
    const distortion_eval e = distort_normalised(cam.distortion, x, y);
    *u_out = cam.fx * e.xd + cam.cx;
    *v_out = cam.fy * e.yd + cam.cy;
}

void undistort_pixel(const camera_model &cam, double u, double v, double *u_out, double *v_out) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    const double xd = (u - cam.cx) / cam.fx, yd = (v - cam.cy) / cam.fy;
    if (!std::isfinite(xd) || !std::isfinite(yd)) {
        *u_out = *v_out = nan;
        return;
    }
    // Converged when the distorted point is within 1e-13 of the observation
    // in normalised units: 1e-13 * f (~1100 px) ~ 1e-10 px.
    const double tolerance = 1e-13 * (1 + std::fabs(xd) + std::fabs(yd));
    double x = xd, y = yd;
    distortion_eval e = distort_normalised(cam.distortion, x, y);
    double rx = e.xd - xd, ry = e.yd - yd;
    double err = std::hypot(rx, ry);
    for (int it = 0; it < 100 && err > tolerance; ++it) {
        const double det = e.j00 * e.j11 - e.j01 * e.j10;
        if (!(std::fabs(det) > 1e-300))
            break;
        const double dx = (e.j11 * rx - e.j01 * ry) / det;
        const double dy = (-e.j10 * rx + e.j00 * ry) / det;
        // Damped step: halve until the residual shrinks, so a strongly
        // distorted corner cannot throw the iteration onto another branch.
        bool improved = false;
        for (int half = 0; half < 30; ++half) {
            const double step = std::ldexp(1.0, -half);  // 1, 1/2, 1/4, ... exactly
            const double xn = x - step * dx, yn = y - step * dy;
            const distortion_eval en = distort_normalised(cam.distortion, xn, yn);
            const double rxn = en.xd - xd, ryn = en.yd - yd;
            const double errn = std::hypot(rxn, ryn);
            if (errn < err) {
                x = xn, y = yn, e = en, rx = rxn, ry = ryn, err = errn;
                improved = true;
                break;
            }
        }
        if (!improved)
            break;
    }
    if (!(err <= tolerance * 1e3)) {  // no convergence (1e-7 px at worst)
        *u_out = *v_out = nan;
        return;
    }
    *u_out = cam.fx * x + cam.cx;
    *v_out = cam.fy * y + cam.cy;
}

}  // namespace flt
