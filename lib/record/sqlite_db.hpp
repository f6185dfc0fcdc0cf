// SPDX-License-Identifier: Apache-2.0
// Internal: a thin RAII layer over SQLite's C API for the recordings and the
// SQLite archive. Errors are thrown as flt::error (FLT_ERR_IO, or
// FLT_ERR_FORMAT for a file that is no database) with SQLite's message.
#pragma once

#include <cstdint>
#include <string>

struct sqlite3;
struct sqlite3_stmt;

namespace flt::record {

class sqlite_statement;

class sqlite_db {
  public:
    enum class mode { create_new, read_write, read_only };
    // Opens `path` (UTF-8). create_new refuses an existing file.
    sqlite_db(const std::string &path, mode how);
    ~sqlite_db();
    sqlite_db(const sqlite_db &) = delete;
    sqlite_db &operator=(const sqlite_db &) = delete;

    void exec(const char *sql);
    sqlite3 *handle() const { return db_; }
    const std::string &path() const { return path_; }
    [[noreturn]] void raise(const char *what) const;
    // One integer from a query (0 when it has no row).
    std::int64_t scalar_int(const char *sql);
    std::int64_t last_insert_rowid() const;

  private:
    sqlite3 *db_ = nullptr;
    std::string path_;
};

class sqlite_statement {
  public:
    sqlite_statement(sqlite_db &db, const char *sql);
    ~sqlite_statement();
    sqlite_statement(const sqlite_statement &) = delete;
    sqlite_statement &operator=(const sqlite_statement &) = delete;

    // Parameters from 1.
    sqlite_statement &bind(int i, std::int64_t v);
    sqlite_statement &bind(int i, double v);
    sqlite_statement &bind(int i, const std::string &v);
    sqlite_statement &bind_null(int i);
    // The blob is not copied: it must live until the statement is reset.
    sqlite_statement &bind_blob(int i, const void *data, std::size_t size);
    // Runs to the next row: true with a row, false when done.
    bool step();
    void reset();  // and clears the bindings
    // Runs a statement that returns no rows, then resets it.
    void run();

    std::int64_t column_int(int i) const;
    double column_double(int i) const;
    std::string column_text(int i) const;
    bool column_null(int i) const;
    int column_count() const;
    const std::uint8_t *column_blob(int i, std::size_t *size) const;

  private:
    sqlite_db &db_;
    sqlite3_stmt *stmt_ = nullptr;
};

}  // namespace flt::record
