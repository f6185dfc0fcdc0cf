// SPDX-License-Identifier: Apache-2.0
// The straightedge deviation of a profile (README.md, "The straightedge
// deviation").
//
// A straightedge resting on two samples i < j (contacts at most `length`
// apart, every sample between them on or below the segment) shows the gap
// max over i < k < j of segment(k) - z_k. For a fixed left contact i, the
// valid right contacts are the samples whose slope from i is at least that
// of every sample before them, so their slopes grow with j; a steeper
// segment from i lies higher at every sample before the flatter one's
// contact. The gap therefore grows with j, and only the last valid contact
// counts: the sample of largest slope from i within the length (the
// farthest one on a tie). The deviation is the largest of these gaps over
// every i.
//
// Both steps are range queries on convex hulls: the steepest sample from i
// in (i, i + length] is a tangent to the upper hull of that range, and the
// deepest sample under the segment is the extreme point of the lower hull
// of (i, j) in the segment's direction. A segment tree holds both hulls of
// each node's range; a query visits O(log n) nodes and searches each hull
// in O(log n): O(n log^2 n) per profile, O(n log n) memory, exact up to
// rounding.
//
// A gap under a segment from i never exceeds the range of heights within
// the straightedge's reach from i (the segment lies no higher than the
// higher contact, the sample no lower than the lowest). Left contacts
// whose range is no more than the deviation already found (on this
// profile or an earlier line of the same map) are skipped: on a sheet most
// of them are, and a profile that has none left builds no tree.
#include "verdict/straightedge.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <utility>

namespace flt {
namespace verdict {
namespace {

constexpr std::size_t k_none = std::numeric_limits<std::size_t>::max();

// The levels of the segment tree over n samples: ceil(log2 n) + 1.
std::size_t levels_of(std::size_t n) {
    std::size_t levels = 1;
    while ((std::size_t(1) << (levels - 1)) < n)
        ++levels;
    return levels;
}

}  // namespace

void straightedge::reserve(std::size_t count) {
    p_.reserve(count);
    h_.reserve(count);
    high_.reserve(count);
    low_.reserve(count);
    nodes_.reserve(4 * count);
    pool_.reserve(2 * count * levels_of(count));
    order_.reserve(count);
    range_.reserve(count);
}

const std::vector<std::size_t> &
straightedge::order_lines(const double *z, const unsigned char *flags, std::size_t count,
                          std::size_t line_stride, std::size_t length, std::size_t z_stride,
                          unsigned skip_bits) {
    order_.resize(count);
    range_.resize(count);
    for (std::size_t i = 0; i < count; ++i) {
        double lo = std::numeric_limits<double>::infinity(), hi = -lo;
        for (std::size_t j = 0; j < length; ++j) {
            const std::size_t at = i * line_stride + j * z_stride;
            const double v = z[at];
            if (!std::isfinite(v) || (flags != nullptr && (flags[at] & skip_bits) != 0))
                continue;
            lo = v < lo ? v : lo;
            hi = v > hi ? v : hi;
        }
        order_[i] = i;
        range_[i] = hi >= lo ? hi - lo : 0.0;
    }
    // Insertion into a sorted prefix would be quadratic; std::stable_sort
    // may allocate. A heap sort on (range desc, index asc) is in place.
    const auto before = [&](std::size_t a, std::size_t b) {  // a goes first
        return range_[a] > range_[b] || (range_[a] == range_[b] && a < b);
    };
    // Max-heap of "goes last" at the root, then pop to the back.
    const auto sift = [&](std::size_t root, std::size_t end) {
        for (;;) {
            std::size_t child = 2 * root + 1;
            if (child >= end)
                return;
            if (child + 1 < end && before(order_[child], order_[child + 1]))
                ++child;
            if (!before(order_[root], order_[child]))
                return;
            std::swap(order_[root], order_[child]);
            root = child;
        }
    };
    for (std::size_t i = count / 2; i-- > 0;)
        sift(i, count);
    for (std::size_t end = count; end > 1; --end) {
        std::swap(order_[0], order_[end - 1]);
        sift(0, end - 1);
    }
    return order_;
}

straightedge_gap straightedge::measure(const double *pos, const double *z,
                                       const unsigned char *flags, std::size_t count,
                                       std::size_t z_stride, unsigned skip_bits, double length,
                                       double floor) {
    p_.clear();
    h_.clear();
    for (std::size_t i = 0; i < count; ++i) {
        const double v = z[i * z_stride];
        if (!std::isfinite(v) || (flags != nullptr && (flags[i * z_stride] & skip_bits) != 0))
            continue;
        p_.push_back(pos[i]);
        h_.push_back(v);
    }
    n_ = p_.size();
    straightedge_gap out;
    if (n_ < 2)
        return out;
    out.measured = true;
    out.at = out.left = p_[0];
    out.right = p_[1];

    // A span of exactly the length on a grid of positions counts, whatever
    // the rounding of the positions (1e-9 relative).
    const double reach = length * (1.0 + 1e-9);
    double best = floor > 0 ? floor : 0.0;
    bool built = false;
    // Monotone deques over [i, r]: the highest and lowest samples' indices.
    high_.assign(n_, 0);
    low_.assign(n_, 0);
    std::size_t hh = 0, ht = 0, lh = 0, lt = 0;  // heads and tails
    std::size_t r = 0;
    high_[ht++] = 0;
    low_[lt++] = 0;
    for (std::size_t i = 0; i + 1 < n_; ++i) {
        while (r + 1 < n_ && p_[r + 1] - p_[i] <= reach) {
            ++r;
            while (ht > hh && h_[high_[ht - 1]] <= h_[r])
                --ht;
            high_[ht++] = r;
            while (lt > lh && h_[low_[lt - 1]] >= h_[r])
                --lt;
            low_[lt++] = r;
        }
        while (high_[hh] < i)
            ++hh;
        while (low_[lh] < i)
            ++lh;
        if (r <= i + 1)
            continue;  // no sample can lie between two contacts
        if (h_[high_[hh]] - h_[low_[lh]] <= best)
            continue;  // no gap from i can exceed what was found
        if (!built) {
            // The tree: 4n nodes cover any n; each level's hulls hold at
            // most n samples twice (upper and lower), and there are
            // ceil(log2 n) + 1 levels.
            nodes_.assign(4 * n_, hull_ref{0, 0, 0, 0});
            pool_.clear();
            pool_.reserve(2 * n_ * levels_of(n_));
            build(1, 0, n_);
            built = true;
        }
        std::size_t j = k_none;
        steepest(1, 0, n_, i + 1, r + 1, i, j);
        if (j <= i + 1)
            continue;  // adjacent contacts: no gap
        const double m = (h_[j] - h_[i]) / (p_[j] - p_[i]);
        std::size_t k = k_none;
        double gap = -std::numeric_limits<double>::infinity();
        deepest(1, 0, n_, i + 1, j, i, m, k, gap);
        if (k != k_none && gap > best) {
            best = gap;
            out.deviation = gap;
            out.at = p_[k];
            out.left = p_[i];
            out.right = p_[j];
        }
    }
    return out;
}

void straightedge::build(std::size_t node, std::size_t lo, std::size_t hi) {
    if (hi - lo > 1) {
        const std::size_t mid = lo + (hi - lo) / 2;
        build(2 * node, lo, mid);
        build(2 * node + 1, mid, hi);
    }
    // cross > 0: b lies above the line from o through a (left turn).
    auto cross = [&](std::size_t o, std::size_t a, std::size_t b) {
        return (p_[a] - p_[o]) * (h_[b] - h_[o]) - (h_[a] - h_[o]) * (p_[b] - p_[o]);
    };
    hull_ref &ref = nodes_[node];
    // Upper hull (right turns only), collinear middle samples dropped.
    ref.upper_first = pool_.size();
    for (std::size_t s = lo; s < hi; ++s) {
        while (pool_.size() - ref.upper_first >= 2 &&
               cross(pool_[pool_.size() - 2], pool_.back(), s) >= 0)
            pool_.pop_back();
        pool_.push_back(s);
    }
    ref.upper_count = pool_.size() - ref.upper_first;
    // Lower hull (left turns only).
    ref.lower_first = pool_.size();
    for (std::size_t s = lo; s < hi; ++s) {
        while (pool_.size() - ref.lower_first >= 2 &&
               cross(pool_[pool_.size() - 2], pool_.back(), s) <= 0)
            pool_.pop_back();
        pool_.push_back(s);
    }
    ref.lower_count = pool_.size() - ref.lower_first;
}

void straightedge::steepest(std::size_t node, std::size_t lo, std::size_t hi, std::size_t from,
                            std::size_t to, std::size_t i, std::size_t &best) const {
    if (to <= lo || hi <= from)
        return;
    // slope(i, a) >= slope(i, b), both to the right of i.
    auto not_flatter = [&](std::size_t a, std::size_t b) {
        return (h_[a] - h_[i]) * (p_[b] - p_[i]) >= (h_[b] - h_[i]) * (p_[a] - p_[i]);
    };
    if (from <= lo && hi <= to) {
        // Along the upper hull the slope from i (left of every sample)
        // rises, then falls: the tangent is where it stops rising.
        const std::size_t *u = pool_.data() + nodes_[node].upper_first;
        std::size_t a = 0, b = nodes_[node].upper_count - 1;
        while (a < b) {
            const std::size_t mid = a + (b - a) / 2;
            if (not_flatter(u[mid + 1], u[mid]))
                a = mid + 1;
            else
                b = mid;
        }
        // Nodes are visited left to right: a later one wins a tie.
        if (best == k_none || not_flatter(u[a], best))
            best = u[a];
        return;
    }
    const std::size_t mid = lo + (hi - lo) / 2;
    steepest(2 * node, lo, mid, from, to, i, best);
    steepest(2 * node + 1, mid, hi, from, to, i, best);
}

void straightedge::deepest(std::size_t node, std::size_t lo, std::size_t hi, std::size_t from,
                           std::size_t to, std::size_t i, double m, std::size_t &best,
                           double &best_gap) const {
    if (to <= lo || hi <= from)
        return;
    if (from <= lo && hi <= to) {
        // The gap below the line is concave along the lower hull (its edges'
        // slopes rise): the deepest vertex is where the edges' slope passes m.
        const std::size_t *l = pool_.data() + nodes_[node].lower_first;
        auto gap = [&](std::size_t k) {
            return m * (p_[k] - p_[i]) - (h_[k] - h_[i]);
        };
        std::size_t a = 0, b = nodes_[node].lower_count - 1;
        while (a < b) {
            const std::size_t mid = a + (b - a) / 2;
            if (gap(l[mid + 1]) >= gap(l[mid]))
                a = mid + 1;
            else
                b = mid;
        }
        const double g = gap(l[a]);
        if (g > best_gap) {
            best_gap = g;
            best = l[a];
        }
        return;
    }
    const std::size_t mid = lo + (hi - lo) / 2;
    deepest(2 * node, lo, mid, from, to, i, m, best, best_gap);
    deepest(2 * node + 1, mid, hi, from, to, i, m, best, best_gap);
}

}  // namespace verdict
}  // namespace flt
