// SPDX-License-Identifier: Apache-2.0
// The archive on PostgreSQL through libpq, loaded when an archive is
// opened (dlopen / LoadLibrary): libflatline links no libpq, builds without
// it, and a user who has a PostgreSQL client gets the backend. The few
// libpq functions used are declared here with libpq's own signatures
// (libpq-fe.h, stable since PostgreSQL 7.4).
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <mutex>

#ifdef _WIN32
#  ifndef WIN32_LEAN_AND_MEAN
#    define WIN32_LEAN_AND_MEAN
#  endif
#  include <windows.h>
#else
#  include <dlfcn.h>
#endif

#include "core/error.hpp"
#include "core/number_text.hpp"
#include "core/utf8_path.hpp"
#include "record/database.hpp"

namespace flt::record {
namespace {

// libpq's types, opaque here.
struct pg_conn;
struct pg_result;
using Oid = unsigned int;
constexpr int k_connection_ok = 0;  // ConnStatusType CONNECTION_OK
constexpr int k_command_ok = 1;     // ExecStatusType PGRES_COMMAND_OK
constexpr int k_tuples_ok = 2;      // PGRES_TUPLES_OK

struct libpq {
    pg_conn *(*connectdb)(const char *) = nullptr;
    int (*status)(const pg_conn *) = nullptr;
    char *(*error_message)(const pg_conn *) = nullptr;
    void (*finish)(pg_conn *) = nullptr;
    pg_result *(*exec_params)(pg_conn *, const char *, int, const Oid *, const char *const *,
                              const int *, const int *, int) = nullptr;
    int (*result_status)(const pg_result *) = nullptr;
    char *(*result_error_message)(const pg_result *) = nullptr;
    void (*clear)(pg_result *) = nullptr;
    int (*ntuples)(const pg_result *) = nullptr;
    int (*nfields)(const pg_result *) = nullptr;
    char *(*getvalue)(const pg_result *, int, int) = nullptr;
    int (*getisnull)(const pg_result *, int, int) = nullptr;
    using notice_processor = void (*)(void *, const char *);
    notice_processor (*set_notice_processor)(pg_conn *, notice_processor, void *) = nullptr;
    bool loaded = false;
    std::string tried;
    std::string missing;  // a function the loaded library lacks
};

// `missing` names the first function the library lacks (then it is no
// libpq, or one too old).
template <class F>
void resolve(void *lib, const char *name, F &out, bool &ok, std::string &missing) {
#ifdef _WIN32
    auto *sym = reinterpret_cast<void *>(GetProcAddress(static_cast<HMODULE>(lib), name));
#else
    void *sym = dlsym(lib, name);
#endif
    if (!sym) {
        if (ok)
            missing = name;
        ok = false;
    }
    std::memcpy(&out, &sym, sizeof out);
}

// Loaded once per process; never unloaded (libpq keeps global state).
const libpq &load_libpq() {
    static libpq pq;
    static std::once_flag once;
    std::call_once(once, [] {
        const char *env = std::getenv("FLT_LIBPQ");
#ifdef _WIN32
        // FLT_LIBPQ is UTF-8, as every path the library takes (a folder
        // named "Jürgen" too): converted to UTF-16 for LoadLibraryW.
        const char *name = env && *env ? env : "libpq.dll";
        void *lib = nullptr;
        try {
            lib = LoadLibraryW(utf8_path(name).c_str());
        } catch (const error &) {  // not UTF-8: no file has that name
        }
#elif defined(__APPLE__)
        const char *name = env && *env ? env : "libpq.5.dylib";
        void *lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
#else
        const char *name = env && *env ? env : "libpq.so.5";
        void *lib = dlopen(name, RTLD_NOW | RTLD_LOCAL);
#endif
        pq.tried = name;
        if (!lib)
            return;
        bool ok = true;
        resolve(lib, "PQconnectdb", pq.connectdb, ok, pq.missing);
        resolve(lib, "PQstatus", pq.status, ok, pq.missing);
        resolve(lib, "PQerrorMessage", pq.error_message, ok, pq.missing);
        resolve(lib, "PQfinish", pq.finish, ok, pq.missing);
        resolve(lib, "PQexecParams", pq.exec_params, ok, pq.missing);
        resolve(lib, "PQresultStatus", pq.result_status, ok, pq.missing);
        resolve(lib, "PQresultErrorMessage", pq.result_error_message, ok, pq.missing);
        resolve(lib, "PQclear", pq.clear, ok, pq.missing);
        resolve(lib, "PQntuples", pq.ntuples, ok, pq.missing);
        resolve(lib, "PQnfields", pq.nfields, ok, pq.missing);
        resolve(lib, "PQgetvalue", pq.getvalue, ok, pq.missing);
        resolve(lib, "PQgetisnull", pq.getisnull, ok, pq.missing);
        resolve(lib, "PQsetNoticeProcessor", pq.set_notice_processor, ok, pq.missing);
        pq.loaded = ok;
    });
    return pq;
}

void quiet_notices(void * /*arg*/, const char * /*message*/) {}

// ?N -> $N (the statements are written for SQLite).
std::string dollar_parameters(const std::string &sql) {
    std::string out = sql;
    for (std::size_t i = 0; i + 1 < out.size(); ++i)
        if (out[i] == '?' && out[i + 1] >= '0' && out[i + 1] <= '9')
            out[i] = '$';
    return out;
}

std::string trimmed(const char *message) {
    std::string m = message ? message : "";
    // libpq's messages span lines; a log line and an error message do not.
    for (char &c : m)
        if (c == '\n' || c == '\t')
            c = ' ';
    while (!m.empty() && (m.back() == '\n' || m.back() == ' '))
        m.pop_back();
    return m;
}

class postgres_backend final : public database {
  public:
    explicit postgres_backend(const std::string &location) : pq_(load_libpq()) {
        if (!pq_.loaded && !pq_.missing.empty()) {
            char message[400];
            format_c(message, sizeof message,
                     "PostgreSQL needs libpq: '%s' was loaded but has no function %s (not libpq, "
                     "or one too old; the environment variable FLT_LIBPQ names the file)",
                     pq_.tried.c_str(), pq_.missing.c_str());
            throw error(FLT_ERR_NOT_FOUND, message);
        }
        if (!pq_.loaded) {
            char message[400];
            format_c(message, sizeof message,
                     "PostgreSQL needs libpq, which could not be loaded from '%s' (install a "
                     "PostgreSQL client: Debian libpq5, or put libpq.dll and its DLLs on the PATH; "
                     "or name the file in the environment variable FLT_LIBPQ)",
                     pq_.tried.c_str());
            throw error(FLT_ERR_NOT_FOUND, message);
        }
        conninfo_ = location.rfind("pg:", 0) == 0 ? location.substr(3) : location;
    }
    ~postgres_backend() override { disconnect(); }
    int backend() const override { return 1; }
    void connect() override {
        if (conn_)
            return;
        pg_conn *c = pq_.connectdb(conninfo_.c_str());
        if (!c)
            throw error(FLT_ERR_OUT_OF_MEMORY, "libpq could not allocate a connection");
        if (pq_.status(c) != k_connection_ok) {
            const std::string why = trimmed(pq_.error_message(c));
            pq_.finish(c);
            lost_ = true;
            throw error(FLT_ERR_IO, ("PostgreSQL: cannot connect: " + why).c_str());
        }
        pq_.set_notice_processor(c, quiet_notices, nullptr);
        conn_ = c;
        lost_ = false;
    }
    bool connected() const override { return conn_ != nullptr; }
    void disconnect() override {
        if (conn_)
            pq_.finish(conn_);
        conn_ = nullptr;
    }
    void execute(const std::string &sql, const std::vector<db_param> &params) override {
        run(sql, params, nullptr);
    }
    db_rows query(const std::string &sql, const std::vector<db_param> &params) override {
        db_rows rows;
        run(sql, params, &rows);
        return rows;
    }
    bool lost_connection() const override { return lost_; }
    const char *real_type() const override { return "DOUBLE PRECISION"; }
    const char *blob_type() const override { return "BYTEA"; }

  private:
    void run(const std::string &sql, const std::vector<db_param> &params, db_rows *rows) {
        connect();
        const std::size_t n = params.size();
        std::vector<std::string> text(n);
        std::vector<const char *> values(n);
        std::vector<int> lengths(n), formats(n);
        for (std::size_t i = 0; i < n; ++i) {
            const db_param &p = params[i];
            values[i] = nullptr;
            switch (p.kind) {
                case db_param::integer:
                    text[i] = std::to_string(p.i);
                    values[i] = text[i].c_str();
                    break;
                case db_param::real:
                    if (!std::isnan(p.d)) {
                        text[i] = format_double(p.d);  // locale-proof
                        values[i] = text[i].c_str();
                    }
                    break;
                case db_param::text:
                    values[i] = p.s.c_str();
                    break;
                case db_param::blob:
                    values[i] = reinterpret_cast<const char *>(p.size ? p.data : nullptr);
                    if (!values[i])
                        values[i] = "";
                    lengths[i] = int(p.size);
                    formats[i] = 1;  // binary: the bytes as they are
                    break;
                default:
                    break;
            }
        }
        const std::string statement = dollar_parameters(sql);
        pg_result *r = pq_.exec_params(conn_, statement.c_str(), int(n), nullptr, values.data(),
                                       lengths.data(), formats.data(), 0);
        const int st = r ? pq_.result_status(r) : -1;
        if (st != k_command_ok && st != k_tuples_ok) {
            std::string why = r ? trimmed(pq_.result_error_message(r)) : std::string();
            if (why.empty())
                why = trimmed(pq_.error_message(conn_));
            if (r)
                pq_.clear(r);
            // A connection that broke is dropped and made again later; a
            // statement the server refused leaves it standing.
            lost_ = pq_.status(conn_) != k_connection_ok;
            if (lost_)
                disconnect();
            throw error(FLT_ERR_IO, ("PostgreSQL: " + why).c_str());
        }
        lost_ = false;
        if (rows) {
            const int nt = pq_.ntuples(r), nf = pq_.nfields(r);
            for (int t = 0; t < nt; ++t) {
                std::vector<std::string> row;
                row.reserve(std::size_t(nf));
                for (int f = 0; f < nf; ++f)
                    row.push_back(pq_.getisnull(r, t, f) ? std::string() : pq_.getvalue(r, t, f));
                rows->push_back(std::move(row));
            }
        }
        pq_.clear(r);
    }

    const libpq &pq_;
    std::string conninfo_;
    pg_conn *conn_ = nullptr;
    bool lost_ = false;
};

}  // namespace

std::unique_ptr<database> open_postgres(const std::string &location) {
    return std::make_unique<postgres_backend>(location);
}

}  // namespace flt::record
