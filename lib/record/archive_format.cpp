// SPDX-License-Identifier: Apache-2.0
#include "record/archive_format.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "flatline/gauge.h"
#include "record/codec.hpp"

namespace flt::record {
namespace {

constexpr double k_nan = std::numeric_limits<double>::quiet_NaN();
constexpr double k_max_map_height_mm = 1.0e5;

// The tables, written once for both databases: {R} is the 8-byte float
// type, {B} the byte string type.
const char *const k_schema[] = {
    "CREATE TABLE IF NOT EXISTS archive_meta (key TEXT PRIMARY KEY, value TEXT NOT NULL)",
    "CREATE TABLE IF NOT EXISTS coils ("
    " coil_uid TEXT PRIMARY KEY, line TEXT NOT NULL, coil_id TEXT NOT NULL,"
    " order_no TEXT NOT NULL, heat TEXT NOT NULL, grade TEXT NOT NULL, customer TEXT NOT NULL,"
    " nominal_thickness_mm {R} NOT NULL, nominal_width_mm {R} NOT NULL,"
    " gauge_coil BIGINT NOT NULL, first_utc_ns BIGINT NOT NULL, last_utc_ns BIGINT NOT NULL,"
    " sheets BIGINT NOT NULL, finished BIGINT NOT NULL)",
    "CREATE INDEX IF NOT EXISTS coils_by_id ON coils (coil_id, first_utc_ns)",
    "CREATE INDEX IF NOT EXISTS coils_by_time ON coils (first_utc_ns)",
    "CREATE TABLE IF NOT EXISTS coil_extras ("
    " coil_uid TEXT NOT NULL, position BIGINT NOT NULL, key TEXT NOT NULL, value TEXT NOT NULL,"
    " PRIMARY KEY (coil_uid, position))",
    "CREATE TABLE IF NOT EXISTS sheets ("
    " sheet_uid TEXT PRIMARY KEY, coil_uid TEXT NOT NULL, line TEXT NOT NULL,"
    " coil_id TEXT NOT NULL, grade TEXT NOT NULL, utc_ns BIGINT NOT NULL,"
    " gauge_coil BIGINT NOT NULL, sheet_id BIGINT NOT NULL, sheet_index BIGINT NOT NULL,"
    " s_start_mm {R}, s_end_mm {R}, rows BIGINT NOT NULL, fibers BIGINT NOT NULL,"
    " zones BIGINT NOT NULL, verdict TEXT NOT NULL, rules BIGINT NOT NULL,"
    " rules_failed BIGINT NOT NULL, shape BIGINT, confidence {R}, max_i_units {R},"
    " wave_height_mm {R}, wave_steepness {R}, bow_mm {R}, crossbow_mm {R},"
    " strip_width_mm {R}, flags BIGINT NOT NULL, thickness_mm {R}, width_mm {R},"
    " sheet_values {B} NOT NULL, sheet_arrays {B} NOT NULL, map_codec BIGINT NOT NULL,"
    " map_crc32 BIGINT, map {B}, bytes BIGINT NOT NULL)",
    "CREATE INDEX IF NOT EXISTS sheets_by_coil ON sheets (coil_uid, sheet_index)",
    "CREATE INDEX IF NOT EXISTS sheets_by_coil_id ON sheets (coil_id, utc_ns)",
    "CREATE INDEX IF NOT EXISTS sheets_by_grade ON sheets (grade, utc_ns)",
    "CREATE INDEX IF NOT EXISTS sheets_by_time ON sheets (utc_ns)",
    "CREATE INDEX IF NOT EXISTS sheets_by_verdict ON sheets (verdict, utc_ns)",
    "CREATE TABLE IF NOT EXISTS verdicts ("
    " sheet_uid TEXT NOT NULL, rule BIGINT NOT NULL, name TEXT NOT NULL,"
    " measure BIGINT NOT NULL, length_mm {R} NOT NULL, state BIGINT NOT NULL, worst {R},"
    " limit_value {R}, margin {R}, x_mm {R}, s_mm {R}, band BIGINT NOT NULL,"
    " PRIMARY KEY (sheet_uid, rule))",
    "CREATE TABLE IF NOT EXISTS coil_stats ("
    " coil_uid TEXT NOT NULL, rule BIGINT NOT NULL, name TEXT NOT NULL, stats {B} NOT NULL,"
    " PRIMARY KEY (coil_uid, rule))",
    "CREATE TABLE IF NOT EXISTS notes ("
    " sheet_uid TEXT NOT NULL, position BIGINT NOT NULL, kind TEXT NOT NULL,"
    " text TEXT NOT NULL, s_mm {R}, utc_ns BIGINT NOT NULL, PRIMARY KEY (sheet_uid, position))",
};

std::string with_types(const database &db, const char *sql) {
    std::string out = sql;
    for (std::size_t at; (at = out.find("{R}")) != std::string::npos;)
        out.replace(at, 3, db.real_type());
    for (std::size_t at; (at = out.find("{B}")) != std::string::npos;)
        out.replace(at, 3, db.blob_type());
    return out;
}

void put_f64s(std::vector<std::uint8_t> &out, const double *v, std::size_t n) {
    const auto *b = reinterpret_cast<const std::uint8_t *>(v);
    out.insert(out.end(), b, b + n * sizeof(double));
}

db_param real(double v) {
    return db_param::of(v);
}
db_param integer(std::int64_t v) {
    return db_param::of(v);
}
db_param text(const std::string &v) {
    return db_param::of(v);
}

}  // namespace

std::size_t sheet_record::bytes() const {
    std::size_t n = map.size() + values.size() * 8 + 512;
    for (const auto &a : arrays)
        n += a.second.size() * 8 + 8;
    for (const auto &r : rule_results)
        n += r.name.size() + 96;
    for (const auto &s : coil_stats)
        n += s.values.size() * 8 + s.name.size();
    return n;
}

double sheet_record::value(int key) const {
    return key >= 0 && std::size_t(key) < values.size() ? values[std::size_t(key)] : k_nan;
}

void encode_map(std::size_t rows, std::size_t fibers, const double *s_mm, const double *z_mm,
                const std::uint8_t *flags, double quantum_mm, std::vector<std::uint8_t> &out) {
    out.clear();
    put_u32(out, k_map_magic);
    put_u32(out, std::uint32_t(rows));
    put_u32(out, std::uint32_t(fibers));
    put_f64(out, quantum_mm);
    const std::size_t n = rows * fibers;
    std::vector<std::uint8_t> side;
    side.reserve(rows * 8 + n);
    put_f64s(side, s_mm, rows);
    const std::size_t flags_at = side.size();
    side.insert(side.end(), flags, flags + n);
    for (std::size_t i = 0; i < n; ++i) {
        side[flags_at + i] &= std::uint8_t(~k_map_nan);
        if (!(std::fabs(z_mm[i]) <= k_max_map_height_mm))
            side[flags_at + i] |= k_map_nan;
    }
    put_u32(out, std::uint32_t(side.size()));
    const std::size_t at = out.size();
    put_u32(out, 0);
    deflate_append(side.data(), side.size(), 6, out);
    const std::uint32_t deflated = std::uint32_t(out.size() - at - 4);
    std::memcpy(&out[at], &deflated, 4);
    // Fiber after fiber, the quantized heights' second differences along
    // the strip (a NaN repeats the height before it).
    std::vector<std::uint64_t> values(n);
    std::uint64_t sum = 0;
    std::size_t i = 0;
    for (std::size_t k = 0; k < fibers; ++k) {
        std::int64_t q_prev = 0, d_prev = 0;
        for (std::size_t r = 0; r < rows; ++r) {
            const double z = z_mm[r * fibers + k];
            const std::int64_t q =
                std::fabs(z) <= k_max_map_height_mm ? std::llround(z / quantum_mm) : q_prev;
            const std::int64_t d = q - q_prev;
            const std::uint64_t u = zigzag(d - d_prev);
            values[i++] = u;
            sum += std::min<std::uint64_t>(u, std::uint64_t(1) << 40);
            q_prev = q;
            d_prev = d;
        }
    }
    std::uint64_t unary_bits = 0;
    const unsigned k = best_rice_k(values.data(), n, sum, &unary_bits);
    std::vector<std::uint8_t> unary, binary;
    std::vector<std::uint64_t> escapes;
    rice_encode(values.data(), n, k, unary_bits, unary, binary, escapes);
    out.push_back(std::uint8_t(k));
    put_u32(out, std::uint32_t(unary.size()));
    put_u32(out, std::uint32_t(binary.size()));
    put_u32(out, std::uint32_t(escapes.size()));
    out.insert(out.end(), unary.begin(), unary.end());
    out.insert(out.end(), binary.begin(), binary.end());
    for (std::uint64_t e : escapes)
        put_u64(out, e);
}

void decode_map(const std::uint8_t *data, std::size_t size, std::size_t max_samples,
                std::size_t *rows_out, std::size_t *fibers_out, std::vector<double> &s_mm,
                std::vector<double> &z_mm, std::vector<std::uint8_t> &flags) {
    const char *what = "archived height map";
    byte_reader r(data, size, what);
    if (r.u32() != k_map_magic)
        r.malformed("no map magic");
    const std::size_t rows = r.u32(), fibers = r.u32();
    if (rows == 0 || fibers == 0 || fibers > FLT_MAX_FIBERS || rows > max_samples / fibers)
        r.malformed("size out of range");
    const double quantum = r.f64();
    if (!(quantum >= 1e-6 && quantum <= 1.0))
        r.malformed("quantum out of range");
    const std::size_t n = rows * fibers;
    const std::size_t side_bytes = r.u32(), deflated = r.u32();
    if (side_bytes != rows * 8 + n)
        r.malformed("side data of the wrong size");
    std::vector<std::uint8_t> side;
    inflate_exact(r.bytes(deflated), deflated, side_bytes, side, what);
    s_mm.resize(rows);
    std::memcpy(s_mm.data(), side.data(), rows * 8);
    flags.assign(side.begin() + long(rows * 8), side.end());
    const unsigned k = r.u8();
    const std::size_t ub = r.u32(), bb = r.u32(), ne = r.u32();
    const std::uint8_t *unary = r.bytes(ub);
    const std::uint8_t *binary = r.bytes(bb);
    if (ne > n)
        r.malformed("more escapes than values");
    byte_reader er(r.bytes(ne * 8), ne * 8, what);
    std::vector<std::uint64_t> escapes(ne), values(n);
    for (std::size_t i = 0; i < ne; ++i)
        escapes[i] = er.u64();
    if (r.left() != 0)
        r.malformed("bytes after the heights");
    rice_decode(unary, ub, binary, bb, escapes.data(), ne, k, n, values.data(), what);
    z_mm.assign(n, k_nan);
    std::size_t i = 0;
    for (std::size_t f = 0; f < fibers; ++f) {
        std::uint64_t d = 0, q = 0;  // unsigned: a damaged map wraps, never overflows
        for (std::size_t row = 0; row < rows; ++row) {
            d += std::uint64_t(unzigzag(values[i++]));
            q += d;
            const std::size_t at = row * fibers + f;
            if (!(flags[at] & k_map_nan))
                z_mm[at] = double(std::int64_t(q)) * quantum;
        }
    }
    for (std::uint8_t &fl : flags)
        fl &= std::uint8_t(~k_map_nan);
    *rows_out = rows;
    *fibers_out = fibers;
}

void ensure_archive_schema(database &db) {
    const db_rows have = db.query(
        db.backend() == 0
            ? "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = 'archive_meta'"
            : "SELECT count(*) FROM information_schema.tables WHERE table_name = 'archive_meta' "
              "AND table_schema = current_schema()");
    const bool exists = !have.empty() && !have[0].empty() && have[0][0] != "0";
    if (exists) {
        const db_rows v = db.query("SELECT key, value FROM archive_meta");
        std::string format, version;
        for (const auto &row : v)
            if (row.size() == 2) {
                if (row[0] == "format")
                    format = row[1];
                else if (row[0] == "version")
                    version = row[1];
            }
        if (format != "flatline-archive")
            throw error(FLT_ERR_FORMAT,
                        "the database holds an 'archive_meta' table that is no flatline archive");
        if (version != std::to_string(k_archive_version)) {
            char message[200];
            format_c(message, sizeof message,
                     "the archive has schema version '%s'; this library reads version %d",
                     version.c_str(), k_archive_version);
            throw error(FLT_ERR_FORMAT, message);
        }
        return;
    }
    db.execute("BEGIN");
    try {
        for (const char *sql : k_schema)
            db.execute(with_types(db, sql));
        db.execute("INSERT INTO archive_meta (key, value) VALUES ('format', 'flatline-archive') "
                   "ON CONFLICT (key) DO NOTHING");
        db.execute("INSERT INTO archive_meta (key, value) VALUES ('version', ?1) ON CONFLICT "
                   "(key) DO NOTHING",
                   {text(std::to_string(k_archive_version))});
        db.execute("COMMIT");
    } catch (...) {
        try {
            db.execute("ROLLBACK");
        } catch (...) {
        }
        throw;
    }
}

void write_sheet(database &db, const std::string &line, const sheet_record &r) {
    const flt_coil_info &c = r.coil;
    // The coil: made by its first sheet, widened by the later ones.
    db.execute(
        "INSERT INTO coils (coil_uid, line, coil_id, order_no, heat, grade, customer, "
        "nominal_thickness_mm, nominal_width_mm, gauge_coil, first_utc_ns, last_utc_ns, sheets, "
        "finished) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?11, 0, 0) ON CONFLICT "
        "(coil_uid) DO UPDATE SET last_utc_ns = CASE WHEN excluded.last_utc_ns > "
        "coils.last_utc_ns THEN excluded.last_utc_ns ELSE coils.last_utc_ns END",
        {text(r.coil_uid), text(line), text(c.text[0]), text(c.text[1]), text(c.text[2]),
         text(c.text[3]), text(c.text[4]), real(c.thickness_mm), real(c.width_mm),
         integer(r.gauge_coil), integer(r.utc_ns)});
    const db_rows had =
        db.query("SELECT count(*) FROM sheets WHERE sheet_uid = ?1", {text(r.sheet_uid)});
    if (!had.empty() && !had[0].empty() && had[0][0] != "0")
        return;  // stored by an attempt whose answer was lost
    for (std::size_t i = 0; i < c.extras.size(); ++i)
        db.execute("INSERT INTO coil_extras (coil_uid, position, key, value) VALUES (?1, ?2, ?3, "
                   "?4) ON CONFLICT (coil_uid, position) DO NOTHING",
                   {text(r.coil_uid), integer(std::int64_t(i)), text(c.extras[i].first),
                    text(c.extras[i].second)});
    std::vector<std::uint8_t> values, arrays;
    put_f64s(values, r.values.data(), r.values.size());
    put_u32(arrays, std::uint32_t(r.arrays.size()));
    for (const auto &a : r.arrays) {
        put_u32(arrays, std::uint32_t(a.first));
        put_u32(arrays, std::uint32_t(a.second.size()));
        put_f64s(arrays, a.second.data(), a.second.size());
    }
    const double shape = r.value(FLT_SHEET_SHAPE);
    std::vector<db_param> p = {
        text(r.sheet_uid),
        text(r.coil_uid),
        text(line),
        text(c.text[0]),
        text(c.text[3]),
        integer(r.utc_ns),
        integer(r.gauge_coil),
        integer(r.sheet_id),
        integer(r.sheet_index),
        real(r.value(FLT_SHEET_S_START)),
        real(r.value(FLT_SHEET_S_END)),
        integer(std::int64_t(r.value(FLT_SHEET_ROWS))),
        integer(std::int64_t(r.value(FLT_SHEET_FIBERS))),
        integer(std::int64_t(r.value(FLT_SHEET_ZONES))),
        text(r.verdict),
        integer(r.rules),
        integer(r.rules_failed),
        std::isfinite(shape) ? integer(std::int64_t(shape)) : db_param(),
        real(r.value(FLT_SHEET_CONFIDENCE)),
        real(r.value(FLT_SHEET_MAX_I_UNITS)),
        real(r.value(FLT_SHEET_WAVE_HEIGHT)),
        real(r.value(FLT_SHEET_WAVE_STEEPNESS)),
        real(r.value(FLT_SHEET_BOW)),
        real(r.value(FLT_SHEET_CROSSBOW)),
        real(r.value(FLT_SHEET_STRIP_WIDTH)),
        integer(std::int64_t(r.value(FLT_SHEET_FLAGS))),
        real(r.thickness_mm),
        real(r.width_mm),
        db_param::of_blob(values.data(), values.size()),
        db_param::of_blob(arrays.data(), arrays.size()),
        integer(r.map.empty() ? 0 : k_map_codec),
        r.map.empty() ? db_param() : integer(std::int64_t(r.map_crc)),
        r.map.empty() ? db_param() : db_param::of_blob(r.map.data(), r.map.size()),
        integer(std::int64_t(r.map.size() + values.size() + arrays.size())),
    };
    db.execute("INSERT INTO sheets (sheet_uid, coil_uid, line, coil_id, grade, utc_ns, "
               "gauge_coil, sheet_id, sheet_index, s_start_mm, s_end_mm, rows, fibers, zones, "
               "verdict, rules, rules_failed, shape, confidence, max_i_units, wave_height_mm, "
               "wave_steepness, bow_mm, crossbow_mm, strip_width_mm, flags, thickness_mm, "
               "width_mm, sheet_values, sheet_arrays, map_codec, map_crc32, map, bytes) VALUES "
               "(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16, ?17, "
               "?18, ?19, ?20, ?21, ?22, ?23, ?24, ?25, ?26, ?27, ?28, ?29, ?30, ?31, ?32, ?33, "
               "?34)",
               p);
    for (std::size_t i = 0; i < r.rule_results.size(); ++i) {
        const rule_record &v = r.rule_results[i];
        db.execute("INSERT INTO verdicts (sheet_uid, rule, name, measure, length_mm, state, "
                   "worst, limit_value, margin, x_mm, s_mm, band) VALUES (?1, ?2, ?3, ?4, ?5, "
                   "?6, ?7, ?8, ?9, ?10, ?11, ?12)",
                   {text(r.sheet_uid), integer(std::int64_t(i)), text(v.name), integer(v.measure),
                    real(v.length_mm), integer(v.state), real(v.worst), real(v.limit),
                    real(v.margin), real(v.x_mm), real(v.s_mm), integer(v.band)});
    }
    for (std::size_t i = 0; i < r.notes.size(); ++i) {
        const note_record &n = r.notes[i];
        db.execute("INSERT INTO notes (sheet_uid, position, kind, text, s_mm, utc_ns) VALUES "
                   "(?1, ?2, ?3, ?4, ?5, ?6)",
                   {text(r.sheet_uid), integer(std::int64_t(i)), text(n.kind), text(n.text),
                    real(n.s_mm), integer(n.utc_ns)});
    }
    db.execute("UPDATE coils SET sheets = sheets + 1 WHERE coil_uid = ?1", {text(r.coil_uid)});
    if (r.ends_coil) {
        db.execute("UPDATE coils SET finished = 1 WHERE coil_uid = ?1", {text(r.coil_uid)});
        for (std::size_t i = 0; i < r.coil_stats.size(); ++i) {
            std::vector<std::uint8_t> blob;
            put_f64s(blob, r.coil_stats[i].values.data(), r.coil_stats[i].values.size());
            db.execute("INSERT INTO coil_stats (coil_uid, rule, name, stats) VALUES (?1, ?2, ?3, "
                       "?4) ON CONFLICT (coil_uid, rule) DO NOTHING",
                       {text(r.coil_uid), integer(std::int64_t(i)), text(r.coil_stats[i].name),
                        db_param::of_blob(blob.data(), blob.size())});
        }
    }
}

std::uint64_t prune_archive(database &db, double retention_days, double retention_mb,
                            std::int64_t now_ns) {
    std::vector<std::string> doomed;
    if (retention_days > 0) {
        const std::int64_t cutoff = now_ns - std::int64_t(retention_days * 86400.0 * 1e9);
        for (const auto &row :
             db.query("SELECT sheet_uid FROM sheets WHERE utc_ns < ?1", {integer(cutoff)}))
            doomed.push_back(row.at(0));
    }
    if (retention_mb > 0) {
        const double limit = retention_mb * 1048576.0;
        const db_rows total = db.query("SELECT sum(bytes) FROM sheets");
        double have = 0;
        if (!total.empty() && !total[0].empty() && !total[0][0].empty())
            parse_double(total[0][0], have);
        if (have > limit) {
            // The oldest first, until the rest fit.
            for (const auto &row :
                 db.query("SELECT sheet_uid, bytes FROM sheets ORDER BY utc_ns")) {
                if (have <= limit)
                    break;
                double b = 0;
                parse_double(row.at(1), b);
                have -= b;
                doomed.push_back(row.at(0));
            }
        }
    }
    std::sort(doomed.begin(), doomed.end());
    doomed.erase(std::unique(doomed.begin(), doomed.end()), doomed.end());
    if (doomed.empty())
        return 0;
    db.execute("BEGIN");
    try {
        for (const std::string &uid : doomed) {
            for (const char *sql : {"DELETE FROM verdicts WHERE sheet_uid = ?1",
                                    "DELETE FROM notes WHERE sheet_uid = ?1",
                                    "DELETE FROM sheets WHERE sheet_uid = ?1"})
                db.execute(sql, {text(uid)});
        }
        // Coils left without a sheet go with their extras and statistics.
        const char *orphans = "SELECT coil_uid FROM coils WHERE coil_uid NOT IN (SELECT coil_uid "
                              "FROM sheets)";
        for (const auto &row : db.query(orphans))
            for (const char *sql : {"DELETE FROM coil_extras WHERE coil_uid = ?1",
                                    "DELETE FROM coil_stats WHERE coil_uid = ?1",
                                    "DELETE FROM coils WHERE coil_uid = ?1"})
                db.execute(sql, {text(row.at(0))});
        db.execute("COMMIT");
    } catch (...) {
        try {
            db.execute("ROLLBACK");
        } catch (...) {
        }
        throw;
    }
    return doomed.size();
}

}  // namespace flt::record
