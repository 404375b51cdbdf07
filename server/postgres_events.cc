#include "server/postgres_events.h"

#include <libpq-fe.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <atomic>
#include <deque>
#include <mutex>
#include <random>
#include <set>
#include <thread>
#include <vector>

#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "server/postgres_util.h"

namespace sheetmesh::server {
namespace {

constexpr size_t kMaxQueued = 4096;   // changes waiting to be sent; more are dropped
constexpr size_t kMaxPayload = 7900;  // NOTIFY takes at most 8000 bytes

char KindChar(JobEvent::Kind kind) {
  switch (kind) {
    case JobEvent::Kind::kStage:
      return 's';
    case JobEvent::Kind::kFinished:
      return 'f';
    case JobEvent::Kind::kChanged:
      break;
  }
  return 'c';
}

std::string NewOrigin() {
  std::random_device rd;
  return absl::StrFormat("%08x%08x", rd(), rd());
}

}  // namespace

class PgEventRelay::Impl {
 public:
  Impl(std::string conninfo, JobEvents* events)
      : conninfo_(std::move(conninfo)), events_(events), origin_(NewOrigin()) {
    wake_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  }
  ~Impl() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      stopping_ = true;
    }
    Wake();
    if (thread_.joinable()) thread_.join();
    if (conn_ != nullptr) PQfinish(conn_);
    if (wake_ >= 0) close(wake_);
  }

  // (Re)connects and listens.
  absl::Status Connect() {
    if (conn_ != nullptr) PQfinish(conn_);
    conn_ = PgConnect(conninfo_);
    if (PQstatus(conn_) != CONNECTION_OK) {
      return absl::UnavailableError(
          absl::StrCat("job events: PostgreSQL is unreachable: ",
                       absl::StripTrailingAsciiWhitespace(PQerrorMessage(conn_))));
    }
    PGresult* r = PQexec(conn_, absl::StrCat("LISTEN ", kJobEventsChannel).c_str());
    const bool ok = PQresultStatus(r) == PGRES_COMMAND_OK;
    PQclear(r);
    if (!ok) {
      return absl::UnavailableError(
          absl::StrCat("job events: LISTEN failed: ",
                       absl::StripTrailingAsciiWhitespace(PQerrorMessage(conn_))));
    }
    return absl::OkStatus();
  }

  void StartThread() {
    thread_ = std::thread([this] { Run(); });
  }

  void Push(const JobEvent& event) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stopping_ || queue_.size() >= kMaxQueued) return;  // the heartbeat will tell
      // A change of a job already waiting to be told adds nothing.
      if (event.kind == JobEvent::Kind::kChanged && !changed_.insert(event.job).second) return;
      queue_.push_back(Encode(origin_, event));
    }
    Wake();
  }

  uint64_t sent() const { return sent_; }
  uint64_t applied() const { return applied_; }

 private:
  void Wake() {
    const uint64_t one = 1;
    if (wake_ >= 0) (void)!write(wake_, &one, sizeof one);
  }

  bool stopping() {
    std::lock_guard<std::mutex> lock(mu_);
    return stopping_;
  }

  // Sends what waits; false when the connection failed.
  bool Send() {
    std::deque<std::string> out;
    {
      std::lock_guard<std::mutex> lock(mu_);
      out.swap(queue_);
      changed_.clear();
    }
    for (const std::string& payload : out) {
      const char* params[2] = {kJobEventsChannel, payload.c_str()};
      PGresult* r =
          PQexecParams(conn_, "SELECT pg_notify($1, $2)", 2, nullptr, params, nullptr, nullptr, 0);
      const bool ok = PQresultStatus(r) == PGRES_TUPLES_OK;
      PQclear(r);
      if (!ok) return false;  // the rest is lost with the connection: the heartbeat tells
      ++sent_;
    }
    return true;
  }

  // Applies what the other servers sent; false when the connection failed.
  bool Receive() {
    if (PQconsumeInput(conn_) == 0) return false;
    while (PGnotify* n = PQnotifies(conn_)) {
      std::optional<std::pair<std::string, JobEvent>> e = Decode(n->extra);
      PQfreemem(n);
      if (!e || e->first == origin_) continue;  // ours came back
      ++applied_;                               // before its watchers wake
      events_->Apply(e->second);
    }
    return true;
  }

  void Run() {
    while (!stopping()) {
      if (PQstatus(conn_) != CONNECTION_OK && !Connect().ok()) {
        Wait(-1, 1000);  // the database is away: try again in a second
        continue;
      }
      if (!Send() || !Receive()) {
        PQfinish(conn_);  // connect and LISTEN again on the next turn
        conn_ = nullptr;
        continue;
      }
      Wait(PQsocket(conn_), 1000);
    }
  }

  // Until `socket` has input, something is pushed, or `ms` pass.
  void Wait(int socket, int ms) {
    pollfd fds[2] = {{wake_, POLLIN, 0}, {socket, POLLIN, 0}};
    poll(fds, socket >= 0 ? 2 : 1, ms);
    uint64_t n = 0;
    if (fds[0].revents & POLLIN) (void)!read(wake_, &n, sizeof n);
  }

  const std::string conninfo_;
  JobEvents* const events_;
  const std::string origin_;  // this server's, so that it skips its own
  PGconn* conn_ = nullptr;    // the thread's, once it runs
  int wake_ = -1;             // an eventfd: something to send, or stop
  std::mutex mu_;
  std::deque<std::string> queue_;
  std::set<std::string> changed_;  // jobs with a kChanged in queue_
  bool stopping_ = false;
  std::atomic<uint64_t> sent_{0}, applied_{0};
  std::thread thread_;
};

PgEventRelay::PgEventRelay(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

absl::StatusOr<std::unique_ptr<PgEventRelay>> PgEventRelay::Start(const std::string& conninfo,
                                                                  JobEvents* events) {
  auto impl = std::make_unique<Impl>(conninfo, events);
  if (absl::Status st = impl->Connect(); !st.ok()) return st;
  impl->StartThread();
  Impl* raw = impl.get();
  events->SetRelay([raw](const JobEvent& e) { raw->Push(e); });
  std::unique_ptr<PgEventRelay> relay(new PgEventRelay(std::move(impl)));
  relay->events_ = events;
  return relay;
}

PgEventRelay::~PgEventRelay() {
  if (events_ != nullptr) events_->SetRelay(nullptr);
}

uint64_t PgEventRelay::sent() const { return impl_->sent(); }
uint64_t PgEventRelay::applied() const { return impl_->applied(); }

std::string PgEventRelay::Encode(const std::string& origin, const JobEvent& event) {
  std::string payload =
      absl::StrCat(origin, "\n", std::string(1, KindChar(event.kind)), "\n", event.job, "\n");
  if (event.kind == JobEvent::Kind::kStage) {
    const std::string progress = absl::Base64Escape(event.progress.SerializeAsString());
    if (payload.size() + progress.size() > kMaxPayload) {
      // Too long to send whole: told as a change, the stage is seen in the job.
      return absl::StrCat(origin, "\nc\n", event.job, "\n");
    }
    payload += progress;
  }
  return payload;
}

std::optional<std::pair<std::string, JobEvent>> PgEventRelay::Decode(const std::string& payload) {
  const std::vector<std::string> parts = absl::StrSplit(payload, absl::MaxSplits('\n', 3));
  if (parts.size() != 4 || parts[0].empty() || parts[1].size() != 1 || parts[2].empty()) {
    return std::nullopt;
  }
  JobEvent e;
  e.job = parts[2];
  switch (parts[1][0]) {
    case 'c':
      e.kind = JobEvent::Kind::kChanged;
      break;
    case 'f':
      e.kind = JobEvent::Kind::kFinished;
      break;
    case 's': {
      e.kind = JobEvent::Kind::kStage;
      std::string bytes;
      if (!absl::Base64Unescape(parts[3], &bytes) || !e.progress.ParseFromString(bytes)) {
        return std::nullopt;
      }
      break;
    }
    default:
      return std::nullopt;
  }
  return std::make_pair(parts[0], std::move(e));
}

}  // namespace sheetmesh::server
