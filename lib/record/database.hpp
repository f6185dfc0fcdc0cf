// SPDX-License-Identifier: Apache-2.0
// Internal: the archive's database, SQLite (embedded) or PostgreSQL (libpq,
// loaded at run time), behind one small interface. Statements are written
// once with ?1, ?2, ... parameters; the PostgreSQL side turns them into
// $1, $2, .... Errors are thrown as flt::error: FLT_ERR_IO for a database
// that could not be reached or refused a statement (the message is the
// database's), with lost_connection() telling a connection that went away
// from a statement that is wrong.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace flt::record {

struct db_param {
    enum kind_t { null, integer, real, text, blob } kind = null;
    std::int64_t i = 0;
    double d = 0.0;  // a NaN is written as NULL
    std::string s;
    const std::uint8_t *data = nullptr;  // blob, borrowed for the call
    std::size_t size = 0;

    static db_param of(std::int64_t v) {
        db_param p;
        p.kind = integer;
        p.i = v;
        return p;
    }
    static db_param of(double v) {
        db_param p;
        p.kind = real;
        p.d = v;
        return p;
    }
    static db_param of(std::string v) {
        db_param p;
        p.kind = text;
        p.s = std::move(v);
        return p;
    }
    static db_param of_blob(const std::uint8_t *data, std::size_t size) {
        db_param p;
        p.kind = blob;
        p.data = data;
        p.size = size;
        return p;
    }
};

// A query's rows as text (numbers in the C locale's form), NULL as "".
using db_rows = std::vector<std::vector<std::string>>;

class database {
  public:
    virtual ~database() = default;
    // 0 SQLite, 1 PostgreSQL.
    virtual int backend() const = 0;
    // Connects (again) when not connected; throws when it cannot.
    virtual void connect() = 0;
    virtual bool connected() const = 0;
    // Drops the connection (the next connect() makes a new one).
    virtual void disconnect() = 0;
    virtual void execute(const std::string &sql, const std::vector<db_param> &params = {}) = 0;
    virtual db_rows query(const std::string &sql, const std::vector<db_param> &params = {}) = 0;
    // After a failed call: true when the connection itself failed (the
    // server went away), false when the statement was refused.
    virtual bool lost_connection() const = 0;
    // The schema's column types: REAL is 8 bytes in SQLite, 4 in
    // PostgreSQL (there: DOUBLE PRECISION); BLOB is BYTEA there.
    virtual const char *real_type() const = 0;
    virtual const char *blob_type() const = 0;
};

// A location: a file path (SQLite), "postgresql://...", "postgres://..."
// or "pg:<libpq key=value form>" (PostgreSQL).
bool is_postgres_location(const std::string &location);
std::unique_ptr<database> open_sqlite(const std::string &path);
// Loads libpq (throws FLT_ERR_NOT_FOUND naming the file tried) and keeps
// the connection string; connect() connects.
std::unique_ptr<database> open_postgres(const std::string &location);

}  // namespace flt::record
