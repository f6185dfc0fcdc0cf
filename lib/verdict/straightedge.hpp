// SPDX-License-Identifier: Apache-2.0
// Internal: the straightedge deviation of a profile and of the lines of a
// height map, exactly (README.md, "The straightedge deviation").
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace flt {
namespace verdict {

// What rounding may add to a gap, or take from a bound on it, computed on
// heights of magnitude at most `extent` (mm): each is a few operations on
// differences of heights, rounded to within 2^-53 of magnitudes of about
// the extent. 1e-12 of it is ample.
inline double bound_slack(double extent) {
    return 1e-12 * extent;
}

// The deepest gap under a straightedge resting on one profile.
struct straightedge_gap {
    double deviation = 0;  // mm, >= 0
    double at = 0;         // position of the deepest point (mm)
    double left = 0;       // the contacts' positions (mm)
    double right = 0;
    bool measured = false;  // false: fewer than 2 samples
};

// A sheet's height map (rows == 0: none), already checked: positions
// strictly increasing, heights finite or NaN.
struct map_view {
    std::size_t rows = 0, fibers = 0;
    const double *s = nullptr, *x = nullptr, *z = nullptr;
    const std::uint8_t *flags = nullptr;
};

constexpr std::size_t k_no_line = std::numeric_limits<std::size_t>::max();

// The worst straightedge gap over some lines of a map (every fiber: along;
// every row: across) for one length. A partial result: the lines of a map
// may be measured in blocks, on any threads, each block into its own
// map_gap with its own straightedge, and merged (merge()) in any order.
// The result is the same bit for bit for the same blocks; for other
// blocks too, but where two lines or two places on a line give exactly the
// same gap (see straightedge.cpp), so a caller who wants the same bits
// whatever its number of threads cuts the same blocks whatever it is.
struct map_gap {
    double deviation = 0;  // mm
    double x = 0, s = 0;   // the deepest point (mm)
    // The line (fiber or row index) of the worst gap; the smallest one on
    // a tie. k_no_line: no line measured (fewer than 2 samples on each).
    std::size_t line = k_no_line;
    bool measured() const { return line != k_no_line; }
};

// Merges `part` into `into`: the larger deviation, the smaller line on a tie.
void merge(map_gap &into, const map_gap &part);

// The number of lines of a map in one direction: fibers (along), rows
// (across).
inline std::size_t line_count(const map_view &m, bool along) {
    return along ? m.fibers : m.rows;
}

// Scratch of the computation, reused from call to call: it grows to the
// longest profile (and the most lines of a map) once, or not at all after
// reserve(). One per thread.
class straightedge {
  public:
    // The profile: `count` samples at strictly increasing positions
    // pos[i] (mm) with heights z[i * z_stride] (mm); a sample whose height
    // is not finite, or whose flags[i * z_stride] & skip_bits is set
    // (flags may be null), is left out. length: the straightedge (mm, > 0).
    // Only a deviation above `floor` (the worst of a map so far; -1 for
    // every one) matters to the caller, or at `floor` too with
    // `ties_count`: resting positions that cannot reach it are skipped.
    // The result is exact when it exceeds the floor (or equals it, with
    // ties_count), else at most the floor.
    straightedge_gap measure(const double *pos, const double *z, const unsigned char *flags,
                             std::size_t count, std::size_t z_stride, unsigned skip_bits,
                             double length, double floor, bool ties_count = false);

    // The worst gap over the lines [first, last) of a map in one direction
    // (along: fibers, positions s; across: rows, positions x), merged into
    // `part` (which may hold the result of other lines: its deviation
    // serves as the floor). Samples with FLT_FLAG_NO_DATA or NaN are left
    // out. Allocates nothing once reserve() made room for the longest line
    // and the most lines.
    void measure_lines(const map_view &m, bool along, double length, std::size_t first,
                       std::size_t last, map_gap &part);

    // Makes room for profiles of up to `count` samples and maps of up to
    // `count` lines now, so that measuring them later allocates nothing.
    void reserve(std::size_t count);

  private:
    // One push onto a hull kept in an array: what it overwrote, to undo it.
    struct undo {
        std::size_t size;  // the hull's size before the push
        std::size_t pos;   // where the pushed sample went
        std::size_t old;   // what was there
    };

    // The used samples of the profile being measured: positions and
    // heights, the caller's or a copy in used_p_, used_h_.
    const double *p_ = nullptr, *h_ = nullptr;
    std::vector<double> used_p_, used_h_;
    std::size_t n_ = 0;
    double reach_ = 0;  // the length, with the rounding allowance
    double slack_ = 0;  // bound_slack of the profile's heights
    // The best gap so far and where it is (sample indices).
    double best_ = 0;
    std::size_t best_k_ = 0, best_i_ = 0, best_j_ = 0;
    bool found_ = false;

    // Hulls as arrays of sample indices, with their sizes: the upper hull
    // of the whole profile; of a block, pushed from the right end leftwards
    // (upper_left_, its top the leftmost sample) and of the next block's
    // head, pushed rightwards (upper_right_); the lower hulls of the same
    // ranges, as they grow.
    std::vector<std::size_t> hull_, upper_left_, upper_right_, lower_left_, lower_right_;
    std::size_t upper_left_n_ = 0, upper_right_n_ = 0, lower_left_n_ = 0, lower_right_n_ = 0;
    // Per sample: its hull neighbour when pushed (the steepest sample to
    // its right within the block; the one before it on the head's hull),
    // and the pushes' undo records.
    std::vector<std::size_t> next_, prev_;
    std::vector<undo> undo_left_, undo_right_, undo_lower_;
    // coarse_bound: the chunks' corners (positions, upper and lower heights).
    std::vector<double> corner_p_, corner_upper_, corner_lower_;
    std::size_t corners_ = 0;
    std::vector<double> chunk_slope_;  // each chunk's chord

    // measure_lines: each line's height range and used samples, and the
    // order in which to measure the lines.
    std::vector<double> low_, high_;
    std::vector<std::size_t> used_, order_;

    void grow(std::size_t count);
    // measure() of the n samples at p_, h_ (all used), heights of
    // magnitude at most extent.
    straightedge_gap measure_used(std::size_t n, double extent, double length, double floor,
                                  bool ties_count);
    void consider(double gap, std::size_t k, std::size_t i, std::size_t j) {
        if (gap > best_) {
            best_ = gap;
            best_k_ = k;
            best_i_ = i;
            best_j_ = j;
            found_ = true;
        }
    }
    // A bound on every gap of the profile, from chunks of samples.
    double coarse_bound();
    // The upper hull of the profile into hull_ (after coarse_bound); its size.
    std::size_t upper_hull();
    // A bound on the gaps of the samples strictly between u and v below
    // their segment (after coarse_bound).
    double depth_bound(std::size_t u, std::size_t v) const;
    // The deepest sample strictly between u and v below their segment;
    // returns its gap (0 with none between).
    double deepest_under(std::size_t u, std::size_t v, std::size_t &k) const;
    // Every resting position within samples [lo, hi] (all below the
    // segment lo-hi, which is longer than the straightedge) that can
    // exceed the deviation found.
    void search(std::size_t lo, std::size_t hi);
    // Every resting position within samples [lo, hi] whose left contact is
    // at most `left`.
    void within(std::size_t lo, std::size_t hi, std::size_t left);
    // Resting positions with the left contact in [m0, m) and the right one
    // in [m, r] (every sample of [m, r] within reach of m - 1).
    void across_boundary(std::size_t m0, std::size_t m, std::size_t r);

    void push_upper_left(std::size_t q);
    void push_upper_right(std::size_t q);
    void push_lower_left(std::size_t q);
    void push_lower_right(std::size_t q, bool undoable);
    void pop_lower_right(std::size_t q);
    void pop_upper_left(std::size_t q);
    void pop_upper_right(std::size_t q);
    // The sample of upper_right_ of largest slope from i (left of all; the
    // farthest on a tie), and of upper_left_ of smallest slope to j (right
    // of all; the farthest on a tie).
    std::size_t tangent_from(std::size_t i) const;
    std::size_t tangent_to(std::size_t j) const;
    // The sample of a lower hull (left to right: hull[0 .. count), or
    // reversed) farthest below the line through sample i of slope m, and
    // its gap.
    double deepest_on(const std::size_t *hull, std::size_t count, bool reversed, std::size_t i,
                      double m, std::size_t &k) const;
};

}  // namespace verdict
}  // namespace flt
