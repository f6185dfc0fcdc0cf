// SPDX-License-Identifier: Apache-2.0
// The rule file: JSON text, version 1 (flatline/verdict.h, "Rule files").
#include "verdict/rules.hpp"

#include <cstdint>

#include "core/json.hpp"

namespace flt {
namespace verdict {
namespace {

constexpr std::uint64_t k_version = 1;

struct measure_name {
    const char *name;
    flt_measure measure;
};

constexpr measure_name k_measures[] = {
    {"straightedge_along", FLT_MEASURE_STRAIGHTEDGE_ALONG},
    {"straightedge_across", FLT_MEASURE_STRAIGHTEDGE_ACROSS},
    {"zone_i_units", FLT_MEASURE_ZONE_I_UNITS},
    {"wave_steepness", FLT_MEASURE_WAVE_STEEPNESS},
    {"wave_height", FLT_MEASURE_WAVE_HEIGHT},
    {"bow", FLT_MEASURE_BOW},
    {"crossbow", FLT_MEASURE_CROSSBOW},
};

// [min, max) in mm: 0 <= min < max.
void read_range(const json::node &n, const std::string &path, double &min_value,
                double &max_value) {
    json::expect_kind(n, json::node::array, path);
    if (n.items.size() != 2)
        json::format_error("field '" + path + "' (line " + std::to_string(n.line) + ") has " +
                           std::to_string(n.items.size()) + " entries; a band is [min, max]");
    min_value = json::number(n.items[0], path + "[0]");
    max_value = json::number(n.items[1], path + "[1]");
    if (min_value < 0)
        json::format_error("field '" + path + "[0]' = " + n.items[0].text + " must be >= 0");
    if (!(max_value > min_value))
        json::format_error("field '" + path + "' = [" + n.items[0].text + ", " + n.items[1].text +
                           "]: max must be greater than min");
}

bool overlap(double a0, double a1, double b0, double b1) {
    return a0 < b1 && b0 < a1;
}

rule read_rule(const json::node &n, const std::string &path) {
    const auto f = json::fields(n, path, {"name", "measure", "bands"}, {"length_mm"});
    rule r;
    r.name = json::string(*f[0], path + ".name");
    const std::string &measure = json::string(*f[1], path + ".measure");
    bool known = false;
    for (const measure_name &m : k_measures)
        if (measure == m.name) {
            r.measure = m.measure;
            known = true;
        }
    if (!known) {
        std::string names;
        for (const measure_name &m : k_measures)
            names += names.empty() ? m.name : std::string(", ") + m.name;
        json::format_error("field '" + path + ".measure' = \"" + measure + "\" (line " +
                           std::to_string(f[1]->line) + ") is not one of " + names);
    }
    if (is_straightedge(r.measure)) {
        if (f[3] == nullptr)
            json::format_error("missing field '" + path +
                               ".length_mm' (the straightedge's length)");
        r.length = json::positive(*f[3], path + ".length_mm");
    } else {
        if (f[3] != nullptr)
            json::format_error("field '" + path + ".length_mm' (line " +
                               std::to_string(f[3]->line) + ") belongs to a straightedge; \"" +
                               measure + "\" has no length");
        r.length = 0;
    }
    const json::node &bands = *f[2];
    json::expect_kind(bands, json::node::array, path + ".bands");
    if (bands.items.empty())
        json::format_error("field '" + path + ".bands' (line " + std::to_string(bands.line) +
                           ") is empty; a rule needs at least one band");
    for (std::size_t b = 0; b < bands.items.size(); ++b) {
        const std::string bp = path + ".bands[" + std::to_string(b) + "]";
        const auto g = json::fields(bands.items[b], bp, {"thickness_mm", "width_mm", "limit"});
        band x{};
        read_range(*g[0], bp + ".thickness_mm", x.thickness_min, x.thickness_max);
        read_range(*g[1], bp + ".width_mm", x.width_min, x.width_max);
        x.limit = json::positive(*g[2], bp + ".limit");
        for (std::size_t a = 0; a < r.bands.size(); ++a) {
            const band &y = r.bands[a];
            if (overlap(x.thickness_min, x.thickness_max, y.thickness_min, y.thickness_max) &&
                overlap(x.width_min, x.width_max, y.width_min, y.width_max)) {
                std::string message = "field '" + bp;
                message += "' (line " + std::to_string(bands.items[b].line);
                message += ") overlaps '" + path;
                message += ".bands[" + std::to_string(a);
                message += "]': a sheet must fall in one band at most";
                json::format_error(message);
            }
        }
        r.bands.push_back(x);
    }
    return r;
}

}  // namespace

bool is_straightedge(flt_measure m) {
    return m == FLT_MEASURE_STRAIGHTEDGE_ALONG || m == FLT_MEASURE_STRAIGHTEDGE_ACROSS;
}

int rule::band_of(double thickness, double width) const {
    for (std::size_t b = 0; b < bands.size(); ++b) {
        const band &x = bands[b];
        if (thickness >= x.thickness_min && thickness < x.thickness_max && width >= x.width_min &&
            width < x.width_max)
            return int(b);
    }
    return -1;
}

rule_set read_rules(const char *text, std::size_t length) {
    const json::node root = json::parse(text, length, "the rule file");
    json::expect_kind(root, json::node::object, "(top level)");
    // The version decides what else must be there, so it is read first: a
    // newer file reports its version, not its new fields.
    const json::node *format = json::member(root, "format");
    if (format == nullptr)
        json::format_error("missing field 'format'");
    if (json::string(*format, "format") != "flatline-tolerances")
        json::format_error("field 'format' = \"" + format->text +
                           "\" is not \"flatline-tolerances\"");
    const json::node *version = json::member(root, "version");
    if (version == nullptr)
        json::format_error("missing field 'version'");
    const std::uint64_t v = json::integer(*version, "version", 0, 1e9);
    if (v != k_version)
        json::format_error("field 'version' = " + std::to_string(v) +
                           " is a version this library cannot read (it reads " +
                           std::to_string(k_version) + ")");
    const auto top = json::fields(root, "", {"format", "version", "name", "rules"});
    rule_set set;
    set.name = json::string(*top[2], "name");
    const json::node &rules = *top[3];
    json::expect_kind(rules, json::node::array, "rules");
    if (rules.items.empty())
        json::format_error("field 'rules' (line " + std::to_string(rules.line) + ") is empty");
    for (std::size_t i = 0; i < rules.items.size(); ++i)
        set.rules.push_back(read_rule(rules.items[i], "rules[" + std::to_string(i) + "]"));
    return set;
}

}  // namespace verdict
}  // namespace flt
