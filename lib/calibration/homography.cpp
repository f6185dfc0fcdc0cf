// SPDX-License-Identifier: Apache-2.0
// Laser-plane homographies: normalised DLT (Hartley), Levenberg-Marquardt
// refinement of the image reprojection error, and RANSAC.
//
// The estimated unknown is G = H^-1, plane (x, z) mm -> undistorted image
// (u, v) px, because the noise is in the image (peak detection) while the
// plane points are the target's known geometry: minimising the image
// distance |pi(G p) - u| is then the maximum-likelihood estimate.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>

#include <Eigen/Dense>

#include "calibration/calib_model.hpp"
#include "core/error.hpp"

namespace flt {
namespace {

using mat3 = Eigen::Matrix3d;
using rowmat3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
// Below this reciprocal condition number a homography is taken as singular.
// A real image->plane homography of the reference sensor has about 1e-7
// (px and mm scales differ, and the perspective row is ~1e-4).
constexpr double k_min_rcond = 1e-12;

// Hartley normalisation: centroid to the origin, mean distance sqrt(2).
mat3 normalising_transform(std::size_t n, const double *pts) {
    double mx = 0, my = 0;
    for (std::size_t i = 0; i < n; ++i)
        mx += pts[2 * i], my += pts[2 * i + 1];
    mx /= double(n), my /= double(n);
    double mean_dist = 0;
    for (std::size_t i = 0; i < n; ++i)
        mean_dist += std::hypot(pts[2 * i] - mx, pts[2 * i + 1] - my);
    mean_dist /= double(n);
    if (!(mean_dist > 0))
        throw error(FLT_ERR_NUMERIC, "all points coincide");
    const double s = std::sqrt(2.0) / mean_dist;
    mat3 t;
    t << s, 0, -s * mx, 0, s, -s * my, 0, 0, 1;
    return t;
}

Eigen::Vector2d project(const mat3 &g, double a, double b) {
    const Eigen::Vector3d q = g * Eigen::Vector3d(a, b, 1);
    return Eigen::Vector2d(q(0) / q(2), q(1) / q(2));
}

// Normalised points, row i = (a, b).
Eigen::MatrixX2d transform_points(const mat3 &t, std::size_t n, const double *pts,
                                  const std::size_t *index) {
    Eigen::MatrixX2d out(Eigen::Index(n), 2);
    for (std::size_t i = 0; i < n; ++i) {
        const std::size_t k = index ? index[i] : i;
        out(Eigen::Index(i), 0) = t(0, 0) * pts[2 * k] + t(0, 2);
        out(Eigen::Index(i), 1) = t(1, 1) * pts[2 * k + 1] + t(1, 2);
    }
    return out;
}

// DLT on normalised points: G maps plane -> image. Returns false when the
// points do not determine a homography (rank < 8).
bool dlt(const Eigen::MatrixX2d &plane, const Eigen::MatrixX2d &image, mat3 *g_out) {
    const Eigen::Index n = plane.rows();
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(2 * n, 9);
    for (Eigen::Index i = 0; i < n; ++i) {
        const double x = plane(i, 0), z = plane(i, 1);
        const double u = image(i, 0), v = image(i, 1);
        a.row(2 * i) << -x, -z, -1, 0, 0, 0, u * x, u * z, u;
        a.row(2 * i + 1) << 0, 0, 0, -x, -z, -1, v * x, v * z, v;
    }
    // With 4 points A is 8x9: pad to 9 rows so the SVD has a 9th singular
    // value (zero) and V's last column is the null vector.
    if (a.rows() < 9) {
        a.conservativeResize(9, 9);
        a.row(8).setZero();
    }
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeFullV);
    const Eigen::VectorXd &sv = svd.singularValues();
    // The 8th singular value is what separates the solution from a family.
    if (!(sv(7) > 1e-10 * sv(0)))
        return false;
    const Eigen::VectorXd h = svd.matrixV().col(8);
    mat3 g;
    g << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
    *g_out = g;
    return true;
}

double rcond(const mat3 &m) {
    Eigen::JacobiSVD<mat3> svd(m);
    const Eigen::Vector3d &sv = svd.singularValues();
    return sv(0) > 0 ? sv(2) / sv(0) : 0.0;
}

// Levenberg-Marquardt on the 9 entries of the normalised G, kept at unit
// norm (the scale is a gauge freedom; the damping keeps the step finite).
mat3 refine(const mat3 &g0, const Eigen::MatrixX2d &plane, const Eigen::MatrixX2d &image) {
    const Eigen::Index n = plane.rows();
    auto cost_of = [&](const mat3 &g) {
        double c = 0;
        for (Eigen::Index i = 0; i < n; ++i) {
            const Eigen::Vector2d p = project(g, plane(i, 0), plane(i, 1));
            c += (p - image.row(i).transpose()).squaredNorm();
        }
        return std::isfinite(c) ? c : std::numeric_limits<double>::infinity();
    };
    mat3 g = g0 / g0.norm();
    double cost = cost_of(g);
    double lambda = 1e-3;
    bool converged = false;
    for (int it = 0; it < 100 && cost > 0 && !converged; ++it) {
        Eigen::Matrix<double, 9, 9> jtj = Eigen::Matrix<double, 9, 9>::Zero();
        Eigen::Matrix<double, 9, 1> jtr = Eigen::Matrix<double, 9, 1>::Zero();
        for (Eigen::Index i = 0; i < n; ++i) {
            const Eigen::Vector3d p(plane(i, 0), plane(i, 1), 1);
            const Eigen::Vector3d q = g * p;
            const double w = 1 / q(2);
            Eigen::Matrix<double, 2, 9> j = Eigen::Matrix<double, 2, 9>::Zero();
            j.block<1, 3>(0, 0) = p.transpose() * w;
            j.block<1, 3>(0, 6) = -p.transpose() * (q(0) * w * w);
            j.block<1, 3>(1, 3) = p.transpose() * w;
            j.block<1, 3>(1, 6) = -p.transpose() * (q(1) * w * w);
            const Eigen::Vector2d r(q(0) * w - image(i, 0), q(1) * w - image(i, 1));
            jtj.noalias() += j.transpose() * j;
            jtr.noalias() += j.transpose() * r;
        }
        bool accepted = false;
        for (int tries = 0; tries < 20; ++tries) {
            Eigen::Matrix<double, 9, 9> a = jtj;
            for (int k = 0; k < 9; ++k)
                a(k, k) += lambda * (jtj(k, k) + 1e-12);
            const Eigen::Matrix<double, 9, 1> step = a.ldlt().solve(-jtr);
            mat3 gn = g;
            for (int k = 0; k < 9; ++k)
                gn(k / 3, k % 3) += step(k);
            gn /= gn.norm();
            const double cn = cost_of(gn);
            if (cn < cost) {
                const double gain = (cost - cn) / cost;
                g = gn, cost = cn;
                lambda = std::max(lambda * 0.3, 1e-12);
                accepted = true;
                converged = gain < 1e-14;  // at double precision
                break;
            }
            lambda *= 10;
        }
        if (!accepted)
            break;
    }
    return g;
}

// Fits G (plane -> undistorted image, in pixel and mm units) to the
// correspondences listed in index (all when index is null).
bool fit_subset(std::size_t n, const double *image_px, const double *plane_mm,
                const std::size_t *index, std::size_t m, bool refine_it, mat3 *g_out) {
    std::vector<double> sub_img, sub_pl;
    const double *img = image_px, *pl = plane_mm;
    if (index) {
        sub_img.resize(2 * m), sub_pl.resize(2 * m);
        for (std::size_t i = 0; i < m; ++i)
            for (int c = 0; c < 2; ++c) {
                sub_img[2 * i + c] = image_px[2 * index[i] + c];
                sub_pl[2 * i + c] = plane_mm[2 * index[i] + c];
            }
        img = sub_img.data(), pl = sub_pl.data();
    } else {
        m = n;
    }
    mat3 t_img, t_pl;
    try {
        t_img = normalising_transform(m, img);
        t_pl = normalising_transform(m, pl);
    } catch (const error &) {
        return false;
    }
    const Eigen::MatrixX2d pn = transform_points(t_pl, m, pl, nullptr);
    const Eigen::MatrixX2d un = transform_points(t_img, m, img, nullptr);
    mat3 gn;
    if (!dlt(pn, un, &gn))
        return false;
    if (refine_it)
        gn = refine(gn, pn, un);
    if (!(rcond(gn) > k_min_rcond))
        return false;
    const mat3 g = t_img.inverse() * gn * t_pl;
    if (!g.allFinite())
        return false;
    *g_out = g / g.norm();
    return true;
}

double reprojection_px(const mat3 &g, const double *image_px, const double *plane_mm,
                       std::size_t i) {
    const Eigen::Vector2d p = project(g, plane_mm[2 * i], plane_mm[2 * i + 1]);
    const double d = std::hypot(p(0) - image_px[2 * i], p(1) - image_px[2 * i + 1]);
    return std::isfinite(d) ? d : std::numeric_limits<double>::infinity();
}

}  // namespace

bool homography_invertible(const double h[9]) {
    const rowmat3 m = Eigen::Map<const rowmat3>(h);
    if (!m.allFinite())
        return false;
    return rcond(m) > k_min_rcond;
}

void homography_inverse(const double h[9], double inv[9]) {
    const rowmat3 m = Eigen::Map<const rowmat3>(h);
    rowmat3 m_inv = m.inverse();
    m_inv /= m_inv.norm();
    Eigen::Map<rowmat3> out(inv);
    out = m_inv;
}

void homography_apply(const double h[9], double a, double b, double *a_out, double *b_out) {
    const double x = h[0] * a + h[1] * b + h[2];
    const double y = h[3] * a + h[4] * b + h[5];
    const double w = h[6] * a + h[7] * b + h[8];
    if (w == 0 || !std::isfinite(w)) {
        *a_out = *b_out = nan;
        return;
    }
    *a_out = x / w;
    *b_out = y / w;
}

homography_fit fit_homography(std::size_t n, const double *image_px, const double *plane_mm,
                              const ransac_params &ransac) {
    std::vector<std::size_t> inliers;
    mat3 g;
    if (ransac.enabled && n > 4) {
        // Deterministic draws: mt19937 is specified bit-exactly by the
        // standard; uniform_int_distribution is not, so index by modulo.
        std::mt19937 rng(ransac.seed);
        std::size_t best_count = 0;
        double best_sum = std::numeric_limits<double>::infinity();
        std::vector<std::size_t> best;
        std::vector<std::size_t> current;
        for (long it = 0; it < ransac.iterations; ++it) {
            std::size_t sample[4];
            for (int k = 0; k < 4; ++k) {
                bool fresh;
                do {
                    sample[k] = std::size_t(rng()) % n;
                    fresh = true;
                    for (int j = 0; j < k; ++j)
                        fresh &= sample[j] != sample[k];
                } while (!fresh);
            }
            mat3 gs;
            if (!fit_subset(n, image_px, plane_mm, sample, 4, false, &gs))
                continue;
            current.clear();
            double sum = 0;
            for (std::size_t i = 0; i < n; ++i) {
                const double e = reprojection_px(gs, image_px, plane_mm, i);
                if (e < ransac.threshold_px)
                    current.push_back(i), sum += e;
            }
            if (current.size() > best_count || (current.size() == best_count && sum < best_sum)) {
                best_count = current.size(), best_sum = sum;
                best.swap(current);
            }
        }
        if (best_count < 4)
            throw error(FLT_ERR_NUMERIC, "RANSAC found no homography with 4 or more inliers; "
                                         "check calib_ransac_threshold and the correspondences");
        // Refit on the consensus, then re-select inliers with the refined
        // model once more (the minimal-sample model is noisy).
        inliers = best;
        for (int round = 0; round < 3; ++round) {
            if (!fit_subset(n, image_px, plane_mm, inliers.data(), inliers.size(), true, &g))
                throw error(FLT_ERR_NUMERIC, "the RANSAC inliers are degenerate");
            std::vector<std::size_t> again;
            for (std::size_t i = 0; i < n; ++i)
                if (reprojection_px(g, image_px, plane_mm, i) < ransac.threshold_px)
                    again.push_back(i);
            if (again == inliers || again.size() < 4)
                break;
            inliers.swap(again);
        }
    } else {
        if (!fit_subset(n, image_px, plane_mm, nullptr, n, true, &g))
            throw error(FLT_ERR_NUMERIC, "the correspondences do not determine a homography "
                                         "(fewer than 4 distinct points, or collinear)");
        inliers.resize(n);
        for (std::size_t i = 0; i < n; ++i)
            inliers[i] = i;
    }

    homography_fit fit;
    rowmat3 h = g.inverse();
    h /= h.norm();
    if (h(2, 2) < 0)
        h = -h;  // a fixed sign makes saved files comparable
    Eigen::Map<rowmat3> h_out(fit.h);
    h_out = h;
    if (!homography_invertible(fit.h))
        throw error(FLT_ERR_NUMERIC, "the estimated homography is singular");
    fit.residual_px.resize(n);
    fit.residual_mm.resize(n);
    fit.inlier.assign(n, 0);
    for (std::size_t i : inliers)
        fit.inlier[i] = 1;
    double sum_px = 0, sum_mm = 0;
    for (std::size_t i = 0; i < n; ++i) {
        fit.residual_px[i] = reprojection_px(g, image_px, plane_mm, i);
        double x, z;
        homography_apply(fit.h, image_px[2 * i], image_px[2 * i + 1], &x, &z);
        fit.residual_mm[i] = std::hypot(x - plane_mm[2 * i], z - plane_mm[2 * i + 1]);
        if (fit.inlier[i]) {
            sum_px += fit.residual_px[i] * fit.residual_px[i];
            sum_mm += fit.residual_mm[i] * fit.residual_mm[i];
        }
    }
    fit.rms_px = std::sqrt(sum_px / double(inliers.size()));
    fit.rms_mm = std::sqrt(sum_mm / double(inliers.size()));
    return fit;
}

}  // namespace flt
