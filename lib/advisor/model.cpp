// SPDX-License-Identifier: Apache-2.0
// The leveler file: JSON text, version 1 (flatline/advisor.h, "Leveler
// files").
#include "advisor/model.hpp"

#include <cmath>
#include <cstdint>

#include "core/json.hpp"
#include "flatline/advisor.h"

namespace flt {
namespace advisor {
namespace {

constexpr std::uint64_t k_version = 1;

std::string at_line(const json::node &n) {
    return " (line " + std::to_string(n.line) + ")";
}

// A finite number of at most FLT_ADVISOR_MAX_VALUE in magnitude.
double bounded(const json::node &n, const std::string &path) {
    const double v = json::number(n, path);
    if (!(std::fabs(v) <= FLT_ADVISOR_MAX_VALUE))
        json::format_error("field '" + path + "' = " + n.text + at_line(n) +
                           " is beyond +-1e9: a unit mistake");
    return v;
}

// An array of exactly `count` numbers.
std::vector<double> numbers(const json::node &n, const std::string &path, std::size_t count,
                            const char *what) {
    json::expect_kind(n, json::node::array, path);
    if (n.items.size() != count)
        json::format_error("field '" + path + "'" + at_line(n) + " has " +
                           std::to_string(n.items.size()) + " entries, expected " +
                           std::to_string(count) + " (" + what + ")");
    std::vector<double> out(count);
    for (std::size_t i = 0; i < count; ++i)
        out[i] = bounded(n.items[i], path + "[" + std::to_string(i) + "]");
    return out;
}

// A whole number in [1, max_value], its line named in every error.
std::size_t count(const json::node &n, const std::string &path, double max_value) {
    const double v = json::number(n, path);
    if (v != std::floor(v) || v < 1 || v > max_value)
        json::format_error("field '" + path + "' = " + n.text + at_line(n) +
                           " must be a whole number in [1, " + json::text_of(max_value) + "]");
    return std::size_t(v);
}

actuator read_actuator(const json::node &n, const std::string &path) {
    const auto f = json::fields(n, path, {"name", "unit", "min", "max", "step"});
    actuator a;
    a.name = json::string(*f[0], path + ".name");
    if (a.name.empty() || a.name.size() > k_max_name)
        json::format_error("field '" + path + ".name'" + at_line(*f[0]) + " has " +
                           std::to_string(a.name.size()) + " bytes; a name has 1 to 63");
    a.unit = json::string(*f[1], path + ".unit");
    if (a.unit.size() > k_max_unit)
        json::format_error("field '" + path + ".unit'" + at_line(*f[1]) + " has " +
                           std::to_string(a.unit.size()) + " bytes; a unit has at most 15");
    a.min = bounded(*f[2], path + ".min");
    a.max = bounded(*f[3], path + ".max");
    a.step = bounded(*f[4], path + ".step");
    if (!(a.max > a.min))
        json::format_error("field '" + path + ".max' = " + f[3]->text + at_line(*f[3]) +
                           " must be greater than min = " + f[2]->text);
    if (!(a.step > 0))
        json::format_error("field '" + path + ".step' = " + f[4]->text + at_line(*f[4]) +
                           " must be > 0");
    return a;
}

}  // namespace

// The most JSON values a valid leveler file holds: the influence rows and
// their numbers, the target, the actuators' objects and fields, and the top
// level's few. A file with more is refused while it is read, so a 16 MiB
// file of tiny values costs a few hundred kilobytes of reading, not
// millions of nodes.
constexpr std::size_t k_max_values = FLT_ADVISOR_MAX_ZONES * (FLT_ADVISOR_MAX_ACTUATORS + 1) +
                                     (FLT_ADVISOR_MAX_ZONES + 1) + FLT_ADVISOR_MAX_ACTUATORS * 6 +
                                     16;

leveler_model read_leveler(const char *text, std::size_t length) {
    const json::node root = json::parse(text, length, "the leveler file", k_max_values);
    json::expect_kind(root, json::node::object, "(top level)");
    // The version decides what else must be there, so it is read first.
    const json::node *format = json::member(root, "format");
    if (format == nullptr)
        json::format_error("missing field 'format'");
    if (json::string(*format, "format") != "flatline-leveler")
        json::format_error("field 'format' = \"" + format->text + "\"" + at_line(*format) +
                           " is not \"flatline-leveler\"");
    const json::node *version = json::member(root, "version");
    if (version == nullptr)
        json::format_error("missing field 'version'");
    if (json::integer(*version, "version", 0, 1e9) != k_version)
        json::format_error("field 'version' = " + version->text + at_line(*version) +
                           ": this library reads version 1 of the leveler file");
    const auto f = json::fields(root, "", {"format", "version", "zones", "actuators", "influence"},
                                {"name", "target"});
    if (f[5] != nullptr)
        json::string(*f[5], "name");
    leveler_model m;
    m.zones = count(*f[2], "zones", FLT_ADVISOR_MAX_ZONES);
    const json::node &acts = *f[3];
    json::expect_kind(acts, json::node::array, "actuators");
    if (acts.items.empty() || acts.items.size() > FLT_ADVISOR_MAX_ACTUATORS)
        json::format_error("field 'actuators'" + at_line(acts) + " has " +
                           std::to_string(acts.items.size()) + " entries; a leveler has 1 to " +
                           std::to_string(FLT_ADVISOR_MAX_ACTUATORS));
    for (std::size_t j = 0; j < acts.items.size(); ++j) {
        const std::string path = "actuators[" + std::to_string(j) + "]";
        m.actuators.push_back(read_actuator(acts.items[j], path));
        for (std::size_t k = 0; k < j; ++k)
            if (m.actuators[k].name == m.actuators[j].name)
                json::format_error("field '" + path + ".name' = \"" + m.actuators[j].name + "\"" +
                                   at_line(acts.items[j]) + " repeats actuators[" +
                                   std::to_string(k) + "]'s name");
    }
    const std::size_t n = m.actuators.size();
    const json::node &g = *f[4];
    json::expect_kind(g, json::node::array, "influence");
    if (g.items.size() != m.zones)
        json::format_error("field 'influence'" + at_line(g) + " has " +
                           std::to_string(g.items.size()) + " rows, expected " +
                           std::to_string(m.zones) + " (one per zone)");
    m.g.reserve(m.zones * n);
    for (std::size_t z = 0; z < m.zones; ++z) {
        const std::vector<double> row =
            numbers(g.items[z], "influence[" + std::to_string(z) + "]", n, "one per actuator");
        m.g.insert(m.g.end(), row.begin(), row.end());
    }
    if (f[6] != nullptr)
        m.target = numbers(*f[6], "target", m.zones, "one per zone");
    else
        m.target.assign(m.zones, 0.0);
    return m;
}

}  // namespace advisor
}  // namespace flt
