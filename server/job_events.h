// JobEvents: tells watchers that a job changed. Each job has a version that grows with
// every change; a watcher waits for the version to pass the one it has seen.
#ifndef SHEETMESH_SERVER_JOB_EVENTS_H_
#define SHEETMESH_SERVER_JOB_EVENTS_H_

#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>

#include "absl/time/time.h"

namespace sheetmesh::server {

// Thread-safe.
class JobEvents {
 public:
  // Marks `job` changed and wakes its watchers.
  void Notify(const std::string& job);
  // The job's current version.
  uint64_t Version(const std::string& job);
  // Waits until the job's version passes `seen`, or `timeout`, or Close(). Returns the
  // version then.
  uint64_t Wait(const std::string& job, uint64_t seen, absl::Duration timeout);
  // Wakes every watcher for good (shutdown).
  void Close();
  bool closed();

 private:
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<std::string, uint64_t> versions_;
  bool closed_ = false;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_JOB_EVENTS_H_
