// SPDX-License-Identifier: Apache-2.0
// The straightedge deviation of a profile and of a map's lines (README.md,
// "The straightedge deviation" and "How it is computed").
//
// A straightedge resting on samples i < j (at most `length` apart, every
// sample between on or below their segment) shows the gap max over
// i < k < j of segment(k) - z_k; the deviation is the largest over every
// resting position. The computation is exact (up to rounding) and takes
// time linear in the samples, but for binary searches on hulls:
//
// 1. Every gap is at most the gap under the upper hull of any stretch
//    holding the segment: a resting segment is an edge of the upper hull
//    of the samples from its left to its right contact.
// 2. coarse_bound(): chunks of 16 samples, each between two lines of its
//    chord's slope through its highest and lowest sample, bound every gap
//    of the profile from the hull of their upper corners. A line with no
//    hollow deeper than the deviation already found (on this profile or
//    an earlier line of the same map) stops here.
// 3. On the upper hull of the whole profile (upper_hull(), built from the
//    chunks that reach it), an edge no longer than the straightedge is a
//    resting position under which the hull is as high as any resting
//    segment can be: the gaps under it are final. A longer edge (u, v)
//    bridges a stretch the straightedge cannot span; every segment resting
//    over a sample there has both contacts within [u, v].
// 4. search(): the left contacts of such a stretch in chunks of a
//    sixteenth of the length; their gaps are bounded by the height range,
//    less the tilt, of the samples they reach. Runs of chunks that may
//    exceed the deviation found go to within().
// 5. within(): blocks no longer than the straightedge. A segment inside a
//    block is bounded by, and equal at best to, the gaps under the block's
//    upper hull. A segment leaving it rests on a left contact i in the
//    block and a right one in its head, the samples after it within reach.
//    Of all the contacts i can rest with, the one of largest slope from i
//    (the farthest on a tie) gives the highest segment over every sample,
//    so only that one counts. across_boundary() sweeps i leftwards: the
//    steepest sample from i in the block is its neighbour on the block's
//    upper hull pushed leftwards, in the head the tangent from i to the
//    head's upper hull, which shrinks with i's reach (a hull in an array
//    whose pushes are undone); the deepest sample under the segment is an
//    extreme point of the lower hulls of the block's part and the head's.
//    Rarely (see there) the head's part needs the mirrored sweep from the
//    right contacts.
//
// Every bound allows for rounding (bound_slack), so what a skipped
// stretch would have given, as computed, never exceeds the deviation
// found: the result does not depend on the floor, nor on the order in
// which the lines of a map are measured, with one exception. Where two
// resting positions give exactly the same gap (heights on a grid,
// noise-free shapes), which of them is reported (its deepest sample, and
// the last bits of the gap as computed) may.
#include "verdict/straightedge.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "flatline/recon.h"  // FLT_FLAG_NO_DATA

namespace flt {
namespace verdict {
namespace {

constexpr std::size_t k_none = std::numeric_limits<std::size_t>::max();
// coarse_bound's chunks: samples [16 c, 16 c + 16) make chunk c, whose
// corners are 2 c and 2 c + 1 (a last chunk of one sample has one).
constexpr std::size_t k_chunk = 16;

}  // namespace

void merge(map_gap &into, const map_gap &part) {
    if (!part.measured())
        return;
    if (!into.measured() || part.deviation > into.deviation ||
        (part.deviation == into.deviation && part.line < into.line)) {
        into.deviation = part.deviation;
        into.x = part.x;
        into.s = part.s;
        into.line = part.line;
    }
}

void straightedge::grow(std::size_t count) {
    if (hull_.size() >= count)
        return;
    hull_.resize(count);
    corner_p_.resize(count);
    corner_upper_.resize(count);
    corner_lower_.resize(count);
    chunk_slope_.resize(count / k_chunk + 1);
    upper_left_.resize(count);
    upper_right_.resize(count);
    lower_left_.resize(count);
    lower_right_.resize(count);
    next_.resize(count);
    prev_.resize(count);
    undo_left_.resize(count);
    undo_right_.resize(count);
    undo_lower_.resize(count);
}

void straightedge::reserve(std::size_t count) {
    used_p_.resize(count);
    used_h_.resize(count);
    grow(count);
    low_.reserve(count);
    high_.reserve(count);
    used_.reserve(count);
    order_.reserve(count);
}

straightedge_gap straightedge::measure(const double *pos, const double *z,
                                       const unsigned char *flags, std::size_t count,
                                       std::size_t z_stride, unsigned skip_bits, double length,
                                       double floor, bool ties_count) {
    // The used samples: the profile itself when it has no unused one and
    // is contiguous; else a copy of them (without branches: every sample
    // is written, the used ones kept).
    std::size_t n = 0;
    double extent = 0;  // the largest height magnitude
    bool all = z_stride == 1;
    for (std::size_t i = 0; i < count; ++i)
        all = all && std::isfinite(z[i]) && (flags == nullptr || (flags[i] & skip_bits) == 0);
    if (all) {
        p_ = pos;
        h_ = z;
        n = count;
        for (std::size_t i = 0; i < count; ++i)
            extent = std::max(extent, std::fabs(z[i]));
    } else {
        if (used_p_.size() < count) {
            used_p_.resize(count);
            used_h_.resize(count);
        }
        double *pp = used_p_.data(), *hh = used_h_.data();
        for (std::size_t i = 0; i < count; ++i) {
            const double v = z[i * z_stride];
            const bool u =
                std::isfinite(v) && (flags == nullptr || (flags[i * z_stride] & skip_bits) == 0);
            pp[n] = pos[i];
            hh[n] = v;
            n += u ? 1 : 0;
            extent = u && std::fabs(v) > extent ? std::fabs(v) : extent;
        }
        p_ = pp;
        h_ = hh;
    }
    return measure_used(n, extent, length, floor, ties_count);
}

straightedge_gap straightedge::measure_used(std::size_t n, double extent, double length,
                                            double floor, bool ties_count) {
    n_ = n;
    straightedge_gap out;
    if (n_ < 2)
        return out;
    out.measured = true;
    out.at = out.left = p_[0];
    out.right = p_[1];
    grow(n_);

    // A span of exactly the length on a grid of positions counts, whatever
    // the rounding of the positions (1e-9 relative).
    reach_ = length * (1.0 + 1e-9);
    // Gaps are recorded when they exceed best_: the floor, or just below
    // it when a gap equal to the floor must be found too.
    best_ = 0.0;
    if (floor > 0)
        best_ =
            ties_count ? std::nextafter(floor, -std::numeric_limits<double>::infinity()) : floor;
    found_ = false;
    slack_ = bound_slack(extent);
    if (coarse_bound() + slack_ <= best_)
        return out;

    // The upper hull of the whole profile (collinear samples dropped).
    const std::size_t hn = upper_hull();
    const std::size_t *hull = hull_.data();
    // Its edges: a short one rests, a long one bounds a stretch to search.
    // within() reuses every array but hull_.
    for (std::size_t e = 0; e + 1 < hn; ++e) {
        const std::size_t u = hull[e], v = hull[e + 1];
        if (v - u < 2)
            continue;
        if (p_[v] - p_[u] <= reach_) {
            std::size_t k = 0;
            const double gap = deepest_under(u, v, k);
            consider(gap, k, u, v);
        } else if (depth_bound(u, v) + slack_ > best_) {
            search(u, v);
        }
    }
    if (found_) {
        out.deviation = best_;
        out.at = p_[best_k_];
        out.left = p_[best_i_];
        out.right = p_[best_j_];
    }
    return out;
}

double straightedge::coarse_bound() {
    // Chunks of k_chunk samples, each between two parallel lines of its
    // chord's slope: one through its highest sample, one through its
    // lowest. A segment resting on the profile lies below the upper hull
    // of the upper lines' ends (the corners), and a sample lies above its
    // chunk's lower line; within a chunk both are straight, so the gap is
    // largest at a chunk's end: under the corners' hull above a lower
    // line's end. The bound holds for a straightedge of any length; on a
    // line with no hollow longer than a chunk it is about the height of
    // the measurement noise.
    const double *p = p_, *h = h_;
    // The chords' slopes first: the divisions overlap.
    double *slopes = chunk_slope_.data();
    const std::size_t chunks = (n_ + k_chunk - 1) / k_chunk;
    for (std::size_t c = 0; c < chunks; ++c) {
        const std::size_t f = c * k_chunk, l = std::min(f + k_chunk, n_) - 1;
        slopes[c] = l > f ? (h[l] - h[f]) / (p[l] - p[f]) : 0.0;
    }
    std::size_t corners = 0;
    for (std::size_t f = 0; f < n_; f += k_chunk) {
        const std::size_t l = std::min(f + k_chunk, n_) - 1;
        const double span = p[l] - p[f];
        const double slope = slopes[f / k_chunk];
        double low_all = h[f], high_all = h[f];
        if (l - f + 1 == k_chunk) {
            // Four interleaved minima and maxima (one would wait on the
            // last), over a whole chunk the compiler unrolls.
            double lo[4] = {h[f], h[f], h[f], h[f]}, hi[4] = {h[f], h[f], h[f], h[f]};
            for (std::size_t d = 1; d < k_chunk; ++d) {
                const double v = h[f + d] - slope * (p[f + d] - p[f]);
                lo[d % 4] = v < lo[d % 4] ? v : lo[d % 4];
                hi[d % 4] = v > hi[d % 4] ? v : hi[d % 4];
            }
            low_all = std::min(std::min(lo[0], lo[1]), std::min(lo[2], lo[3]));
            high_all = std::max(std::max(hi[0], hi[1]), std::max(hi[2], hi[3]));
        } else {
            for (std::size_t q = f + 1; q <= l; ++q) {
                const double v = h[q] - slope * (p[q] - p[f]);
                low_all = v < low_all ? v : low_all;
                high_all = v > high_all ? v : high_all;
            }
        }
        corner_p_[corners] = p[f];
        corner_upper_[corners] = high_all;
        corner_lower_[corners++] = low_all;
        if (l > f) {
            corner_p_[corners] = p[l];
            corner_upper_[corners] = high_all + slope * span;
            corner_lower_[corners++] = low_all + slope * span;
        }
    }
    corners_ = corners;
    const double *cp = corner_p_.data(), *cu = corner_upper_.data(), *cl = corner_lower_.data();
    std::size_t *hull = hull_.data(), hn = 0;
    for (std::size_t q = 0; q < corners; ++q) {
        while (hn >= 2) {
            const std::size_t o = hull[hn - 2], t = hull[hn - 1];
            if ((cu[q] - cu[o]) * (cp[t] - cp[o]) >= (cu[t] - cu[o]) * (cp[q] - cp[o]))
                --hn;
            else
                break;
        }
        hull[hn++] = q;
    }
    if (hn == 1)
        return cu[0] - cl[0];
    double bound = 0;
    std::size_t e = 0;  // the hull's edge over corner q: hull[e] .. hull[e + 1]
    double slope = (cu[hull[1]] - cu[hull[0]]) / (cp[hull[1]] - cp[hull[0]]);
    for (std::size_t q = 0; q < corners; ++q) {
        if (e + 2 < hn && hull[e + 1] <= q) {  // corners on the hull end an edge
            ++e;
            slope = (cu[hull[e + 1]] - cu[hull[e]]) / (cp[hull[e + 1]] - cp[hull[e]]);
        }
        const double top = cu[hull[e]] + slope * (cp[q] - cp[hull[e]]);
        bound = std::max(bound, top - cl[q]);
    }
    return bound;
}

std::size_t straightedge::upper_hull() {
    // Its vertices lie in chunks whose upper line (coarse_bound) reaches
    // the upper hull of the chunks' highest samples (which lies below the
    // profile's): the line is straight and that hull concave, so a chunk
    // whose corners are both below it lies below it. The hull of the
    // samples of the other chunks is the profile's.
    const double *p = p_, *h = h_;
    const double *cp = corner_p_.data(), *cu = corner_upper_.data();
    const std::size_t chunks = (n_ + k_chunk - 1) / k_chunk;
    std::size_t *tops = upper_right_.data(), tn = 0;  // free until within()
    for (std::size_t c = 0; c < chunks; ++c) {
        // The chunk's sample on its upper line: the first farthest above
        // its chord.
        const std::size_t f = c * k_chunk, l = std::min(f + k_chunk, n_) - 1;
        const double slope = chunk_slope_[c];
        std::size_t q = f;
        double high = h[f];
        for (std::size_t k = f + 1; k <= l; ++k) {
            const double v = h[k] - slope * (p[k] - p[f]);
            q = v > high ? k : q;
            high = v > high ? v : high;
        }
        while (tn >= 2) {
            const std::size_t o = tops[tn - 2], t = tops[tn - 1];
            if ((h[q] - h[o]) * (p[t] - p[o]) >= (h[t] - h[o]) * (p[q] - p[o]))
                --tn;
            else
                break;
        }
        tops[tn++] = q;
    }
    std::size_t e = 0;                         // the edge of the tops' hull over the corner
    const auto reaches = [&](std::size_t q) {  // corner q on or above the tops' hull
        if (cp[q] < p[tops[0]] || cp[q] > p[tops[tn - 1]])
            return true;
        while (e + 1 < tn && p[tops[e + 1]] < cp[q])
            ++e;
        if (e + 1 == tn)  // at the last top
            return cu[q] + slack_ >= h[tops[e]];
        const std::size_t a = tops[e], b = tops[e + 1];
        return cu[q] + slack_ >= h[a] + (h[b] - h[a]) * ((cp[q] - p[a]) / (p[b] - p[a]));
    };

    std::size_t *hull = hull_.data(), hn = 0;
    double op = 0, oh = 0, tp = 0, th = 0;  // hull[hn - 2], hull[hn - 1]
    for (std::size_t c = 0; c < chunks; ++c) {
        // Corners 2 c and 2 c + 1 (a last chunk of one sample has one).
        if (!reaches(2 * c) && (2 * c + 1 >= corners_ || !reaches(2 * c + 1)))
            continue;
        for (std::size_t q = c * k_chunk; q < std::min((c + 1) * k_chunk, n_); ++q) {
            const double qp = p[q], qh = h[q];
            // The top on or below the segment from the one under it to q
            // leaves; the top two samples' coordinates are kept at hand.
            while (hn >= 2 && (qh - oh) * (tp - op) >= (th - oh) * (qp - op)) {
                --hn;
                tp = op;
                th = oh;
                if (hn >= 2) {
                    op = p[hull[hn - 2]];
                    oh = h[hull[hn - 2]];
                }
            }
            hull[hn++] = q;
            op = tp;
            oh = th;
            tp = qp;
            th = qh;
        }
    }
    return hn;
}

double straightedge::depth_bound(std::size_t u, std::size_t v) const {
    // The samples of chunks partly in (u, v), and the lower corners of the
    // chunks wholly in it (coarse_bound: a sample lies above its chunk's
    // lower line, and a line minus a line is largest at an end).
    const double *p = p_, *h = h_;
    const double *cp = corner_p_.data(), *cl = corner_lower_.data();
    const double m = (h[v] - h[u]) / (p[v] - p[u]);
    double bound = 0;
    const auto sample = [&](std::size_t q) {
        bound = std::max(bound, m * (p[q] - p[u]) - (h[q] - h[u]));
    };
    const std::size_t whole = u / k_chunk + 1, end = v / k_chunk;  // chunks [whole, end)
    if (whole >= end) {
        for (std::size_t q = u + 1; q < v; ++q)
            sample(q);
        return bound;
    }
    for (std::size_t q = u + 1; q < whole * k_chunk; ++q)
        sample(q);
    for (std::size_t q = 2 * whole; q < 2 * end; ++q)
        bound = std::max(bound, m * (cp[q] - p[u]) - (cl[q] - h[u]));
    for (std::size_t q = end * k_chunk; q < v; ++q)
        sample(q);
    return bound;
}

double straightedge::deepest_under(std::size_t u, std::size_t v, std::size_t &k) const {
    const double m = (h_[v] - h_[u]) / (p_[v] - p_[u]);
    double best = -std::numeric_limits<double>::infinity();
    k = u + 1;
    for (std::size_t q = u + 1; q < v; ++q) {
        const double gap = m * (p_[q] - p_[u]) - (h_[q] - h_[u]);
        if (gap > best) {
            best = gap;
            k = q;
        }
    }
    return best;
}

void straightedge::search(std::size_t lo, std::size_t hi) {
    // Left contacts in chunks of a sixteenth of the length: those of chunk
    // [c0, c1] rest within [c0, r], r the last sample within reach of c1.
    // Their gaps are at most the range of z - slope p over [c0, r], for
    // any slope (a segment minus a line lies between its ends' values);
    // the slope from c0 to r follows the stretch's tilt, and the range is
    // then close to the gap where the stretch is hollow, where the gaps
    // are. Over coarse_bound's chunks wholly within [c0, r] the range is
    // bounded from their corners (a sample lies between its chunk's lines,
    // and a line minus the slope is largest at an end). A run of chunks
    // that can exceed the deviation found is searched exactly over the
    // samples its contacts reach.
    const double *p = p_, *h = h_;
    const double *cp = corner_p_.data(), *cu = corner_upper_.data(), *cl = corner_lower_.data();
    const double chunk = reach_ / 16;
    // The run's samples, and its last left contact.
    std::size_t run_lo = k_none, run_hi = 0, run_left = 0;
    std::size_t r = lo;
    for (std::size_t c0 = lo; c0 < hi;) {
        std::size_t c1 = c0;
        while (c1 + 1 < hi && p[c1 + 1] - p[c0] <= chunk)
            ++c1;
        while (r < hi && p[r + 1] - p[c1] <= reach_)
            ++r;
        bool open = false;
        if (r >= c0 + 2) {
            const double slope = (h[r] - h[c0]) / (p[r] - p[c0]);
            double low = h[c0], high = h[c0];
            const auto sample = [&](std::size_t q) {
                const double v = h[q] - slope * (p[q] - p[c0]);
                low = v < low ? v : low;
                high = v > high ? v : high;
            };
            // The whole chunks from the corners, the samples at the ends.
            const std::size_t whole = c0 / k_chunk + 1, end = (r + 1) / k_chunk;
            if (whole < end) {
                for (std::size_t q = c0 + 1; q < whole * k_chunk; ++q)
                    sample(q);
                for (std::size_t q = 2 * whole; q < 2 * end; ++q) {
                    const double drop = slope * (cp[q] - p[c0]);
                    low = std::min(low, cl[q] - drop);
                    high = std::max(high, cu[q] - drop);
                }
                for (std::size_t q = end * k_chunk; q <= r; ++q)
                    sample(q);
            } else {
                for (std::size_t q = c0 + 1; q <= r; ++q)
                    sample(q);
            }
            open = high - low + slack_ > best_;
        }
        if (open) {
            if (run_lo != k_none && c0 > run_hi) {  // a new run, apart from the last
                within(run_lo, run_hi, run_left);
                run_lo = k_none;
            }
            if (run_lo == k_none)
                run_lo = c0;
            run_left = c1;
            run_hi = r;
        }
        c0 = c1 + 1;
    }
    if (run_lo != k_none)
        within(run_lo, run_hi, run_left);
}

void straightedge::within(std::size_t lo, std::size_t hi, std::size_t left) {
    std::size_t m0 = lo;
    while (m0 <= left) {
        // The block [m0, m): every sample within reach of m0, none past the
        // last left contact wanted.
        std::size_t m = m0 + 1;
        while (m <= left && p_[m] - p_[m0] <= reach_)
            ++m;
        // Its upper hull, pushed leftwards (each sample's steepest
        // neighbour within the block recorded for across_boundary), and the
        // gaps under its edges, which all rest.
        upper_left_n_ = 0;
        for (std::size_t q = m; q-- > m0;)
            push_upper_left(q);
        for (std::size_t e = upper_left_n_ - 1; e > 0; --e) {
            const std::size_t u = upper_left_[e], v = upper_left_[e - 1];
            if (v - u < 2)
                continue;
            std::size_t k = 0;
            const double gap = deepest_under(u, v, k);
            consider(gap, k, u, v);
        }
        if (m > hi)
            break;
        // The samples after the block within reach of its last one: a
        // segment from the block ends there (the next block starts beyond
        // the reach of every sample before it, so no segment crosses two
        // boundaries but from a block cut short, the last one).
        std::size_t r = m;
        while (r < hi && p_[r + 1] - p_[m - 1] <= reach_)
            ++r;
        if (p_[r] - p_[m - 1] <= reach_)
            across_boundary(m0, m, r);
        m0 = m;
    }
}

void straightedge::across_boundary(std::size_t m0, std::size_t m, std::size_t r) {
    // No gap can exceed the range of heights of [m0, r].
    double lo = h_[m0], hi = h_[m0];
    for (std::size_t q = m0 + 1; q <= r; ++q) {
        lo = std::min(lo, h_[q]);
        hi = std::max(hi, h_[q]);
    }
    if (hi - lo + slack_ <= best_)
        return;

    // The head [m, r], its upper and lower hulls pushed rightwards (the
    // pushes undone below).
    upper_right_n_ = 0;
    lower_right_n_ = 0;
    for (std::size_t q = m; q <= r; ++q) {
        push_upper_right(q);
        push_lower_right(q, true);
    }

    // Left contacts i from m - 1 leftwards: the head shrinks to i's reach;
    // lower_left_ holds the lower hull of (i, m). Under the segment from i
    // to its farthest contact j in the head, the samples of (i, m) are
    // searched on lower_left_, those of [m, j) on the head's lower hull:
    // that search covers the head past j too, under the segment's
    // extension, so it is exact when the deepest sample lies before j, and
    // a bound otherwise. Only when such a bound exceeds the deviation found
    // is the head searched from its right contacts (below).
    lower_left_n_ = 0;
    bool unsettled = false;
    std::size_t last = r;  // the head is [m, last]
    for (std::size_t i = m; i-- > m0;) {
        while (last >= m && p_[last] - p_[i] > reach_) {
            pop_upper_right(last);
            pop_lower_right(last--);
        }
        if (last < m)
            break;  // nothing to the left reaches across either
        const std::size_t j = tangent_from(i);
        // The farthest contact crosses m unless i's neighbour in the block
        // is steeper (a tie goes to the farther, in the head).
        const std::size_t f = i + 1 < m ? next_[i] : k_none;
        if (f == k_none || (h_[j] - h_[i]) * (p_[f] - p_[i]) >= (h_[f] - h_[i]) * (p_[j] - p_[i])) {
            const double slope = (h_[j] - h_[i]) / (p_[j] - p_[i]);
            if (i + 1 < m) {
                std::size_t k = 0;
                const double gap = deepest_on(lower_left_.data(), lower_left_n_, true, i, slope, k);
                consider(gap, k, i, j);
            }
            if (j > m) {
                std::size_t k = 0;
                const double gap =
                    deepest_on(lower_right_.data(), lower_right_n_, false, i, slope, k);
                if (k < j)
                    consider(gap, k, i, j);
                else if (gap + slack_ > best_)
                    unsettled = true;
            }
        }
        push_lower_left(i);
    }
    if (!unsettled)
        return;

    // Right contacts j from m rightwards: the samples of [m, j) are deepest
    // under the segment from j's farthest left contact. The block's upper
    // hull shrinks from the left to j's reach (undoing its pushes);
    // lower_right_ holds the lower hull of [m, j).
    lower_right_n_ = 0;
    std::size_t first = m0;  // the block's hull is of [first, m)
    for (std::size_t j = m; j <= r; ++j) {
        while (p_[j] - p_[first] > reach_)
            pop_upper_left(first++);
        if (j > m) {
            const std::size_t i = tangent_to(j), b = prev_[j];
            // The farthest left contact is in the block unless j's
            // neighbour in the head gives a higher line (a tie goes to the
            // farther, in the block).
            if ((h_[j] - h_[i]) * (p_[j] - p_[b]) <= (h_[j] - h_[b]) * (p_[j] - p_[i])) {
                const double slope = (h_[j] - h_[i]) / (p_[j] - p_[i]);
                std::size_t k = 0;
                const double gap =
                    deepest_on(lower_right_.data(), lower_right_n_, false, i, slope, k);
                consider(gap, k, i, j);
            }
        }
        push_lower_right(j, false);
    }
}

// Upper hull pushed leftwards: upper_left_[0] the rightmost sample, the top
// the leftmost. q goes on top; a top sample on or below the segment from q
// to the one under it leaves. What stays under q is its steepest sample.
void straightedge::push_upper_left(std::size_t q) {
    std::size_t n = upper_left_n_;
    while (n >= 2) {
        const std::size_t t = upper_left_[n - 1], o = upper_left_[n - 2];
        if ((h_[o] - h_[q]) * (p_[t] - p_[q]) >= (h_[t] - h_[q]) * (p_[o] - p_[q]))
            --n;
        else
            break;
    }
    undo_left_[q] = undo{upper_left_n_, n, upper_left_[n]};
    upper_left_[n] = q;
    upper_left_n_ = n + 1;
    next_[q] = n >= 1 ? upper_left_[n - 1] : k_none;
}

// Upper hull pushed rightwards: upper_right_[0] the leftmost sample.
void straightedge::push_upper_right(std::size_t q) {
    std::size_t n = upper_right_n_;
    while (n >= 2) {
        const std::size_t t = upper_right_[n - 1], o = upper_right_[n - 2];
        if ((h_[q] - h_[o]) * (p_[t] - p_[o]) >= (h_[t] - h_[o]) * (p_[q] - p_[o]))
            --n;
        else
            break;
    }
    undo_right_[q] = undo{upper_right_n_, n, upper_right_[n]};
    upper_right_[n] = q;
    upper_right_n_ = n + 1;
    prev_[q] = n >= 1 ? upper_right_[n - 1] : k_none;
}

// Undoes the push of q, the last one not undone.
void straightedge::pop_upper_left(std::size_t q) {
    const undo &u = undo_left_[q];
    upper_left_[u.pos] = u.old;
    upper_left_n_ = u.size;
}

void straightedge::pop_upper_right(std::size_t q) {
    const undo &u = undo_right_[q];
    upper_right_[u.pos] = u.old;
    upper_right_n_ = u.size;
}

// Lower hulls: a top sample on or above the segment leaves.
void straightedge::push_lower_left(std::size_t q) {
    std::size_t n = lower_left_n_;
    while (n >= 2) {
        const std::size_t t = lower_left_[n - 1], o = lower_left_[n - 2];
        if ((h_[t] - h_[q]) * (p_[o] - p_[q]) >= (h_[o] - h_[q]) * (p_[t] - p_[q]))
            --n;
        else
            break;
    }
    lower_left_[n] = q;
    lower_left_n_ = n + 1;
}

void straightedge::push_lower_right(std::size_t q, bool undoable) {
    std::size_t n = lower_right_n_;
    while (n >= 2) {
        const std::size_t t = lower_right_[n - 1], o = lower_right_[n - 2];
        if ((h_[t] - h_[o]) * (p_[q] - p_[o]) >= (h_[q] - h_[o]) * (p_[t] - p_[o]))
            --n;
        else
            break;
    }
    if (undoable)
        undo_lower_[q] = undo{lower_right_n_, n, lower_right_[n]};
    lower_right_[n] = q;
    lower_right_n_ = n + 1;
}

void straightedge::pop_lower_right(std::size_t q) {
    const undo &u = undo_lower_[q];
    lower_right_[u.pos] = u.old;
    lower_right_n_ = u.size;
}

std::size_t straightedge::tangent_from(std::size_t i) const {
    // Along the hull the slope from i rises, then falls: the tangent is
    // where it stops rising (a tie moves on, to the farther).
    const std::size_t *u = upper_right_.data();
    std::size_t a = 0, b = upper_right_n_ - 1;
    while (a < b) {
        const std::size_t mid = a + (b - a) / 2, s = u[mid], t = u[mid + 1];
        if ((h_[t] - h_[i]) * (p_[s] - p_[i]) >= (h_[s] - h_[i]) * (p_[t] - p_[i]))
            a = mid + 1;
        else
            b = mid;
    }
    return u[a];
}

std::size_t straightedge::tangent_to(std::size_t j) const {
    // Left to right along the hull (the array's top down) the slope to j
    // falls, then rises: the tangent is where it stops falling (a tie
    // stays, with the farther).
    const std::size_t *u = upper_left_.data();
    const std::size_t n = upper_left_n_;
    std::size_t a = 0, b = n - 1;
    while (a < b) {
        const std::size_t mid = a + (b - a) / 2, s = u[n - 1 - mid], t = u[n - 2 - mid];
        if ((h_[j] - h_[t]) * (p_[j] - p_[s]) < (h_[j] - h_[s]) * (p_[j] - p_[t]))
            a = mid + 1;
        else
            b = mid;
    }
    return u[n - 1 - a];
}

double straightedge::deepest_on(const std::size_t *hull, std::size_t count, bool reversed,
                                std::size_t i, double m, std::size_t &k) const {
    // The gap below the line is concave along a lower hull (its edges'
    // slopes rise): the deepest vertex is where they pass m.
    const auto at = [&](std::size_t q) {
        return reversed ? hull[count - 1 - q] : hull[q];
    };
    const auto gap = [&](std::size_t q) {
        return m * (p_[q] - p_[i]) - (h_[q] - h_[i]);
    };
    std::size_t a = 0, b = count - 1;
    while (a < b) {
        const std::size_t mid = a + (b - a) / 2;
        if (gap(at(mid + 1)) >= gap(at(mid)))
            a = mid + 1;
        else
            b = mid;
    }
    k = at(a);
    return gap(k);
}

void straightedge::measure_lines(const map_view &m, bool along, double length, std::size_t first,
                                 std::size_t last, map_gap &part) {
    if (m.rows == 0 || m.fibers == 0 || first >= last)
        return;
    const std::size_t lines = last - first;
    const std::size_t samples = along ? m.rows : m.fibers;  // per line
    // Each line's height range and used samples, in the map's memory order
    // (without branches: an unused sample counts as a used one's twin).
    low_.resize(lines);
    high_.resize(lines);
    used_.resize(lines);
    const auto used = [&](std::size_t at, double v) {
        return std::isfinite(v) && (m.flags == nullptr || (m.flags[at] & FLT_FLAG_NO_DATA) == 0);
    };
    if (along) {
        double *low = low_.data(), *high = high_.data();
        std::size_t *count = used_.data();
        for (std::size_t l = 0; l < lines; ++l) {
            low[l] = std::numeric_limits<double>::infinity();
            high[l] = -low[l];
            count[l] = 0;
        }
        for (std::size_t r = 0; r < m.rows; ++r) {
            const std::size_t row = r * m.fibers + first;
            for (std::size_t l = 0; l < lines; ++l) {
                const double v = m.z[row + l];
                const bool u = used(row + l, v);
                low[l] = u && v < low[l] ? v : low[l];
                high[l] = u && v > high[l] ? v : high[l];
                count[l] += u ? 1 : 0;
            }
        }
    } else {
        // Four interleaved minima and maxima: one would wait on the last.
        const double inf = std::numeric_limits<double>::infinity();
        for (std::size_t l = 0; l < lines; ++l) {
            const std::size_t row = (first + l) * m.fibers;
            double lo0 = inf, lo1 = inf, lo2 = inf, lo3 = inf;
            double hi0 = -inf, hi1 = -inf, hi2 = -inf, hi3 = -inf;
            std::size_t count = 0;
            const auto take = [&](std::size_t k, double &lo, double &hi) {
                const double v = m.z[row + k];
                const bool u = used(row + k, v);
                lo = u && v < lo ? v : lo;
                hi = u && v > hi ? v : hi;
                count += u ? 1 : 0;
            };
            std::size_t k = 0;
            for (; k + 4 <= m.fibers; k += 4) {
                take(k, lo0, hi0);
                take(k + 1, lo1, hi1);
                take(k + 2, lo2, hi2);
                take(k + 3, lo3, hi3);
            }
            for (; k < m.fibers; ++k)
                take(k, lo0, hi0);
            low_[l] = std::min(std::min(lo0, lo1), std::min(lo2, lo3));
            high_[l] = std::max(std::max(hi0, hi1), std::max(hi2, hi3));
            used_[l] = count;
        }
    }
    // The tallest lines first: a line's gap never exceeds its range, so
    // they raise the floor early and most others are skipped. Ties in line
    // order. std::stable_sort may allocate; a heap sort is in place.
    order_.resize(lines);
    for (std::size_t l = 0; l < lines; ++l)
        order_[l] = l;
    const auto range = [&](std::size_t l) {
        return used_[l] >= 2 ? high_[l] - low_[l] : -1.0;
    };
    const auto before = [&](std::size_t a, std::size_t b) {  // a goes first
        const double ra = range(a), rb = range(b);
        return ra > rb || (ra == rb && a < b);
    };
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
    for (std::size_t i = lines / 2; i-- > 0;)
        sift(i, lines);
    for (std::size_t end = lines; end > 1; --end) {
        std::swap(order_[0], order_[end - 1]);
        sift(0, end - 1);
    }

    for (std::size_t l : order_) {
        if (used_[l] < 2)
            break;  // the rest measure nothing either
        const std::size_t line = first + l;
        // Ties go to the smaller line: a smaller one must find a gap equal
        // to the worst so far, a larger one must exceed it.
        const bool ties_count = line < part.line;
        const double bound =
            range(l) + bound_slack(std::max(std::fabs(low_[l]), std::fabs(high_[l])));
        if (part.measured() && (bound < part.deviation || (bound == part.deviation && !ties_count)))
            continue;
        const double floor = part.measured() ? part.deviation : -1.0;
        straightedge_gap g;
        double x = 0, s = 0;
        if (along) {
            g = measure(m.s, m.z + line, m.flags ? m.flags + line : nullptr, samples, m.fibers,
                        FLT_FLAG_NO_DATA, length, floor, ties_count);
            x = m.x[line];
            s = g.at;
        } else if (used_[l] == samples) {
            // A complete row: measured in place, its extent known.
            p_ = m.x;
            h_ = m.z + line * m.fibers;
            g = measure_used(samples, std::max(std::fabs(low_[l]), std::fabs(high_[l])), length,
                             floor, ties_count);
            x = g.at;
            s = m.s[line];
        } else {
            const std::size_t at = line * m.fibers;
            g = measure(m.x, m.z + at, m.flags ? m.flags + at : nullptr, samples, 1,
                        FLT_FLAG_NO_DATA, length, floor, ties_count);
            x = g.at;
            s = m.s[line];
        }
        if (!g.measured)
            continue;
        if (!part.measured() || g.deviation > part.deviation ||
            (g.deviation == part.deviation && ties_count)) {
            part.deviation = g.deviation;
            part.x = x;
            part.s = s;
            part.line = line;
        }
    }
}

}  // namespace verdict
}  // namespace flt
