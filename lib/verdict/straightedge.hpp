// SPDX-License-Identifier: Apache-2.0
// Internal: the straightedge deviation of a profile, exactly (README.md,
// "The straightedge deviation").
#pragma once

#include <cstddef>
#include <vector>

namespace flt {
namespace verdict {

// The deepest gap under a straightedge resting on one profile.
struct straightedge_gap {
    double deviation = 0;  // mm, >= 0
    double at = 0;         // position of the deepest point (mm)
    double left = 0;       // the contacts' positions (mm)
    double right = 0;
    bool measured = false;  // false: fewer than 2 samples
};

// Scratch of a profile's computation, reused from call to call (it grows
// to the longest profile once).
class straightedge {
  public:
    // The profile: `count` samples at strictly increasing positions
    // pos[i] (mm) with heights z[i * z_stride] (mm); a sample whose height
    // is not finite, or whose flags[i * z_stride] & skip_bits is set
    // (flags may be null), is left out. length: the straightedge (mm, > 0).
    // Only a deviation above `floor` matters to the caller (the worst of a
    // map so far; -1 for every one): resting positions that cannot exceed
    // it are skipped, and the result is exact when it exceeds the floor,
    // else at most the floor.
    straightedge_gap measure(const double *pos, const double *z, const unsigned char *flags,
                             std::size_t count, std::size_t z_stride, unsigned skip_bits,
                             double length, double floor);
    // Makes room for profiles of up to `count` samples (and maps of up to
    // `count` lines) now, so that measuring them later allocates nothing.
    void reserve(std::size_t count);

    // The order in which to measure the lines of a map: by decreasing
    // height range (max - min of the heights measure() uses), ties in line
    // order. A line's gap never exceeds its range, so the tallest lines
    // first raise the floor early and the rest are mostly skipped: the
    // result is the same, found sooner. lines: `count` lines, line i's
    // samples z[i * line_stride + j * z_stride] (j < length) with their
    // flags likewise. Returns the order (valid until the next call).
    const std::vector<std::size_t> &order_lines(const double *z, const unsigned char *flags,
                                                std::size_t count, std::size_t line_stride,
                                                std::size_t length, std::size_t z_stride,
                                                unsigned skip_bits);

  private:
    // The used samples.
    std::vector<double> p_, h_;
    // A segment tree over the samples: node n covers [lo, hi) and holds
    // its upper and lower convex hulls (sample indices, increasing
    // position) in pool_[first .. first + count).
    struct hull_ref {
        std::size_t upper_first, upper_count, lower_first, lower_count;
    };
    std::vector<hull_ref> nodes_;
    std::vector<std::size_t> pool_;
    std::vector<std::size_t> high_, low_;  // sliding-window extremes (deques)
    std::size_t n_ = 0;
    std::vector<std::size_t> order_;  // order_lines
    std::vector<double> range_;

    void build(std::size_t node, std::size_t lo, std::size_t hi);
    // The sample in [lo, hi) of largest slope from sample i (< lo); the
    // farthest one on a tie. Updates best (SIZE_MAX = none yet).
    void steepest(std::size_t node, std::size_t lo, std::size_t hi, std::size_t from,
                  std::size_t to, std::size_t i, std::size_t &best) const;
    // The sample in [from, to) farthest below the line through sample i
    // of slope m. Updates best / best_gap.
    void deepest(std::size_t node, std::size_t lo, std::size_t hi, std::size_t from, std::size_t to,
                 std::size_t i, double m, std::size_t &best, double &best_gap) const;
};

}  // namespace verdict
}  // namespace flt
