// SPDX-License-Identifier: Apache-2.0
// lib/verdict/straightedge: a map's lines measured in blocks, through the
// internal interface (compiled into this test; the shared library exports
// only flt_*). The blocks' results, merged in any order, must equal the
// whole map's bit for bit; on a tie the smaller line wins whatever the
// blocks; a floor changes nothing above it; once reserved, nothing is
// allocated. (The deviation itself is checked against its definition in
// test_verdict.c, through the C API.)
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <new>
#include <vector>

extern "C" {
#include <setjmp.h>
#include <stdarg.h>

#include <cmocka.h>
}

#include "flatline/recon.h"
#include "verdict/straightedge.hpp"

#ifdef FLT_COUNT_NEW
// Every operator new of this process, counted while g_counting is set (the
// code under test is compiled into this executable).
namespace {
bool g_counting = false;
std::size_t g_allocations = 0;
}  // namespace

void *operator new(std::size_t size) {
    if (g_counting)
        ++g_allocations;
    if (void *p = std::malloc(size == 0 ? 1 : size))
        return p;
    throw std::bad_alloc();
}
void operator delete(void *p) noexcept {
    std::free(p);
}
void operator delete(void *p, std::size_t) noexcept {
    std::free(p);
}
#endif

namespace {

using flt::verdict::map_gap;
using flt::verdict::map_view;
using flt::verdict::straightedge;
using flt::verdict::straightedge_gap;

const double k_pi = 3.14159265358979323846;

std::uint64_t g_seed = 77;

double uniform() {
    g_seed = g_seed * 6364136223846793005ull + 1442695040888963407ull;
    return double(g_seed >> 11) / 9007199254740992.0;
}

// A map: waves along and across with noise, uneven positions, NaN holes
// with FLT_FLAG_NO_DATA.
struct test_map {
    std::size_t rows, fibers;
    std::vector<double> s, x, z;
    std::vector<std::uint8_t> flags;
    test_map(std::size_t r, std::size_t k) : rows(r), fibers(k) {
        s.resize(r);
        x.resize(k);
        z.resize(r * k);
        flags.assign(r * k, 0);
        double pos = 0;
        for (double &v : s)
            v = pos += 1 + 2 * uniform();
        pos = -600;
        for (double &v : x)
            v = pos += 4 + 8 * uniform();
        for (std::size_t i = 0; i < r; ++i)
            for (std::size_t j = 0; j < k; ++j) {
                double v = 2 * std::sin(2 * k_pi * s[i] / 170) * std::cos(k_pi * x[j] / 1300) +
                           0.7 * std::cos(2 * k_pi * x[j] / 500) + 0.05 * (uniform() - 0.5);
                if (uniform() < 0.03) {
                    v = NAN;
                    flags[i * k + j] = FLT_FLAG_NO_DATA;
                }
                z[i * k + j] = v;
            }
    }
    map_view view() const {
        map_view m;
        m.rows = rows;
        m.fibers = fibers;
        m.s = s.data();
        m.x = x.data();
        m.z = z.data();
        m.flags = flags.data();
        return m;
    }
};

// The lines cut into blocks at `cuts` (increasing, inside (0, lines)),
// each measured with its own straightedge into its own part, merged in
// order or in reverse.
map_gap in_blocks(const map_view &m, bool along, double length,
                  const std::vector<std::size_t> &cuts, bool reverse) {
    const std::size_t lines = flt::verdict::line_count(m, along);
    std::vector<std::size_t> edges{0};
    edges.insert(edges.end(), cuts.begin(), cuts.end());
    edges.push_back(lines);
    std::vector<map_gap> parts(edges.size() - 1);
    for (std::size_t b = 0; b + 1 < edges.size(); ++b) {
        straightedge se;
        se.measure_lines(m, along, length, edges[b], edges[b + 1], parts[b]);
    }
    map_gap all;
    for (std::size_t b = 0; b < parts.size(); ++b)
        flt::verdict::merge(all, parts[reverse ? parts.size() - 1 - b : b]);
    return all;
}

bool same(const map_gap &a, const map_gap &b) {
    return a.deviation == b.deviation && a.x == b.x && a.s == b.s && a.line == b.line;
}

const std::vector<std::vector<std::size_t>> k_cuts = {
    {}, {1}, {60}, {30, 31, 90}, {7, 14, 21, 28, 35, 42, 49, 56, 63, 70, 77, 84, 91, 98, 105}};

void blocks_merge_to_the_whole_map(void **) {
    const test_map t(160, 120);
    const map_view m = t.view();
    for (int along = 0; along < 2; ++along)
        for (double length : {15.0, 120.0, 700.0}) {
            straightedge se;
            map_gap whole;
            se.measure_lines(m, along != 0, length, 0, flt::verdict::line_count(m, along != 0),
                             whole);
            assert_true(whole.measured());
            assert_true(whole.deviation > 0);
            for (const auto &cuts : k_cuts)
                for (bool reverse : {false, true}) {
                    const map_gap g = in_blocks(m, along != 0, length, cuts, reverse);
                    if (!same(g, whole))
                        fail_msg("along %d, L = %g, %zu cuts: %.17g at line %zu against "
                                 "%.17g at line %zu",
                                 along, length, cuts.size(), g.deviation, g.line, whole.deviation,
                                 whole.line);
                }
        }
}

void ties_go_to_the_smaller_line(void **) {
    // Every line has a twin in the other half of the map (the same heights
    // and holes), so the worst gap is on two lines. Whatever the blocks,
    // the result is the smaller one's.
    test_map t(150, 110);
    for (std::size_t i = 0; i < t.rows; ++i)
        for (std::size_t j = 0; j < t.fibers; ++j) {
            const std::size_t from = (i % 75) * t.fibers + j % 55, to = i * t.fibers + j;
            t.z[to] = t.z[from];
            t.flags[to] = t.flags[from];
        }
    const map_view m = t.view();
    for (int along = 0; along < 2; ++along)
        for (double length : {20.0, 300.0}) {
            const std::size_t lines = flt::verdict::line_count(m, along != 0);
            double worst = -1;
            std::size_t first = lines;
            for (std::size_t l = 0; l < lines; ++l) {  // each line alone
                straightedge se;
                map_gap g;
                se.measure_lines(m, along != 0, length, l, l + 1, g);
                if (g.deviation > worst) {
                    worst = g.deviation;
                    first = l;
                }
            }
            const std::size_t half = along ? 55 : 75;
            assert_true(first < half);  // the twin in the second half ties
            for (const auto &cuts : k_cuts)
                for (bool reverse : {false, true}) {
                    const map_gap g = in_blocks(m, along != 0, length, cuts, reverse);
                    assert_true(g.deviation == worst);
                    assert_int_equal(g.line, first);
                }
            // And the twin's half first, then the other half into the same
            // part: the smaller line must find the gap equal to the floor.
            map_gap part;
            straightedge se;
            se.measure_lines(m, along != 0, length, half, lines, part);
            assert_int_equal(part.line, first + half);
            se.measure_lines(m, along != 0, length, 0, half, part);
            assert_true(part.deviation == worst);
            assert_int_equal(part.line, first);
        }
}

void a_floor_changes_nothing_above_it(void **) {
    // One fiber of the map as a profile, under floors below, at and above
    // its deviation: exact (the same gap at the same place) when it
    // exceeds the floor, or equals it with ties_count; at most the floor
    // otherwise.
    const test_map t(400, 3);
    std::vector<double> z(t.rows);
    for (std::size_t i = 0; i < t.rows; ++i)
        z[i] = t.z[i * t.fibers + 1];
    straightedge se;
    for (double length : {10.0, 90.0, 2000.0}) {
        const straightedge_gap g =
            se.measure(t.s.data(), z.data(), nullptr, t.rows, 1, 0, length, -1.0);
        assert_true(g.measured && g.deviation > 0);
        for (double floor : {0.0, 0.5 * g.deviation, std::nextafter(g.deviation, 0.0)}) {
            const straightedge_gap f =
                se.measure(t.s.data(), z.data(), nullptr, t.rows, 1, 0, length, floor);
            assert_true(f.deviation == g.deviation && f.at == g.at);
        }
        const straightedge_gap tie =
            se.measure(t.s.data(), z.data(), nullptr, t.rows, 1, 0, length, g.deviation, true);
        assert_true(tie.deviation == g.deviation && tie.at == g.at);
        for (double floor : {g.deviation, 2 * g.deviation}) {
            const straightedge_gap f =
                se.measure(t.s.data(), z.data(), nullptr, t.rows, 1, 0, length, floor);
            assert_true(f.measured && f.deviation <= floor);
        }
    }
}

void nothing_allocated_once_reserved(void **) {
#ifdef FLT_COUNT_NEW
    const test_map big(300, 200), small(120, 80);
    straightedge se;
    se.reserve(300);
    g_allocations = 0;
    g_counting = true;
    for (const test_map *t : {&big, &small})
        for (int along = 0; along < 2; ++along)
            for (double length : {15.0, 500.0}) {
                map_gap g;
                const map_view m = t->view();
                se.measure_lines(m, along != 0, length, 0, flt::verdict::line_count(m, along != 0),
                                 g);
                se.measure(t->s.data(), t->z.data(), t->flags.data(), t->rows, t->fibers,
                           FLT_FLAG_NO_DATA, length, -1.0);
            }
    g_counting = false;
    assert_int_equal(g_allocations, 0);
    // The control: the counter sees a straightedge growing.
    g_counting = true;
    straightedge grown;
    map_gap g;
    grown.measure_lines(big.view(), true, 100.0, 0, big.fibers, g);
    g_counting = false;
    assert_true(g_allocations > 0);
#else
    skip();  // under sanitizers, which own operator new
#endif
}

}  // namespace

int main() {
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(blocks_merge_to_the_whole_map),
        cmocka_unit_test(ties_go_to_the_smaller_line),
        cmocka_unit_test(a_floor_changes_nothing_above_it),
        cmocka_unit_test(nothing_allocated_once_reserved),
    };
    return cmocka_run_group_tests(tests, nullptr, nullptr);
}
