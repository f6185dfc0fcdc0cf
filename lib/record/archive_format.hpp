// SPDX-License-Identifier: Apache-2.0
// Internal: the archive's tables (docs/record.md, "The archive") and what
// one archived sheet holds, before it is written. The layer is neutral of
// the gauge: lib/gauge fills a sheet_record from an flt_sheet.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/coil.hpp"
#include "record/database.hpp"

namespace flt::record {

constexpr int k_archive_version = 1;
constexpr std::uint32_t k_map_magic = 0x504D4C46u;  // "FLMP"
constexpr int k_map_codec = 1;
// The NaN bit of a map sample's flags byte (FLT_FLAG_* use bits 0..3).
constexpr std::uint8_t k_map_nan = 0x80;

struct rule_record {
    std::string name;
    int measure = 0, state = 0, band = -1;
    double length_mm = 0, worst = 0, limit = 0, margin = 0, x_mm = 0, s_mm = 0;
};

struct note_record {
    std::string kind, text;
    double s_mm = 0;
    std::int64_t utc_ns = 0;
};

// A coil's statistics for one rule (flt_coil_value keys), at its end.
struct coil_rule_stats {
    std::string name;
    std::vector<double> values;
};

struct sheet_record {
    std::string sheet_uid, coil_uid;
    std::int64_t utc_ns = 0;
    flt_coil_info coil;  // coil id "" when the coil had no identity
    std::int64_t gauge_coil = 0, sheet_id = 0, sheet_index = 0;
    std::vector<double> values;                               // by flt_sheet_value key
    std::vector<std::pair<int, std::vector<double>>> arrays;  // (flt_sheet_array key, values)
    std::string verdict = "none";  // "pass", "fail", "not_judged", "none" (no rules)
    std::int64_t rules = 0, rules_failed = 0;
    double thickness_mm = 0, width_mm = 0;  // what chose the bands (NaN: none)
    std::vector<rule_record> rule_results;
    std::vector<note_record> notes;
    std::vector<std::uint8_t> map;  // encoded (k_map_codec), or empty
    std::uint32_t map_crc = 0;
    bool ends_coil = false;
    std::vector<coil_rule_stats> coil_stats;  // with ends_coil

    // Its size in memory and in the database, bytes (roughly: the blobs).
    std::size_t bytes() const;
    // A value by key (NaN beyond the values given).
    double value(int key) const;
};

// The map codec (docs/record.md, "Height maps"): rows x fibers heights
// (mm, NaN allowed), their FLT_FLAG_* bits and the rows' s, at `quantum`.
void encode_map(std::size_t rows, std::size_t fibers, const double *s_mm, const double *z_mm,
                const std::uint8_t *flags, double quantum_mm, std::vector<std::uint8_t> &out);
// Decodes (FLT_ERR_FORMAT for anything malformed; at most max_samples).
void decode_map(const std::uint8_t *data, std::size_t size, std::size_t max_samples,
                std::size_t *rows, std::size_t *fibers, std::vector<double> &s_mm,
                std::vector<double> &z_mm, std::vector<std::uint8_t> &flags);

// Creates the tables when the database has none; checks the schema
// version of one that has. `line` names the archive's line in messages.
void ensure_archive_schema(database &db);
// Writes one sheet (and its coil's row) in the current transaction;
// idempotent (a sheet already there is left as it is).
void write_sheet(database &db, const std::string &line, const sheet_record &r);
// Applies the retention limits; returns the sheets removed.
std::uint64_t prune_archive(database &db, double retention_days, double retention_mb,
                            std::int64_t now_ns);

}  // namespace flt::record
