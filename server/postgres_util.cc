#include "server/postgres_util.h"

#include <libpq-fe.h>

#include <cstdlib>
#include <cstring>
#include <random>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "absl/time/time.h"

namespace sheetmesh::server {

PgResult::~PgResult() {
  if (r_ != nullptr) PQclear(r_);
}
int PgResult::rows() const { return PQntuples(r_); }
bool PgResult::null(int row, int col) const { return PQgetisnull(r_, row, col) != 0; }
std::string PgResult::Text(int row, int col) const {
  return std::string(PQgetvalue(r_, row, col), PQgetlength(r_, row, col));
}
int64_t PgResult::Int(int row, int col) const {
  int64_t v = 0;
  return absl::SimpleAtoi(Text(row, col), &v) ? v : 0;
}
std::string PgResult::Bytes(int row, int col) const {
  size_t n = 0;
  unsigned char* b =
      PQunescapeBytea(reinterpret_cast<const unsigned char*>(PQgetvalue(r_, row, col)), &n);
  if (b == nullptr) return "";
  std::string out(reinterpret_cast<const char*>(b), n);
  PQfreemem(b);
  return out;
}
int64_t PgResult::affected() const {
  int64_t v = 0;
  return absl::SimpleAtoi(PQcmdTuples(r_), &v) ? v : 0;
}

PgParam P(const std::string& s) { return {s, false, false}; }
PgParam P(const char* s) { return {s, false, false}; }
PgParam P(int64_t v) { return {absl::StrCat(v), false, false}; }

PgConnection::~PgConnection() { PQfinish(c_); }

bool PgConnection::healthy() const { return PQstatus(c_) == CONNECTION_OK; }

bool PgConnection::Reset() {
  PQreset(c_);
  return healthy();
}

std::string PgConnection::where() const {
  return absl::StrCat("PostgreSQL at ", PQhost(c_) ? PQhost(c_) : "?", ":",
                      PQport(c_) ? PQport(c_) : "?", " (database ", PQdb(c_) ? PQdb(c_) : "?", ")");
}

absl::StatusOr<PgResult> PgConnection::Query(const std::string& sql,
                                             const std::vector<PgParam>& params) {
  std::vector<const char*> values(params.size());
  std::vector<int> lengths(params.size()), formats(params.size());
  for (size_t i = 0; i < params.size(); ++i) {
    values[i] = params[i].null ? nullptr : params[i].value.data();
    lengths[i] = static_cast<int>(params[i].value.size());
    formats[i] = params[i].binary ? 1 : 0;
  }
  PgResult r(PQexecParams(c_, sql.c_str(), static_cast<int>(params.size()), nullptr, values.data(),
                          lengths.data(), formats.data(), 0));
  const ExecStatusType st = PQresultStatus(r.get());
  if (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK) return r;
  std::string msg(absl::StripAsciiWhitespace(PQerrorMessage(c_)));
  if (!healthy()) {
    return absl::UnavailableError(absl::StrCat(where(), " is unreachable: ", msg));
  }
  const char* state = PQresultErrorField(r.get(), PG_DIAG_SQLSTATE);
  if (state != nullptr && std::strcmp(state, "23505") == 0) {
    return absl::AlreadyExistsError(absl::StrCat(where(), ": ", msg));
  }
  // deadlock_detected, serialization_failure: the transaction was rolled back and may run
  // again (PgPool::Transaction does).
  if (state != nullptr && (std::strcmp(state, "40P01") == 0 || std::strcmp(state, "40001") == 0)) {
    return absl::AbortedError(absl::StrCat(where(), ": ", msg, " (in: ", sql.substr(0, 120), ")"));
  }
  return absl::InternalError(absl::StrCat(where(), ": ", msg, " (in: ", sql.substr(0, 120), ")"));
}

void PgPool::PauseBeforeAttempt(int attempt) {
  static thread_local std::minstd_rand gen(std::random_device{}());
  absl::SleepFor(absl::Milliseconds(std::uniform_real_distribution<double>(5, 20)(gen) * attempt));
}

absl::StatusOr<std::unique_ptr<PgPool>> PgPool::Open(const std::string& conninfo, int size) {
  // Where, for messages: from the parsed conninfo, before any connection exists.
  std::string host = "localhost", port = "5432", db = "";
  char* err = nullptr;
  PQconninfoOption* opts = PQconninfoParse(conninfo.c_str(), &err);
  if (opts == nullptr) {
    std::string msg = err ? std::string(absl::StripAsciiWhitespace(err)) : "cannot be parsed";
    if (err) PQfreemem(err);
    return absl::InvalidArgumentError(absl::StrCat("--postgres='", conninfo, "': ", msg));
  }
  for (PQconninfoOption* o = opts; o->keyword != nullptr; ++o) {
    if (o->val == nullptr) continue;
    if (std::strcmp(o->keyword, "host") == 0) host = o->val;
    if (std::strcmp(o->keyword, "port") == 0) port = o->val;
    if (std::strcmp(o->keyword, "dbname") == 0) db = o->val;
  }
  PQconninfoFree(opts);
  std::string where = absl::StrCat("PostgreSQL at ", host, ":", port,
                                   db.empty() ? "" : absl::StrCat(" (database ", db, ")"));
  std::unique_ptr<PgPool> pool(new PgPool(conninfo, where, size));
  absl::StatusOr<std::unique_ptr<PgConnection>> first = pool->Connect();
  if (!first.ok()) return first.status();
  pool->open_ = 1;
  pool->Return(std::move(*first));
  return pool;
}

PGconn* PgConnect(const std::string& conninfo) {
  // The expanded string's own connect_timeout, where it has one, overrides the one before it.
  const std::string timeout = std::to_string(kDefaultConnectTimeoutSeconds);
  const char* keys[] = {"connect_timeout", "dbname", nullptr};
  const char* values[] = {timeout.c_str(), conninfo.c_str(), nullptr};
  return PQconnectdbParams(keys, values, /*expand_dbname=*/1);
}

absl::StatusOr<std::unique_ptr<PgConnection>> PgPool::Connect() {
  PGconn* c = PgConnect(conninfo_);
  if (c == nullptr) return absl::ResourceExhaustedError("libpq: out of memory");
  if (PQstatus(c) != CONNECTION_OK) {
    std::string msg(absl::StripAsciiWhitespace(PQerrorMessage(c)));
    PQfinish(c);
    return absl::UnavailableError(absl::StrCat(where_, " is unreachable: ", msg));
  }
  // Quiet: notices (an existing table, ...) are not the operator's business.
  PQsetNoticeProcessor(
      c, [](void*, const char*) {}, nullptr);
  return std::make_unique<PgConnection>(c);
}

absl::StatusOr<PgPool::Lease> PgPool::Get() {
  std::unique_lock<std::mutex> lock(mu_);
  cv_.wait(lock, [&] { return !idle_.empty() || open_ < size_; });
  std::unique_ptr<PgConnection> c;
  if (!idle_.empty()) {
    c = std::move(idle_.back());
    idle_.pop_back();
  } else {
    ++open_;
    lock.unlock();
    absl::StatusOr<std::unique_ptr<PgConnection>> fresh = Connect();
    if (!fresh.ok()) {
      std::lock_guard<std::mutex> relock(mu_);
      --open_;
      cv_.notify_one();
      return fresh.status();
    }
    return Lease(this, std::move(*fresh));
  }
  lock.unlock();
  if (!c->healthy() && !c->Reset()) {
    // The server went: this connection is kept and tried again next time.
    const std::string where = c->where();
    Return(std::move(c));
    return absl::UnavailableError(absl::StrCat(where, " is unreachable"));
  }
  return Lease(this, std::move(c));
}

void PgPool::Return(std::unique_ptr<PgConnection> c) {
  std::lock_guard<std::mutex> lock(mu_);
  idle_.push_back(std::move(c));
  cv_.notify_one();
}

PgPool::Lease::~Lease() {
  if (c_ != nullptr) pool_->Return(std::move(c_));
}

}  // namespace sheetmesh::server
