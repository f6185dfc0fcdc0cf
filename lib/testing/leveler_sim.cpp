// SPDX-License-Identifier: Apache-2.0
// The hidden leveler of flatline/testing.h: the advisor's closed loop in
// the simulator. True influence matrix -> zone elongation profile -> a
// height map of sine waves whose I-Units are that profile.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "core/error.hpp"
#include "flatline/testing.h"

using namespace flt;

namespace {
constexpr std::uint32_t k_magic = 0x464c544cu;  // "FLTL"
constexpr double k_pi = 3.14159265358979323846;
constexpr int k_columns_per_zone = 8;
constexpr int k_rows_per_period = 32;
constexpr double k_max_value = 1e9;

// splitmix64: the same noise on every platform (std::normal_distribution
// is not specified bit for bit).
std::uint64_t mix(std::uint64_t x) {
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    return x ^ (x >> 31);
}

double uniform(std::uint64_t &state) {  // (0, 1)
    state = mix(state);
    return (double(state >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

double normal(std::uint64_t &state) {  // Box-Muller
    const double u1 = uniform(state), u2 = uniform(state);
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * k_pi * u2);
}

flt_status check_values(const char *fn, const char *name, const double *v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        if (!(std::fabs(v[i]) <= k_max_value))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument '%s'[%zu] = %g is not a finite value within +-1e9", fn, name,
                        i, v[i]);
    return FLT_OK;
}
}  // namespace

struct flt_leveler_sim {
    std::uint32_t magic = k_magic;
    std::size_t zones = 0, actuators = 0;
    double x0 = 0, width = 0, noise = 0;
    std::uint64_t seed = 0, sheet = 0;
    std::vector<double> g, incoming;
    std::vector<double> next, pending;  // the next sheet's settings; those given since
};

namespace {
flt_status check_leveler(const char *fn, const flt_leveler_sim *l) {
    if (l == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'leveler' is NULL", fn);
    if (l->magic != k_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'leveler' is not a live flt_leveler_sim", fn);
    return FLT_OK;
}
}  // namespace

extern "C" {

FLT_TESTING_API flt_status FLT_CALL flt_leveler_sim_create(size_t zones, size_t actuators,
                                                           double zone_x0_mm, double zone_width_mm,
                                                           const double *g_true, size_t g_count,
                                                           const double *incoming,
                                                           size_t incoming_count, double noise_iu,
                                                           uint64_t seed, flt_leveler_sim **out) {
    const char *fn = "flt_leveler_sim_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (zones < 1 || zones > 1024)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'zones' = %zu is outside 1..1024",
                        fn, zones);
        if (actuators < 1 || actuators > 64)
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'actuators' = %zu is outside 1..64",
                        fn, actuators);
        if (!(std::fabs(zone_x0_mm) <= 1e6))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'zone_x0_mm' = %g is not within +-1e6 mm", fn, zone_x0_mm);
        if (!(zone_width_mm > 0) || !(zone_width_mm <= 1e5))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'zone_width_mm' = %g is outside (0, 1e5] mm", fn,
                        zone_width_mm);
        FLT_CHECK_NOT_NULL(fn, g_true);
        if (g_count != zones * actuators)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'g_count' = %zu, expected zones x actuators = %zu", fn,
                        g_count, zones * actuators);
        FLT_CHECK_NOT_NULL(fn, incoming);
        if (incoming_count != zones)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'incoming_count' = %zu, expected zones = %zu", fn,
                        incoming_count, zones);
        if (flt_status st = check_values(fn, "g_true", g_true, g_count))
            return st;
        if (flt_status st = check_values(fn, "incoming", incoming, incoming_count))
            return st;
        if (!(noise_iu >= 0) || !(noise_iu <= 1e4))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'noise_iu' = %g is outside [0, 1e4] I-Units", fn, noise_iu);
        auto *l = new flt_leveler_sim;
        l->zones = zones;
        l->actuators = actuators;
        l->x0 = zone_x0_mm;
        l->width = zone_width_mm;
        l->noise = noise_iu;
        l->seed = seed;
        l->g.assign(g_true, g_true + g_count);
        l->incoming.assign(incoming, incoming + incoming_count);
        l->next.assign(actuators, 0.0);
        l->pending.assign(actuators, 0.0);
        *out = l;
        return FLT_OK;
    });
}

FLT_TESTING_API void FLT_CALL flt_leveler_sim_destroy(flt_leveler_sim *leveler) {
    guard_void([&] {
        if (leveler && leveler->magic == k_magic) {
            leveler->magic = 0;
            delete leveler;
        }
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_leveler_sim_set_settings(flt_leveler_sim *leveler,
                                                                 const double *settings,
                                                                 size_t settings_count) {
    const char *fn = "flt_leveler_sim_set_settings";
    return guard(fn, [&] {
        if (flt_status st = check_leveler(fn, leveler))
            return st;
        FLT_CHECK_NOT_NULL(fn, settings);
        if (settings_count != leveler->actuators)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'settings_count' = %zu, expected actuators = %zu", fn,
                        settings_count, leveler->actuators);
        if (flt_status st = check_values(fn, "settings", settings, settings_count))
            return st;
        leveler->pending.assign(settings, settings + settings_count);
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_leveler_sim_set_incoming(flt_leveler_sim *leveler,
                                                                 const double *incoming,
                                                                 size_t incoming_count) {
    const char *fn = "flt_leveler_sim_set_incoming";
    return guard(fn, [&] {
        if (flt_status st = check_leveler(fn, leveler))
            return st;
        FLT_CHECK_NOT_NULL(fn, incoming);
        if (incoming_count != leveler->zones)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'incoming_count' = %zu, expected zones = %zu", fn,
                        incoming_count, leveler->zones);
        if (flt_status st = check_values(fn, "incoming", incoming, incoming_count))
            return st;
        leveler->incoming.assign(incoming, incoming + incoming_count);
        return FLT_OK;
    });
}

FLT_TESTING_API flt_status FLT_CALL flt_leveler_sim_next_sheet(
    flt_leveler_sim *leveler, flt_sim *sim, double s0_mm, double length_mm, double period_mm,
    double *elongation_out, size_t elongation_count, double *settings_out, size_t settings_count) {
    const char *fn = "flt_leveler_sim_next_sheet";
    return guard(fn, [&] {
        if (flt_status st = check_leveler(fn, leveler))
            return st;
        flt_leveler_sim &l = *leveler;
        FLT_CHECK_NOT_NULL(fn, sim);
        if (!(std::fabs(s0_mm) <= 1e12))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 's0_mm' = %g is not within +-1e12",
                        fn, s0_mm);
        if (!(length_mm > 0) || !(length_mm <= 1e6))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'length_mm' = %g is outside (0, 1e6] mm", fn, length_mm);
        if (!(period_mm >= length_mm / 1000) || !(period_mm <= length_mm))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'period_mm' = %g is outside [length / 1000, length] = [%g, "
                        "%g] mm",
                        fn, period_mm, length_mm / 1000, length_mm);
        if (elongation_out == nullptr ? elongation_count != 0 : elongation_count != l.zones)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'elongation_count' = %zu, expected %zu", fn, elongation_count,
                        elongation_out ? l.zones : std::size_t(0));
        if (settings_out == nullptr ? settings_count != 0 : settings_count != l.actuators)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'settings_count' = %zu, expected %zu", fn, settings_count,
                        settings_out ? l.actuators : std::size_t(0));
        // e = incoming + G u + noise, relative to its shortest zone.
        std::uint64_t rng = mix(l.seed ^ mix(l.sheet + 1));
        std::vector<double> e(l.zones);
        for (std::size_t z = 0; z < l.zones; ++z) {
            double v = l.incoming[z];
            for (std::size_t j = 0; j < l.actuators; ++j)
                v += l.g[z * l.actuators + j] * l.next[j];
            e[z] = v + l.noise * normal(rng);
        }
        const double e_min = *std::min_element(e.begin(), e.end());
        for (double &v : e)
            v -= e_min;
        // The map: 8 columns per zone at the centres of eighths, 32 rows per
        // period over the sheet.
        const std::size_t cols = l.zones * k_columns_per_zone;
        const double dx = l.width / k_columns_per_zone;
        const double x_first = l.x0 - l.width / 2 + dx / 2;
        const double ds = period_mm / k_rows_per_period;
        const std::size_t rows = std::size_t(std::ceil(length_mm / ds)) + 1;
        std::vector<double> map(rows * cols);
        for (std::size_t r = 0; r < rows; ++r) {
            const double w = std::sin(2 * k_pi * double(r) * ds / period_mm);
            for (std::size_t c = 0; c < cols; ++c) {
                const double amplitude =
                    period_mm / k_pi * std::sqrt(1e-5 * e[c / k_columns_per_zone]);
                map[r * cols + c] = amplitude * w;
            }
        }
        if (flt_status st =
                flt_sim_set_height_map(sim, rows, cols, s0_mm, ds, x_first, dx, map.data()))
            return fail(st, "%s: %s", fn, flt_last_error_message());
        if (elongation_out)
            std::copy(e.begin(), e.end(), elongation_out);
        if (settings_out)
            std::copy(l.next.begin(), l.next.end(), settings_out);
        l.next = l.pending;
        ++l.sheet;
        return FLT_OK;
    });
}

}  // extern "C"
