// A few connections to PostgreSQL (libpq) shared by the threads of one store, and a
// query helper that turns libpq's errors into statuses naming the server.
#ifndef SHEETMESH_SERVER_POSTGRES_UTIL_H_
#define SHEETMESH_SERVER_POSTGRES_UTIL_H_

#include <condition_variable>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

typedef struct pg_conn PGconn;
typedef struct pg_result PGresult;

namespace sheetmesh::server {

// A query's rows, as text (bytea columns unescaped by Bytes).
class PgResult {
 public:
  explicit PgResult(PGresult* r) : r_(r) {}
  PgResult(PgResult&& o) noexcept : r_(o.r_) { o.r_ = nullptr; }
  PgResult& operator=(PgResult&&) = delete;
  ~PgResult();
  int rows() const;
  bool null(int row, int col) const;
  std::string Text(int row, int col) const;
  int64_t Int(int row, int col) const;
  std::string Bytes(int row, int col) const;  // a bytea column
  int64_t affected() const;                   // rows an UPDATE or DELETE touched
  PGresult* get() const { return r_; }

 private:
  PGresult* r_;
};

// A parameter: text, or binary bytes (bytea).
struct PgParam {
  std::string value;
  bool binary = false;
  bool null = false;
  static PgParam Bytes(std::string b) { return {std::move(b), true, false}; }
  static PgParam Null() { return {"", false, true}; }
};
PgParam P(const std::string& s);
PgParam P(const char* s);
PgParam P(int64_t v);

// Connects to `conninfo` (key=value pairs or a URI). A connection string without
// connect_timeout waits kDefaultConnectTimeoutSeconds for a database that does not answer,
// not the system's TCP timeout (minutes): the server's start, its requeueing and its
// shutdown do not hang on a host gone from the network. Never null but out of memory.
inline constexpr int kDefaultConnectTimeoutSeconds = 10;
PGconn* PgConnect(const std::string& conninfo);

class PgConnection {
 public:
  explicit PgConnection(PGconn* c) : c_(c) {}
  ~PgConnection();
  // Runs `sql` with $1.. bound to `params`. kUnavailable when the connection is lost (the
  // pool reconnects it next time), kAlreadyExists for a unique violation, kInternal else;
  // messages name the server.
  absl::StatusOr<PgResult> Query(const std::string& sql, const std::vector<PgParam>& params = {});
  absl::Status Exec(const std::string& sql) { return Query(sql).status(); }
  bool healthy() const;
  bool Reset();  // reconnects; false when the server is still gone
  std::string where() const;

 private:
  PGconn* c_;
};

// Up to `size` connections to one database.
class PgPool {
 public:
  // Connects once to check the server: kUnavailable naming host, port and database and
  // libpq's reason when it cannot.
  static absl::StatusOr<std::unique_ptr<PgPool>> Open(const std::string& conninfo, int size);

  // A connection for one transaction; returned to the pool when it goes.
  class Lease {
   public:
    Lease(PgPool* pool, std::unique_ptr<PgConnection> c) : pool_(pool), c_(std::move(c)) {}
    Lease(Lease&&) = default;
    ~Lease();
    PgConnection* operator->() { return c_.get(); }

   private:
    PgPool* pool_;
    std::unique_ptr<PgConnection> c_;
  };
  absl::StatusOr<Lease> Get();

  // Runs `body` in a transaction (BEGIN ... COMMIT, ROLLBACK on error). Where PostgreSQL
  // rolls it back as a deadlock's victim or for a serialization failure (kAborted from
  // Query: two replicas finishing and requeueing the same jobs), the whole transaction runs
  // again, up to kTransactionAttempts times, a little later each time: `body` must set what
  // it hands out afresh on every run.
  template <class F>
  absl::Status Transaction(F&& body) {
    absl::Status st;
    for (int attempt = 0; attempt < kTransactionAttempts; ++attempt) {
      if (attempt > 0) PauseBeforeAttempt(attempt);
      st = TransactionOnce(body);
      if (!absl::IsAborted(st)) return st;
    }
    return st;
  }
  static constexpr int kTransactionAttempts = 5;

  const std::string& where() const { return where_; }

 private:
  PgPool(std::string conninfo, std::string where, int size)
      : conninfo_(std::move(conninfo)), where_(std::move(where)), size_(size) {}
  template <class F>
  absl::Status TransactionOnce(F& body) {
    absl::StatusOr<Lease> c = Get();
    if (!c.ok()) return c.status();
    if (absl::Status st = (*c)->Exec("BEGIN"); !st.ok()) return st;
    absl::Status st = body(*c);
    if (!st.ok()) {
      (*c)->Exec("ROLLBACK").IgnoreError();
      return st;
    }
    return (*c)->Exec("COMMIT");
  }
  // Sleeps a few milliseconds, more for each attempt and drawn at random, so two replicas
  // that deadlocked do not meet again at once.
  static void PauseBeforeAttempt(int attempt);
  absl::StatusOr<std::unique_ptr<PgConnection>> Connect();
  void Return(std::unique_ptr<PgConnection> c);

  const std::string conninfo_, where_;
  const int size_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::vector<std::unique_ptr<PgConnection>> idle_;
  int open_ = 0;  // connections made and not closed, idle or leased
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_POSTGRES_UTIL_H_
