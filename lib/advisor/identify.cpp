// SPDX-License-Identifier: Apache-2.0
// Ridge least squares for the influence matrix (identify.hpp).
#include "advisor/identify.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include "core/number_text.hpp"

namespace flt {
namespace advisor {

identification identify(std::size_t zones, std::size_t actuators, std::size_t steps,
                        const double *du, const double *dp, double ridge, double min_r_squared) {
    using Mat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    identification out;
    char text[256];
    // Every zone's row of G is its own regression on the same steps: with
    // no more steps than actuators it fits any data exactly and R^2 says
    // nothing.
    if (steps < actuators + 1) {
        format_c(text, sizeof text,
                 "%zu steps cannot identify %zu actuators: at least %zu are needed (one more "
                 "than the actuators, so that the fit can be judged)",
                 steps, actuators, actuators + 1);
        out.why = text;
        return out;
    }
    const Eigen::Map<const Mat> U(du, Eigen::Index(steps), Eigen::Index(actuators));
    Mat Y = Eigen::Map<const Mat>(dp, Eigen::Index(steps), Eigen::Index(zones));
    // P: the profile's mean over the zones is no shape (flatline/advisor.h).
    Y.colwise() -= Y.rowwise().mean();
    const Eigen::JacobiSVD<Mat> svd(U);
    const auto &sv = svd.singularValues();
    const double s_max = sv.size() ? sv(0) : 0.0;
    const double s_min = sv.size() ? sv(sv.size() - 1) : 0.0;
    if (!(s_max > 0) || !(s_min >= 1e-6 * s_max)) {
        format_c(text, sizeof text,
                 "the steps do not move every actuator independently (singular values of the "
                 "setting changes %.3g .. %.3g, ratio below 1e-6): step each actuator on its own",
                 s_min, s_max);
        out.why = text;
        return out;
    }
    const Mat UtU = U.transpose() * U;
    const double rho = ridge * UtU.trace() / double(actuators);
    Mat A = UtU;
    A.diagonal().array() += rho;
    const Mat Gt = A.ldlt().solve(U.transpose() * Y);  // actuators x zones
    const Mat E = Y - U * Gt;
    const double ss_res = E.squaredNorm();
    const double ss_tot = Y.squaredNorm();
    out.fitted = true;
    out.g.assign(zones * actuators, 0.0);
    Eigen::Map<Mat>(out.g.data(), Eigen::Index(zones), Eigen::Index(actuators)) = Gt.transpose();
    out.rms = std::sqrt(ss_res / double(steps * zones));
    if (!(ss_tot > 0)) {
        out.r_squared = 0;
        out.why = "the profile changes are all zero (after removing each one's mean over the "
                  "zones): the steps did not change the shape";
        return out;
    }
    out.r_squared = 1.0 - ss_res / ss_tot;
    if (!(out.r_squared >= min_r_squared)) {
        format_c(text, sizeof text,
                 "the identification explains R^2 = %.3f of the profile changes (RMS residual "
                 "%.3g I-Units), below the %.2f it takes to advise from it",
                 out.r_squared, out.rms, min_r_squared);
        out.why = text;
        return out;
    }
    out.accepted = true;
    return out;
}

}  // namespace advisor
}  // namespace flt
