// SPDX-License-Identifier: Apache-2.0
// The C API of the leveler advisor (flatline/advisor.h).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "advisor/bounded_lsq.hpp"
#include "advisor/identify.hpp"
#include "advisor/model.hpp"
#include "core/error.hpp"
#include "core/options.hpp"
#include "core/utf8_path.hpp"
#include "flatline/advisor.h"

using namespace flt;
using flt::advisor::actuator;
using flt::advisor::box_qp;
using flt::advisor::leveler_model;

namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
constexpr double k_max_ridge = 1e6;  // beyond it the fit is the ridge alone
constexpr double k_min_lambda = 1e-12;

enum class g_source { none, given, identified };

}  // namespace

struct flt_advisor {
    static constexpr unsigned k_magic = 0x464c5441u;  // "FLTA"
    unsigned magic = k_magic;
    leveler_model model;
    double damping = 0, gain = 0;  // the advisor_* options
    g_source source = g_source::none;
    bool refused = false;
    std::string refusal;
    double fit_r2 = k_nan, fit_rms = k_nan;
    std::size_t fit_steps = 0;
    // Derived from G and damping (refresh()): P G and H = (P G)^T P G + lambda I.
    std::vector<double> gc, h;
    // Scratch of advise(), allocated here so that advise allocates nothing.
    // With zones without data, P G and H over the measured zones (gcm, hm).
    std::vector<double> r, f, lo, hi, d, gcm, hm;
    std::vector<unsigned char> state, measured;
    box_qp qp;

    flt_advisor(std::size_t zones, std::size_t actuators)
        : gc(zones * actuators), h(actuators * actuators), r(zones), f(actuators), lo(actuators),
          hi(actuators), d(actuators), gcm(zones * actuators), hm(actuators * actuators),
          state(actuators), measured(zones), qp(actuators) {
        model.zones = zones;
        model.actuators.resize(actuators);
        model.g.assign(zones * actuators, 0.0);
        model.target.assign(zones, 0.0);
    }

    std::size_t zones() const { return model.zones; }
    std::size_t actuators() const { return model.actuators.size(); }

    // P G (each column without its mean over the zones) and H into gc_out
    // and h_out, over the zones whose mask is set (every zone with a NULL
    // mask; the others' rows of P G are 0: they take no part).
    void derive(const unsigned char *mask, double *gc_out, double *h_out) const {
        const std::size_t nz = zones(), na = actuators();
        std::size_t used = 0;
        for (std::size_t z = 0; z < nz; ++z)
            used += mask == nullptr || mask[z] ? 1 : 0;
        for (std::size_t j = 0; j < na; ++j) {
            double mean = 0;
            for (std::size_t z = 0; z < nz; ++z)
                if (mask == nullptr || mask[z])
                    mean += model.g[z * na + j];
            mean /= double(used);
            for (std::size_t z = 0; z < nz; ++z)
                gc_out[z * na + j] = mask == nullptr || mask[z] ? model.g[z * na + j] - mean : 0.0;
        }
        double trace = 0;
        for (std::size_t i = 0; i < na; ++i)
            for (std::size_t j = 0; j < na; ++j) {
                double s = 0;
                for (std::size_t z = 0; z < nz; ++z)
                    s += gc_out[z * na + i] * gc_out[z * na + j];
                h_out[i * na + j] = s;
                if (i == j)
                    trace += s;
            }
        // lambda relative to the mean squared effect of a unit step; with G
        // all shape-less (trace 0) any lambda gives d = 0.
        const double mean_effect = trace > 0 ? trace / double(na) : 1.0;
        const double lambda = std::max(damping, k_min_lambda) * mean_effect;
        for (std::size_t i = 0; i < na; ++i)
            h_out[i * na + i] += lambda;
    }

    // The matrices of every zone, after G or the options changed.
    void refresh() { derive(nullptr, gc.data(), h.data()); }
};

namespace {

flt_status check_advisor(const char *fn, const flt_advisor *a) {
    if (a == nullptr)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'advisor' is NULL", fn);
    if (a->magic != flt_advisor::k_magic)
        return fail(FLT_ERR_INVALID_ARGUMENT,
                    "%s: argument 'advisor' is not a live flt_advisor handle", fn);
    return FLT_OK;
}

flt_status check_count(const char *fn, const char *name, std::size_t got, std::size_t want,
                       const char *what) {
    if (got != want)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument '%s' = %zu but the advisor has %zu %s",
                    fn, name, got, want, what);
    return FLT_OK;
}

// An array of finite values of at most FLT_ADVISOR_MAX_VALUE in magnitude.
flt_status check_values(const char *fn, const char *name, const double *v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
        if (!(std::fabs(v[i]) <= FLT_ADVISOR_MAX_VALUE))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument '%s'[%zu] = %g is not a finite value within +-1e9", fn, name,
                        i, v[i]);
    return FLT_OK;
}

flt_status check_sizes(const char *fn, std::size_t zones, std::size_t actuators) {
    if (zones < 1 || zones > FLT_ADVISOR_MAX_ZONES)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'zones' = %zu is outside 1..%d", fn,
                    zones, FLT_ADVISOR_MAX_ZONES);
    if (actuators < 1 || actuators > FLT_ADVISOR_MAX_ACTUATORS)
        return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'actuators' = %zu is outside 1..%d", fn,
                    actuators, FLT_ADVISOR_MAX_ACTUATORS);
    return FLT_OK;
}

// The advisor_* options (NULL: the defaults); a key of another component
// set in the bag is refused.
flt_status read_options(const char *fn, const flt_options *options, double &damping, double &gain) {
    if (flt_status st = check_option_component(fn, options, {FLT_OPT_ADVISOR_DAMPING}))
        return st;
    damping = option_value(options, FLT_OPT_ADVISOR_DAMPING);
    gain = option_value(options, FLT_OPT_ADVISOR_GAIN);
    return FLT_OK;
}

flt_status load(const char *fn, const char *text, std::size_t length, const flt_options *options,
                flt_advisor **out) {
    double damping = 0, gain = 0;
    if (flt_status st = read_options(fn, options, damping, gain))
        return st;
    leveler_model m;
    try {
        m = flt::advisor::read_leveler(text, length);
    } catch (const error &e) {
        return fail(e.status, "%s: %s", fn, e.what());
    }
    auto a = std::make_unique<flt_advisor>(m.zones, m.actuators.size());
    a->model = std::move(m);
    a->damping = damping;
    a->gain = gain;
    a->source = g_source::given;
    a->fit_r2 = 1;
    a->fit_rms = 0;
    a->refresh();
    *out = a.release();
    return FLT_OK;
}

// The text of a file at a UTF-8 path (lib/core's helper: the wide path on
// Windows).
flt_status read_file(const char *fn, const char *path, std::string &text) {
    std::error_code ec;
    if (std::filesystem::is_directory(flt::utf8_path(path), ec))
        return fail(FLT_ERR_IO, "%s: '%.300s' is a directory, not a leveler file", fn, path);
    // 1024 zones x 64 actuators of numbers is about 1.5 MB; refuse anything
    // absurd before reading it.
    constexpr std::size_t k_max_bytes = std::size_t(16) << 20;
    ec = flt::read_file(path, text, k_max_bytes);
    if (ec == std::errc::file_too_large)
        return fail(FLT_ERR_FORMAT, "%s: '%.300s' is larger than %zu bytes; not a leveler file", fn,
                    path, k_max_bytes);
    if (ec)
        return fail(FLT_ERR_IO, "%s: cannot read '%.300s': %s", fn, path, ec.message().c_str());
    return FLT_OK;
}

}  // namespace

extern "C" {

FLT_API flt_status FLT_CALL flt_advisor_create(size_t zones, size_t actuators,
                                               const flt_options *options, flt_advisor **out) {
    const char *fn = "flt_advisor_create";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        if (flt_status st = check_sizes(fn, zones, actuators))
            return st;
        double damping = 0, gain = 0;
        if (flt_status st = read_options(fn, options, damping, gain))
            return st;
        auto a = std::make_unique<flt_advisor>(zones, actuators);
        a->damping = damping;
        a->gain = gain;
        for (actuator &x : a->model.actuators)
            x.min = x.max = x.step = k_nan;
        a->refresh();
        *out = a.release();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_load(const char *path, const flt_options *options,
                                             flt_advisor **out) {
    const char *fn = "flt_advisor_load";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, path);
        std::string text;
        if (flt_status st = read_file(fn, path, text))
            return st;
        return load(fn, text.data(), text.size(), options, out);
    });
}

FLT_API flt_status FLT_CALL flt_advisor_load_text(const char *text, size_t length,
                                                  const flt_options *options, flt_advisor **out) {
    const char *fn = "flt_advisor_load_text";
    return guard(fn, [&] {
        FLT_CHECK_NOT_NULL(fn, out);
        *out = nullptr;
        FLT_CHECK_NOT_NULL(fn, text);
        if (length > (std::size_t(16) << 20))
            return fail(FLT_ERR_FORMAT,
                        "%s: argument 'length' = %zu is larger than a leveler file can be", fn,
                        length);
        return load(fn, text, length, options, out);
    });
}

FLT_API void FLT_CALL flt_advisor_destroy(flt_advisor *advisor) {
    guard_void([&] {
        if (advisor && advisor->magic == flt_advisor::k_magic) {
            advisor->magic = 0;
            delete advisor;
        }
    });
}

FLT_API flt_status FLT_CALL flt_advisor_size(const flt_advisor *advisor, size_t *zones_out,
                                             size_t *actuators_out) {
    const char *fn = "flt_advisor_size";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        if (zones_out)
            *zones_out = advisor->zones();
        if (actuators_out)
            *actuators_out = advisor->actuators();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_set_actuator(flt_advisor *advisor, size_t index,
                                                     const char *name, const char *unit, double min,
                                                     double max, double step) {
    const char *fn = "flt_advisor_set_actuator";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        if (index >= advisor->actuators())
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'index' = %zu but the advisor has %zu actuators", fn, index,
                        advisor->actuators());
        FLT_CHECK_NOT_NULL(fn, name);
        FLT_CHECK_NOT_NULL(fn, unit);
        const std::size_t name_len = std::strlen(name), unit_len = std::strlen(unit);
        if (name_len < 1 || name_len > flt::advisor::k_max_name)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'name' has %zu bytes; a name has 1 to 63", fn, name_len);
        if (unit_len > flt::advisor::k_max_unit)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'unit' has %zu bytes; a unit has at most 15", fn, unit_len);
        if (!(std::fabs(min) <= FLT_ADVISOR_MAX_VALUE))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'min' = %g is not a finite value within +-1e9", fn, min);
        if (!(std::fabs(max) <= FLT_ADVISOR_MAX_VALUE) || !(max > min))
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'max' = %g must be finite, within +-1e9 and greater than "
                        "min = %g",
                        fn, max, min);
        if (!(step > 0) || !(step <= FLT_ADVISOR_MAX_VALUE))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'step' = %g must be in (0, 1e9]",
                        fn, step);
        actuator &a = advisor->model.actuators[index];
        a.name = name;
        a.unit = unit;
        a.min = min;
        a.max = max;
        a.step = step;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_actuator(const flt_advisor *advisor, size_t index,
                                                 const char **name_out, const char **unit_out,
                                                 double *min_out, double *max_out,
                                                 double *step_out) {
    const char *fn = "flt_advisor_actuator";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        if (index >= advisor->actuators())
            return fail(FLT_ERR_NOT_FOUND,
                        "%s: argument 'index' = %zu but the advisor has %zu actuators", fn, index,
                        advisor->actuators());
        const actuator &a = advisor->model.actuators[index];
        if (name_out)
            *name_out = a.name.c_str();
        if (unit_out)
            *unit_out = a.unit.c_str();
        if (min_out)
            *min_out = a.min;
        if (max_out)
            *max_out = a.max;
        if (step_out)
            *step_out = a.step;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_set_influence(flt_advisor *advisor, const double *g,
                                                      size_t g_count) {
    const char *fn = "flt_advisor_set_influence";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        FLT_CHECK_NOT_NULL(fn, g);
        if (flt_status st =
                check_count(fn, "g_count", g_count, advisor->zones() * advisor->actuators(),
                            "zones x actuators entries"))
            return st;
        if (flt_status st = check_values(fn, "g", g, g_count))
            return st;
        advisor->model.g.assign(g, g + g_count);
        advisor->source = g_source::given;
        advisor->refused = false;
        advisor->fit_r2 = 1;
        advisor->fit_rms = 0;
        advisor->fit_steps = 0;
        advisor->refresh();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_influence(const flt_advisor *advisor, double *g_out,
                                                  size_t g_count) {
    const char *fn = "flt_advisor_influence";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        FLT_CHECK_NOT_NULL(fn, g_out);
        if (flt_status st =
                check_count(fn, "g_count", g_count, advisor->zones() * advisor->actuators(),
                            "zones x actuators entries"))
            return st;
        std::copy(advisor->model.g.begin(), advisor->model.g.end(), g_out);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_set_target(flt_advisor *advisor, const double *target,
                                                   size_t target_count) {
    const char *fn = "flt_advisor_set_target";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        if (target == nullptr) {
            if (target_count != 0)
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'target' is NULL (flat) but 'target_count' = %zu, not 0",
                            fn, target_count);
            std::fill(advisor->model.target.begin(), advisor->model.target.end(), 0.0);
            return FLT_OK;
        }
        if (flt_status st =
                check_count(fn, "target_count", target_count, advisor->zones(), "zones"))
            return st;
        if (flt_status st = check_values(fn, "target", target, target_count))
            return st;
        advisor->model.target.assign(target, target + target_count);
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_identify(flt_advisor *advisor, size_t steps,
                                                 const double *delta_u, size_t delta_u_count,
                                                 const double *delta_p, size_t delta_p_count,
                                                 double ridge) {
    const char *fn = "flt_advisor_identify";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        FLT_CHECK_NOT_NULL(fn, delta_u);
        FLT_CHECK_NOT_NULL(fn, delta_p);
        const std::size_t na = advisor->actuators(), nz = advisor->zones();
        // steps * actuators must not overflow: a log of more steps than
        // 2^40 is no log.
        if (steps < 1 || steps > (std::size_t(1) << 40))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'steps' = %zu is outside 1..2^40",
                        fn, steps);
        if (delta_u_count != steps * na)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'delta_u_count' = %zu, expected steps x actuators = %zu", fn,
                        delta_u_count, steps * na);
        if (delta_p_count != steps * nz)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'delta_p_count' = %zu, expected steps x zones = %zu", fn,
                        delta_p_count, steps * nz);
        if (!(ridge >= 0) || !(ridge <= k_max_ridge))
            return fail(FLT_ERR_INVALID_ARGUMENT, "%s: argument 'ridge' = %g is outside [0, 1e6]",
                        fn, ridge);
        if (flt_status st = check_values(fn, "delta_u", delta_u, delta_u_count))
            return st;
        if (flt_status st = check_values(fn, "delta_p", delta_p, delta_p_count))
            return st;
        const flt::advisor::identification id = flt::advisor::identify(
            nz, na, steps, delta_u, delta_p, ridge, FLT_ADVISOR_MIN_R_SQUARED);
        advisor->fit_steps = steps;
        advisor->fit_r2 = id.fitted ? id.r_squared : k_nan;
        advisor->fit_rms = id.fitted ? id.rms : k_nan;
        if (!id.accepted) {
            advisor->refused = true;
            advisor->refusal = id.why;
            return fail(FLT_ERR_NUMERIC, "%s: refused: %s", fn, id.why.c_str());
        }
        advisor->model.g = id.g;
        advisor->source = g_source::identified;
        advisor->refused = false;
        advisor->refresh();
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_fit(const flt_advisor *advisor, double *r_squared_out,
                                            double *rms_out, size_t *steps_out) {
    const char *fn = "flt_advisor_fit";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        if (r_squared_out)
            *r_squared_out = advisor->fit_r2;
        if (rms_out)
            *rms_out = advisor->fit_rms;
        if (steps_out)
            *steps_out = advisor->fit_steps;
        return FLT_OK;
    });
}

FLT_API flt_status FLT_CALL flt_advisor_advise(flt_advisor *advisor, const double *profile,
                                               size_t profile_count, const double *settings_sheet,
                                               size_t settings_sheet_count,
                                               const double *settings_now,
                                               size_t settings_now_count, double *delta_out,
                                               size_t delta_count, double *predicted_out,
                                               size_t predicted_count, double *confidence_out) {
    const char *fn = "flt_advisor_advise";
    return guard(fn, [&] {
        if (flt_status st = check_advisor(fn, advisor))
            return st;
        flt_advisor &a = *advisor;
        const std::size_t nz = a.zones(), na = a.actuators();
        FLT_CHECK_NOT_NULL(fn, profile);
        FLT_CHECK_NOT_NULL(fn, settings_sheet);
        FLT_CHECK_NOT_NULL(fn, settings_now);
        FLT_CHECK_NOT_NULL(fn, delta_out);
        if (flt_status st = check_count(fn, "profile_count", profile_count, nz, "zones"))
            return st;
        if (flt_status st =
                check_count(fn, "settings_sheet_count", settings_sheet_count, na, "actuators"))
            return st;
        if (flt_status st =
                check_count(fn, "settings_now_count", settings_now_count, na, "actuators"))
            return st;
        if (flt_status st = check_count(fn, "delta_count", delta_count, na, "actuators"))
            return st;
        if (predicted_out == nullptr ? predicted_count != 0 : predicted_count != nz)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'predicted_count' = %zu, expected %zu (%s)", fn,
                        predicted_count, predicted_out ? nz : std::size_t(0),
                        predicted_out ? "zones" : "predicted_out is NULL");
        // A zone without data (NaN, FLT_ZONE_NO_DATA) takes no part.
        std::size_t n_measured = 0;
        for (std::size_t z = 0; z < nz; ++z) {
            a.measured[z] = std::isnan(profile[z]) ? 0 : 1;
            n_measured += a.measured[z];
            if (a.measured[z] && !(std::fabs(profile[z]) <= FLT_ADVISOR_MAX_VALUE))
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'profile'[%zu] = %g is not a finite value within +-1e9 "
                            "(NaN: a zone without data)",
                            fn, z, profile[z]);
        }
        if (n_measured < 2)
            return fail(FLT_ERR_INVALID_ARGUMENT,
                        "%s: argument 'profile' has %zu measured zone(s) (the others NaN); a "
                        "shape needs at least 2",
                        fn, n_measured);
        if (flt_status st = check_values(fn, "settings_sheet", settings_sheet, na))
            return st;
        if (flt_status st = check_values(fn, "settings_now", settings_now, na))
            return st;
        for (std::size_t j = 0; j < na; ++j) {
            const actuator &x = a.model.actuators[j];
            if (!x.described())
                return fail(FLT_ERR_STATE,
                            "%s: actuator %zu is not described (flt_advisor_set_actuator)", fn, j);
            if (!(settings_now[j] >= x.min && settings_now[j] <= x.max))
                return fail(FLT_ERR_INVALID_ARGUMENT,
                            "%s: argument 'settings_now'[%zu] = %g is outside the range [%g, %g] "
                            "of '%s'",
                            fn, j, settings_now[j], x.min, x.max, x.name.c_str());
        }
        if (a.refused)
            return fail(FLT_ERR_STATE, "%s: no advice from a refused identification: %s", fn,
                        a.refusal.c_str());
        if (a.source == g_source::none)
            return fail(FLT_ERR_STATE,
                        "%s: no influence matrix G: set it (flt_advisor_set_influence) or "
                        "identify it (flt_advisor_identify)",
                        fn);
        // P G and H: precomputed, or over the measured zones.
        const double *gc = a.gc.data(), *h = a.h.data();
        if (n_measured < nz) {
            a.derive(a.measured.data(), a.gcm.data(), a.hm.data());
            gc = a.gcm.data();
            h = a.hm.data();
        }
        // r = P (p - t) + P G (u_now - u_sheet), over the measured zones.
        double mean = 0;
        for (std::size_t z = 0; z < nz; ++z)
            if (a.measured[z])
                mean += profile[z] - a.model.target[z];
        mean /= double(n_measured);
        for (std::size_t z = 0; z < nz; ++z) {
            double v = a.measured[z] ? profile[z] - a.model.target[z] - mean : 0.0;
            for (std::size_t j = 0; j < na; ++j)
                v += gc[z * na + j] * (settings_now[j] - settings_sheet[j]);
            a.r[z] = v;
        }
        // f = (P G)^T b with b = -gain r; the box of each actuator.
        for (std::size_t j = 0; j < na; ++j) {
            double s = 0;
            for (std::size_t z = 0; z < nz; ++z)
                s += gc[z * na + j] * a.r[z];
            a.f[j] = -a.gain * s;
            const actuator &x = a.model.actuators[j];
            a.lo[j] = std::max(x.min - settings_now[j], -x.step);
            a.hi[j] = std::min(x.max - settings_now[j], x.step);
            // lo <= 0 <= hi holds in exact arithmetic (u_now is in range);
            // keep it so after rounding.
            a.lo[j] = std::min(a.lo[j], 0.0);
            a.hi[j] = std::max(a.hi[j], 0.0);
        }
        if (!a.qp.solve(h, a.f.data(), a.lo.data(), a.hi.data(), a.d.data(), a.state.data()))
            return fail(FLT_ERR_NUMERIC,
                        "%s: the bounded least-squares solve did not converge (G with NaN-free "
                        "but extreme values?)",
                        fn);
        // Land exactly on the range: u_now + d within [min, max] and |d| <=
        // step after rounding too.
        std::size_t on_bound = 0;
        for (std::size_t j = 0; j < na; ++j) {
            const actuator &x = a.model.actuators[j];
            double d = std::min(std::max(a.d[j], a.lo[j]), a.hi[j]);
            while (settings_now[j] + d > x.max)
                d = std::nextafter(d, -HUGE_VAL);
            while (settings_now[j] + d < x.min)
                d = std::nextafter(d, HUGE_VAL);
            if (d > x.step)
                d = x.step;
            if (d < -x.step)
                d = -x.step;
            a.d[j] = d;
            if (a.state[j] != box_qp::free_var)
                ++on_bound;
        }
        for (std::size_t j = 0; j < na; ++j)
            delta_out[j] = a.d[j];
        if (predicted_out) {
            for (std::size_t z = 0; z < nz; ++z) {
                double v = profile[z];
                for (std::size_t j = 0; j < na; ++j)
                    v += gc[z * na + j] * (settings_now[j] + a.d[j] - settings_sheet[j]);
                predicted_out[z] = v;
            }
        }
        if (confidence_out) {
            const double q = std::min(1.0, std::max(0.0, a.fit_r2));
            *confidence_out = q * (1.0 - double(on_bound) / (2.0 * double(na)));
        }
        return FLT_OK;
    });
}

}  // extern "C"
