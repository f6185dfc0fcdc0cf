// SPDX-License-Identifier: Apache-2.0
// The active-set solve of a box-constrained quadratic programme
// (bounded_lsq.hpp).
#include "advisor/bounded_lsq.hpp"

#include <algorithm>
#include <cmath>

namespace flt {
namespace advisor {

box_qp::box_qp(std::size_t n) : n_(n), chol_(n * n), rhs_(n), y_(n), grad_(n), free_(n) {}

bool box_qp::solve(const double *H, const double *f, const double *lo, const double *hi, double *x,
                   unsigned char *state) {
    const std::size_t n = n_;
    // The scale of the gradient, for the multipliers' sign test: a
    // multiplier counts as wrong only beyond rounding of the products in
    // H x - f.
    double h_max = 0, f_max = 0, b_max = 0;
    for (std::size_t i = 0; i < n; ++i) {
        f_max = std::max(f_max, std::fabs(f[i]));
        b_max = std::max(b_max, std::max(std::fabs(lo[i]), std::fabs(hi[i])));
        for (std::size_t j = 0; j < n; ++j)
            h_max = std::max(h_max, std::fabs(H[i * n + j]));
    }
    const double tol = 1e-12 * double(n) * (f_max + h_max * b_max) + 1e-300;
    for (std::size_t i = 0; i < n; ++i) {
        x[i] = 0;  // lo <= 0 <= hi: feasible
        state[i] = free_var;
    }
    // Each bound is taken at most once per release, and a release happens
    // only at a strictly better point: 50 (n + 1) is far beyond what a
    // problem of this size needs (tests see < 2 n).
    const std::size_t limit = 50 * (n + 1);
    for (iterations_ = 0; iterations_ < limit; ++iterations_) {
        // The free variables and the system H_FF y = f_F - H_FB x_B.
        std::size_t m = 0;
        for (std::size_t i = 0; i < n; ++i)
            if (state[i] == free_var)
                free_[m++] = i;
        for (std::size_t a = 0; a < m; ++a) {
            const std::size_t i = free_[a];
            double r = f[i];
            for (std::size_t j = 0; j < n; ++j)
                if (state[j] != free_var)
                    r -= H[i * n + j] * x[j];
            rhs_[a] = r;
            for (std::size_t b = 0; b < m; ++b)
                chol_[a * m + b] = H[i * n + free_[b]];
        }
        // Cholesky, lower triangle in place.
        for (std::size_t a = 0; a < m; ++a) {
            for (std::size_t b = 0; b <= a; ++b) {
                double s = chol_[a * m + b];
                for (std::size_t k = 0; k < b; ++k)
                    s -= chol_[a * m + k] * chol_[b * m + k];
                if (a == b) {
                    if (!(s > 0))
                        return false;
                    chol_[a * m + a] = std::sqrt(s);
                } else {
                    chol_[a * m + b] = s / chol_[b * m + b];
                }
            }
        }
        for (std::size_t a = 0; a < m; ++a) {
            double s = rhs_[a];
            for (std::size_t k = 0; k < a; ++k)
                s -= chol_[a * m + k] * y_[k];
            y_[a] = s / chol_[a * m + a];
        }
        for (std::size_t a = m; a-- > 0;) {
            double s = y_[a];
            for (std::size_t k = a + 1; k < m; ++k)
                s -= chol_[k * m + a] * y_[k];
            y_[a] = s / chol_[a * m + a];
        }
        // Walk from x towards y until the first bound blocks.
        double t = 1;
        std::size_t blocking = n;
        for (std::size_t a = 0; a < m; ++a) {
            const std::size_t i = free_[a];
            const double d = y_[a] - x[i];
            if (y_[a] < lo[i] && d < 0) {
                const double ti = (lo[i] - x[i]) / d;
                if (ti < t) {
                    t = ti;
                    blocking = i;
                }
            } else if (y_[a] > hi[i] && d > 0) {
                const double ti = (hi[i] - x[i]) / d;
                if (ti < t) {
                    t = ti;
                    blocking = i;
                }
            }
        }
        t = std::max(0.0, t);
        for (std::size_t a = 0; a < m; ++a) {
            const std::size_t i = free_[a];
            x[i] = blocking == n ? y_[a] : x[i] + t * (y_[a] - x[i]);
        }
        if (blocking != n) {
            // Hold every variable the step brought to (or past) a bound.
            for (std::size_t a = 0; a < m; ++a) {
                const std::size_t i = free_[a];
                if (i == blocking || x[i] <= lo[i] || x[i] >= hi[i]) {
                    const bool lower = i == blocking ? y_[a] < lo[i] : x[i] <= lo[i];
                    state[i] = lower ? at_lower : at_upper;
                    x[i] = lower ? lo[i] : hi[i];
                }
            }
            continue;
        }
        // The free solution is feasible: check the multipliers of the bounds.
        for (std::size_t i = 0; i < n; ++i) {
            double g = -f[i];
            for (std::size_t j = 0; j < n; ++j)
                g += H[i * n + j] * x[j];
            grad_[i] = g;
        }
        std::size_t release = n;
        double worst = tol;
        for (std::size_t i = 0; i < n; ++i) {
            // At the lower bound the objective must not fall as x_i grows
            // (gradient >= 0); at the upper bound, as it shrinks.
            const double wrong = state[i] == at_lower   ? -grad_[i]
                                 : state[i] == at_upper ? grad_[i]
                                                        : 0.0;
            if (wrong > worst) {
                worst = wrong;
                release = i;
            }
        }
        if (release == n)
            return true;
        state[release] = free_var;
    }
    return false;
}

}  // namespace advisor
}  // namespace flt
