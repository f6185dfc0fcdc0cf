// SPDX-License-Identifier: Apache-2.0
#include "record/sqlite_db.hpp"

#include <sqlite3.h>

#include <system_error>

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "core/utf8_path.hpp"

namespace flt::record {

sqlite_db::sqlite_db(const std::string &path, mode how) : path_(path) {
    if (how == mode::create_new) {
        std::error_code ec;
        if (std::filesystem::exists(utf8_path(path), ec)) {
            char message[600];
            format_c(message, sizeof message,
                     "'%s' exists: a record is never overwritten (remove it or choose another "
                     "name)",
                     path.c_str());
            throw error(FLT_ERR_IO, message);
        }
    }
    int flags = SQLITE_OPEN_FULLMUTEX;
    if (how == mode::create_new)
        flags |= SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE;
    else if (how == mode::read_write)
        flags |= SQLITE_OPEN_READWRITE;
    else
        flags |= SQLITE_OPEN_READONLY;
    // SQLite takes UTF-8 file names on every platform (it converts them to
    // UTF-16 on Windows itself).
    const int st = sqlite3_open_v2(path.c_str(), &db_, flags, nullptr);
    if (st != SQLITE_OK) {
        char message[700];
        format_c(message, sizeof message, "cannot open '%s': %s", path.c_str(),
                 db_ ? sqlite3_errmsg(db_) : sqlite3_errstr(st));
        sqlite3_close(db_);
        db_ = nullptr;
        throw error(FLT_ERR_IO, message);
    }
    sqlite3_extended_result_codes(db_, 1);
    // A reader waits for a writer's checkpoint instead of failing at once.
    sqlite3_busy_timeout(db_, 5000);
}

sqlite_db::~sqlite_db() {
    sqlite3_close_v2(db_);
}

void sqlite_db::raise(const char *what) const {
    const int code = sqlite3_errcode(db_);
    const int primary = code & 0xFF;
    const flt_status status =
        primary == SQLITE_NOTADB || primary == SQLITE_CORRUPT ? FLT_ERR_FORMAT : FLT_ERR_IO;
    char message[700];
    format_c(message, sizeof message, "%s ('%s'): %s", what, path_.c_str(), sqlite3_errmsg(db_));
    throw error(status, message);
}

void sqlite_db::exec(const char *sql) {
    if (sqlite3_exec(db_, sql, nullptr, nullptr, nullptr) != SQLITE_OK)
        raise("SQLite");
}

std::int64_t sqlite_db::scalar_int(const char *sql) {
    sqlite_statement q(*this, sql);
    return q.step() ? q.column_int(0) : 0;
}

std::int64_t sqlite_db::last_insert_rowid() const {
    return std::int64_t(sqlite3_last_insert_rowid(db_));
}

sqlite_statement::sqlite_statement(sqlite_db &db, const char *sql) : db_(db) {
    if (sqlite3_prepare_v2(db.handle(), sql, -1, &stmt_, nullptr) != SQLITE_OK)
        db.raise("SQLite statement");
}

sqlite_statement::~sqlite_statement() {
    sqlite3_finalize(stmt_);
}

sqlite_statement &sqlite_statement::bind(int i, std::int64_t v) {
    if (sqlite3_bind_int64(stmt_, i, sqlite3_int64(v)) != SQLITE_OK)
        db_.raise("SQLite bind");
    return *this;
}

sqlite_statement &sqlite_statement::bind(int i, double v) {
    if (sqlite3_bind_double(stmt_, i, v) != SQLITE_OK)
        db_.raise("SQLite bind");
    return *this;
}

sqlite_statement &sqlite_statement::bind(int i, const std::string &v) {
    if (sqlite3_bind_text(stmt_, i, v.data(), int(v.size()), SQLITE_TRANSIENT) != SQLITE_OK)
        db_.raise("SQLite bind");
    return *this;
}

sqlite_statement &sqlite_statement::bind_null(int i) {
    if (sqlite3_bind_null(stmt_, i) != SQLITE_OK)
        db_.raise("SQLite bind");
    return *this;
}

sqlite_statement &sqlite_statement::bind_blob(int i, const void *data, std::size_t size) {
    if (sqlite3_bind_blob64(stmt_, i, size ? data : "", sqlite3_uint64(size), SQLITE_STATIC) !=
        SQLITE_OK)
        db_.raise("SQLite bind");
    return *this;
}

bool sqlite_statement::step() {
    const int st = sqlite3_step(stmt_);
    if (st == SQLITE_ROW)
        return true;
    if (st == SQLITE_DONE)
        return false;
    sqlite3_reset(stmt_);
    db_.raise("SQLite");
}

void sqlite_statement::reset() {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
}

void sqlite_statement::run() {
    while (step()) {
    }
    reset();
}

std::int64_t sqlite_statement::column_int(int i) const {
    return std::int64_t(sqlite3_column_int64(stmt_, i));
}

double sqlite_statement::column_double(int i) const {
    return sqlite3_column_double(stmt_, i);
}

std::string sqlite_statement::column_text(int i) const {
    const auto *t = sqlite3_column_text(stmt_, i);
    const int n = sqlite3_column_bytes(stmt_, i);
    return t ? std::string(reinterpret_cast<const char *>(t), std::size_t(n)) : std::string();
}

int sqlite_statement::column_count() const {
    return sqlite3_column_count(stmt_);
}

bool sqlite_statement::column_null(int i) const {
    return sqlite3_column_type(stmt_, i) == SQLITE_NULL;
}

const std::uint8_t *sqlite_statement::column_blob(int i, std::size_t *size) const {
    const void *b = sqlite3_column_blob(stmt_, i);
    *size = std::size_t(sqlite3_column_bytes(stmt_, i));
    return static_cast<const std::uint8_t *>(b);
}

}  // namespace flt::record
