// SPDX-License-Identifier: Apache-2.0
// Internal: the bounded least-squares solve of the advice, as the box-
// constrained quadratic programme it is:
//
//     minimise 1/2 x^T H x - f^T x   subject to lo <= x <= hi
//
// with H symmetric positive definite (n x n, n <= FLT_ADVISOR_MAX_ACTUATORS)
// and lo <= 0 <= hi. A primal active-set method: start at x = 0 (feasible),
// solve for the free variables with the others held at their bounds, walk
// towards that solution until a bound blocks (and hold it there), and when
// the free solution is feasible release the bound whose multiplier has the
// wrong sign. With H positive definite every iteration lowers the objective
// or releases a bound, so it ends at the unique minimiser; it is exact up
// to the rounding of the Cholesky solves (n is small). Every buffer is
// allocated by the constructor: solve() allocates nothing.
#pragma once

#include <cstddef>
#include <vector>

namespace flt {
namespace advisor {

class box_qp {
  public:
    enum bound_state : unsigned char { free_var = 0, at_lower = 1, at_upper = 2 };

    explicit box_qp(std::size_t n);

    // H [n * n] row-major, f, lo, hi [n]; x [n] receives the minimiser and
    // state [n] which bound each variable ends on. Returns false if the
    // iteration limit was reached (never seen: a guard against a bug) or H
    // is not positive definite on the free variables.
    bool solve(const double *H, const double *f, const double *lo, const double *hi, double *x,
               unsigned char *state);

    std::size_t iterations() const { return iterations_; }

  private:
    std::size_t n_;
    std::size_t iterations_ = 0;
    std::vector<double> chol_, rhs_, y_, grad_;
    std::vector<std::size_t> free_;
};

}  // namespace advisor
}  // namespace flt
