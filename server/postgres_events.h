// Job events shared by the servers of one PostgreSQL database. Each server's JobEvents
// wakes only its own watchers; a job's worker reports to one server, so a watcher on
// another heard of the job's progress only at its next heartbeat. The relay sends every
// change made here with NOTIFY on one channel that every server LISTENs on, and applies
// those the others send, so a watcher on any server hears of a stage, a brick's progress or
// a job's end as its worker's server does.
//
// Best effort, as NOTIFY is: what is sent while the database is away is lost, and the
// watchers then see it at their next heartbeat (the job itself is in the store). One thread
// and one connection of its own (not the store's pool: a listening connection is never
// handed out).
#ifndef SHEETMESH_SERVER_POSTGRES_EVENTS_H_
#define SHEETMESH_SERVER_POSTGRES_EVENTS_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "absl/status/statusor.h"
#include "server/job_events.h"

namespace sheetmesh::server {

inline constexpr char kJobEventsChannel[] = "sheetmesh_job_events";

class PgEventRelay {
 public:
  // Connects to `conninfo`, LISTENs and hooks itself to `events` (SetRelay), which must
  // outlive it. kUnavailable naming the server when it cannot connect.
  static absl::StatusOr<std::unique_ptr<PgEventRelay>> Start(const std::string& conninfo,
                                                             JobEvents* events);
  ~PgEventRelay();  // unhooks, then stops its thread
  PgEventRelay(const PgEventRelay&) = delete;
  PgEventRelay& operator=(const PgEventRelay&) = delete;

  // Changes sent and applied so far (for tests and the log).
  uint64_t sent() const;
  uint64_t applied() const;

  // A change as NOTIFY's payload, and back (nullopt: not one of ours, or damaged).
  static std::string Encode(const std::string& origin, const JobEvent& event);
  static std::optional<std::pair<std::string, JobEvent>> Decode(const std::string& payload);

 private:
  class Impl;
  explicit PgEventRelay(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  JobEvents* events_ = nullptr;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_POSTGRES_EVENTS_H_
