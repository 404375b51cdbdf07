// JobEvents: tells watchers that a job changed. Each job has a version that grows with
// every change; a watcher waits for the version to pass the one it has seen. The start of
// every stage is also kept (for the running jobs and the last finished ones), so that a
// watcher that was slow to wake still reports every stage, in order.
#ifndef SHEETMESH_SERVER_JOB_EVENTS_H_
#define SHEETMESH_SERVER_JOB_EVENTS_H_

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "absl/time/time.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::server {

// One change, as handed to a relay (another server's events, over PostgreSQL).
struct JobEvent {
  enum class Kind { kChanged, kStage, kFinished };
  Kind kind = Kind::kChanged;
  std::string job;
  v1::JobProgress progress;  // kStage: the stage that started
};

// Thread-safe.
class JobEvents {
 public:
  // Marks `job` changed and wakes its watchers.
  void Notify(const std::string& job);
  // Marks `job` changed by the start of a stage, described by `progress`.
  void NotifyStage(const std::string& job, const v1::JobProgress& progress);
  // Marks `job` finished: its stage log is kept for the next `kFinishedKept` finished jobs.
  void NotifyFinished(const std::string& job);
  // The job's current version.
  uint64_t Version(const std::string& job);
  // The stage starts recorded after version `seen`, oldest first.
  std::vector<v1::JobProgress> StagesSince(const std::string& job, uint64_t seen);
  // Waits until the job's version passes `seen`, or `timeout`, or Close(). Returns the
  // version then.
  uint64_t Wait(const std::string& job, uint64_t seen, absl::Duration timeout);
  // Wakes every watcher for good (shutdown).
  void Close();
  bool closed();
  // Called (outside the lock) after every change and at Close; one listener, or none.
  void SetListener(std::function<void()> listener);
  // Called (outside the lock) with every change made here (the Notify calls above), not
  // with those Apply brings in from elsewhere; one relay, or none.
  void SetRelay(std::function<void(const JobEvent&)> relay);
  // A change made elsewhere (another server's): as its Notify call, not relayed.
  void Apply(const JobEvent& event);

  static constexpr size_t kFinishedKept = 256;
  static constexpr size_t kStagesKept = 64;

 private:
  struct Entry {
    uint64_t version = 0;
    std::deque<std::pair<uint64_t, v1::JobProgress>> stages;  // (version, stage start)
  };
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<std::string, Entry> jobs_;
  std::deque<std::string> finished_;
  bool closed_ = false;
  std::function<void()> listener_;
  std::function<void(const JobEvent&)> relay_;

  // Marks the change; with `relay`, hands it to the relay too.
  void Record(const JobEvent& event, bool relay);
  void Changed();
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_EVENTS_H_
