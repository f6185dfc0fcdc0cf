// SPDX-License-Identifier: Apache-2.0
#include "record/recording_reader.hpp"

#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "record/codec.hpp"

namespace flt::record {
namespace {

[[noreturn]] void malformed(const std::string &path, const std::string &why) {
    char message[700];
    format_c(message, sizeof message, "'%s' is no readable recording: %s", path.c_str(),
             why.c_str());
    throw error(FLT_ERR_FORMAT, message);
}

}  // namespace

recording_reader::recording_reader(const std::string &path) {
    // Read-write when allowed: opening recovers the WAL of a writer that was
    // killed. Read-only media still open (without that recovery).
    try {
        db_ = std::make_unique<sqlite_db>(path, sqlite_db::mode::read_write);
    } catch (const error &) {
        db_ = std::make_unique<sqlite_db>(path, sqlite_db::mode::read_only);
        clear_error();
    }
    std::int64_t app = 0, user_version = 0;
    try {
        app = db_->scalar_int("PRAGMA application_id");
        user_version = db_->scalar_int("PRAGMA user_version");
    } catch (const error &e) {
        malformed(path, e.what());
    }
    if (app != k_recording_application_id)
        malformed(path, "it is not a flatline recording (SQLite application_id)");
    if (user_version < 1 || user_version > k_recording_version)
        malformed(path, "format version " + std::to_string(user_version) +
                            " (this library reads 1 to " + std::to_string(k_recording_version) +
                            ")");
    version_ = int(user_version);
    std::string fibers, quantum, spacing, width, height;
    {
        sqlite_statement q(*db_, "SELECT key, value FROM meta");
        while (q.step()) {
            const std::string key = q.column_text(0);
            if (key == "fibers")
                fibers = q.column_text(1);
            else if (key == "quantum_mm")
                quantum = q.column_text(1);
            else if (key == "laser_spacing_mm")
                spacing = q.column_text(1);
            else if (key == "calibration")
                calibration_ = q.column_text(1);
            else if (key == "frame_width")
                width = q.column_text(1);
            else if (key == "frame_height")
                height = q.column_text(1);
        }
    }
    double v = 0.0;
    if (!parse_double(fibers, v) || !(v >= 1 && v <= FLT_MAX_FIBERS) || v != std::floor(v))
        malformed(path, "meta 'fibers' is missing or out of range");
    K_ = std::size_t(v);
    if (!parse_double(quantum, quantum_) || !is_power_of_two(quantum_) || quantum_ < 1.0 / 65536 ||
        quantum_ > 1.0)
        malformed(path, "meta 'quantum_mm' is missing or no power of two");
    if (!parse_double(spacing, spacing_) || !(spacing_ > 0.0 && spacing_ < 1.0e6))
        malformed(path, "meta 'laser_spacing_mm' is missing or out of range");
    if (parse_double(width, v) && v >= 1 && v <= 65535)
        frame_width_ = std::uint32_t(v);
    if (parse_double(height, v) && v >= 1 && v <= 65535)
        frame_height_ = std::uint32_t(v);

    // Options: the gauge's, by key; unknown keys (a later library's) and
    // values out of range are left at their defaults.
    {
        flt_options *bag = nullptr;
        if (flt_options_create(&bag) != FLT_OK)
            throw error(FLT_ERR_OUT_OF_MEMORY, "out of memory");
        options_ = *bag;
        flt_options_destroy(bag);
        sqlite_statement q(*db_, "SELECT key, value FROM gauge_options");
        while (q.step()) {
            const std::int64_t key = q.column_int(0);
            if (key < 0 || key > 100000)
                continue;
            if (flt_options_set(&options_, flt_option(key), q.column_double(1)) == FLT_OK)
                has_options_ = true;
        }
        clear_error();
    }
    {
        sqlite_statement q(*db_, "SELECT block, first_row, rows, first_time_ns, last_time_ns, "
                                 "first_encoder_mm, last_encoder_mm, length(payload) FROM blocks "
                                 "ORDER BY first_row");
        std::uint64_t end = 0;
        while (q.step()) {
            block_entry e;
            e.id = q.column_int(0);
            const std::int64_t first = q.column_int(1), rows = q.column_int(2);
            if (first < 0 || rows <= 0 || rows > std::int64_t(k_max_block_rows) ||
                std::uint64_t(first) < end)
                malformed(path, "block " + std::to_string(e.id) + " overlaps or is out of range");
            e.first_row = std::uint64_t(first);
            e.rows = std::uint64_t(rows);
            e.first_time_ns = q.column_int(3);
            e.last_time_ns = q.column_int(4);
            e.first_encoder_mm = q.column_double(5);
            e.last_encoder_mm = q.column_double(6);
            block_bytes_ += std::uint64_t(q.column_int(7));
            end = e.first_row + e.rows;
            rows_ += e.rows;
            blocks_.push_back(e);
        }
    }
    {
        sqlite_statement q(*db_,
                           "SELECT e.event, e.before_row, e.time_ns, e.kind, e.encoder_mm, "
                           "e.count, e.label, e.text, c.coil_id, c.order_no, c.heat, c.grade, "
                           "c.customer, "
                           "c.nominal_thickness_mm, c.nominal_width_mm FROM events e LEFT JOIN "
                           "coils c ON c.event = e.event ORDER BY e.event");
        sqlite_statement extras(*db_,
                                "SELECT key, value FROM coil_extras WHERE event = ?1 ORDER BY "
                                "position");
        while (q.step()) {
            recorded_event e;
            e.before_row = q.column_int(1);
            e.time_ns = q.column_int(2);
            const std::string kind = q.column_text(3);
            e.encoder_mm = q.column_double(4);
            e.count = std::uint64_t(std::max<std::int64_t>(0, q.column_int(5)));
            if (kind == "cut") {
                e.kind = recorded_event::cut;
                if (!std::isfinite(e.encoder_mm) || std::fabs(e.encoder_mm) > 1e12)
                    malformed(path, "a cut's position is out of range");
            } else if (kind == "flush") {
                e.kind = recorded_event::flush;
            } else if (kind == "note") {
                e.kind = recorded_event::note;
                e.label = q.column_text(6);
                e.text = q.column_text(7);
                if (!coil_key_problem(e.label.c_str()).empty() ||
                    !coil_text_problem(e.text.c_str()).empty())
                    malformed(path, "a note's kind or text is malformed");
            } else if (kind == "gap") {
                e.kind = recorded_event::gap;
                rows_lost_ += e.count;
            } else if (kind == "coil") {
                e.kind = recorded_event::coil;
                auto info = std::make_shared<flt_coil_info>();
                info->lent = true;  // read-only for the caller (flt_frame_event)
                for (int f = 0; f < k_coil_fields; ++f) {
                    info->text[f] = q.column_text(8 + f);
                    if (!coil_text_problem(info->text[f].c_str()).empty())
                        malformed(path, "a coil's text is malformed");
                }
                info->thickness_mm = q.column_double(13);
                info->width_mm = q.column_double(14);
                if (info->text[0].empty() ||
                    !(info->thickness_mm >= 0 && info->thickness_mm <= 1000) ||
                    !(info->width_mm >= 0 && info->width_mm <= 100000))
                    malformed(path, "a coil's identity is out of range");
                extras.bind(1, q.column_int(0));
                while (extras.step()) {
                    std::string key = extras.column_text(0), value = extras.column_text(1);
                    if (!coil_key_problem(key.c_str()).empty() ||
                        !coil_text_problem(value.c_str()).empty() ||
                        info->extras.size() >= FLT_COIL_EXTRA_MAX)
                        malformed(path, "a coil's extra is malformed");
                    info->extras.emplace_back(std::move(key), std::move(value));
                }
                extras.reset();
                e.coil_info = std::move(info);
            }
            events_.push_back(std::move(e));
        }
        // Events in row order (the event number keeps their order within a
        // row).
        std::stable_sort(events_.begin(), events_.end(),
                         [](const recorded_event &a, const recorded_event &b) {
                             return a.before_row < b.before_row;
                         });
    }
    {
        sqlite_statement q(*db_, "SELECT frame, row FROM frames ORDER BY frame");
        while (q.step()) {
            frame_entry_info f;
            f.id = q.column_int(0);
            f.row = std::uint64_t(std::max<std::int64_t>(0, q.column_int(1)));
            frames_.push_back(f);
        }
    }
}

std::size_t recording_reader::block_of_row(std::uint64_t row) const {
    auto it =
        std::upper_bound(blocks_.begin(), blocks_.end(), row,
                         [](std::uint64_t r, const block_entry &b) { return r < b.first_row; });
    if (it == blocks_.begin())
        return blocks_.size();
    --it;
    return row < it->first_row + it->rows ? std::size_t(it - blocks_.begin()) : blocks_.size();
}

void recording_reader::load_block(std::size_t index, row_block &b, block_scratch &scratch) {
    const block_entry &e = blocks_.at(index);
    sqlite_statement q(*db_, "SELECT codec, crc32, payload FROM blocks WHERE block = ?1");
    q.bind(1, e.id);
    char what[80];
    format_c(what, sizeof what, "block %lld", (long long)e.id);
    if (!q.step())
        throw error(FLT_ERR_FORMAT, what);
    if (q.column_int(0) != k_block_codec) {
        char message[160];
        format_c(message, sizeof message, "%s: codec %lld is not known to this library", what,
                 (long long)q.column_int(0));
        throw error(FLT_ERR_FORMAT, message);
    }
    std::size_t size = 0;
    const std::uint8_t *data = q.column_blob(2, &size);
    if (std::int64_t(crc32_of(data, size)) != q.column_int(1)) {
        char message[160];
        format_c(message, sizeof message, "%s: its CRC-32 does not match (the file is damaged)",
                 what);
        throw error(FLT_ERR_FORMAT, message);
    }
    decode_block(data, size, K_, quantum_, b, scratch, what);
    if (b.rows != e.rows) {
        char message[160];
        format_c(message, sizeof message, "%s: holds %zu rows, its table row says %llu", what,
                 b.rows, (unsigned long long)e.rows);
        throw error(FLT_ERR_FORMAT, message);
    }
    b.first_row = e.first_row;
}

void recording_reader::load_frame(std::size_t index, std::vector<std::uint8_t> &pixels,
                                  flt_pixel_format &format, std::uint32_t &width,
                                  std::uint32_t &height, double &encoder_mm,
                                  std::int64_t &time_ns) {
    const frame_entry_info &f = frames_.at(index);
    sqlite_statement q(*db_, "SELECT format, width, height, codec, crc32, pixels, encoder_mm, "
                             "time_ns FROM frames WHERE frame = ?1");
    q.bind(1, f.id);
    char what[80];
    format_c(what, sizeof what, "frame %lld", (long long)f.id);
    if (!q.step())
        throw error(FLT_ERR_FORMAT, what);
    const std::int64_t fmt = q.column_int(0), w = q.column_int(1), h = q.column_int(2);
    if ((fmt != FLT_PIXEL_MONO8 && fmt != FLT_PIXEL_MONO10 && fmt != FLT_PIXEL_MONO12 &&
         fmt != FLT_PIXEL_MONO16) ||
        w < 1 || h < 1 || w > 65535 || h > 65535 || q.column_int(3) != 1)
        throw error(FLT_ERR_FORMAT, (std::string(what) + ": format, size or codec").c_str());
    std::size_t size = 0;
    const std::uint8_t *data = q.column_blob(5, &size);
    if (std::int64_t(crc32_of(data, size)) != q.column_int(4))
        throw error(FLT_ERR_FORMAT, (std::string(what) + ": its CRC-32 does not match").c_str());
    const std::size_t bytes = std::size_t(w) * std::size_t(h) * (fmt == FLT_PIXEL_MONO8 ? 1 : 2);
    inflate_exact(data, size, bytes, pixels, what);
    format = flt_pixel_format(fmt);
    width = std::uint32_t(w);
    height = std::uint32_t(h);
    encoder_mm = q.column_double(6);
    time_ns = q.column_int(7);
}

}  // namespace flt::record
