// SPDX-License-Identifier: Apache-2.0
// The archive on SQLite: one file, WAL mode, the writer thread its only
// writer.
#include <sqlite3.h>

#include <cmath>

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "core/utf8_path.hpp"
#include "record/database.hpp"
#include "record/sqlite_db.hpp"

namespace flt::record {
namespace {

class sqlite_backend final : public database {
  public:
    explicit sqlite_backend(const std::string &path) : path_(path) { connect(); }
    int backend() const override { return 0; }
    void connect() override {
        if (db_)
            return;
        std::error_code ec;
        const bool fresh = !std::filesystem::exists(utf8_path(path_), ec);
        db_ = std::make_unique<sqlite_db>(path_, fresh ? sqlite_db::mode::create_new
                                                       : sqlite_db::mode::read_write);
        if (fresh)
            db_->exec("PRAGMA page_size = 65536");
        db_->exec("PRAGMA journal_mode = WAL");
        db_->exec("PRAGMA synchronous = FULL");
    }
    bool connected() const override { return db_ != nullptr; }
    void disconnect() override { db_.reset(); }
    void execute(const std::string &sql, const std::vector<db_param> &params) override {
        run(sql, params, nullptr);
    }
    db_rows query(const std::string &sql, const std::vector<db_param> &params) override {
        db_rows rows;
        run(sql, params, &rows);
        return rows;
    }
    bool lost_connection() const override { return false; }
    const char *real_type() const override { return "REAL"; }
    const char *blob_type() const override { return "BLOB"; }

  private:
    void run(const std::string &sql, const std::vector<db_param> &params, db_rows *rows) {
        connect();
        if (params.empty() && rows == nullptr) {
            db_->exec(sql.c_str());
            return;
        }
        sqlite_statement st(*db_, sql.c_str());
        for (std::size_t i = 0; i < params.size(); ++i) {
            const db_param &p = params[i];
            const int at = int(i) + 1;
            switch (p.kind) {
                case db_param::integer:
                    st.bind(at, p.i);
                    break;
                case db_param::real:
                    if (std::isnan(p.d))
                        st.bind_null(at);
                    else
                        st.bind(at, p.d);
                    break;
                case db_param::text:
                    st.bind(at, p.s);
                    break;
                case db_param::blob:
                    st.bind_blob(at, p.data, p.size);
                    break;
                default:
                    st.bind_null(at);
            }
        }
        while (st.step()) {
            if (!rows)
                continue;
            std::vector<std::string> row;
            row.reserve(std::size_t(st.column_count()));
            for (int c = 0; c < st.column_count(); ++c)
                row.push_back(st.column_null(c) ? std::string() : st.column_text(c));
            rows->push_back(std::move(row));
        }
    }
    std::string path_;
    std::unique_ptr<sqlite_db> db_;
};

}  // namespace

bool is_postgres_location(const std::string &location) {
    return location.rfind("postgresql://", 0) == 0 || location.rfind("postgres://", 0) == 0 ||
           location.rfind("pg:", 0) == 0;
}

std::unique_ptr<database> open_sqlite(const std::string &path) {
    return std::make_unique<sqlite_backend>(path);
}

}  // namespace flt::record
