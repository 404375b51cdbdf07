// WorkerPool: N threads that lease jobs from a host, run them, keep their leases alive and
// report how they ended. The embedded server runs one in-process; sheetmesh-worker runs
// one against a remote server.
#ifndef SHEETMESH_WORKER_RUNTIME_WORKER_POOL_H_
#define SHEETMESH_WORKER_RUNTIME_WORKER_POOL_H_

#include <atomic>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "absl/time/time.h"
#include "worker/runtime/job_host.h"
#include "worker/runtime/job_runner.h"

namespace sheetmesh::runtime {

// How long running jobs may finish on SIGTERM, by default, before they go back to the queue
// (sheetmesh-server's and sheetmesh-worker's --drain_seconds).
inline constexpr absl::Duration kDefaultDrain = absl::Seconds(30);

struct WorkerPoolOptions {
  int workers = 0;                                      // threads (0: the number of cores)
  std::string name = "worker";                          // prefix of the workers' lease names
  JobRunOptions run;                                    // where and how each job runs
  absl::Duration renew_interval = absl::Seconds(5);     // lease renewal period
  absl::Duration lease_poll = absl::Milliseconds(500);  // Lease() wait per attempt
};

// A lease name unique among all workers over one job store: `prefix`, the host, the pid
// (containers all run as pid 1) and a random tail.
std::string UniqueWorkerName(const std::string& prefix);

// Thread-safe. Start() once; Drain() or Stop() before destruction.
class WorkerPool {
 public:
  WorkerPool(JobHost* host, WorkerPoolOptions options);
  ~WorkerPool();

  void Start();
  // Stops leasing; waits up to `timeout` for running jobs; jobs still running are then
  // stopped and released back to the queue (they run again later). Returns when all
  // threads have ended.
  void Drain(absl::Duration timeout);
  // Drain(0).
  void Stop() { Drain(absl::ZeroDuration()); }

  // Jobs running now.
  int busy() const { return busy_.load(); }
  int size() const { return static_cast<int>(threads_.size()); }

 private:
  void Work(int index);
  void Renew();

  JobHost* host_;
  WorkerPoolOptions options_;
  std::vector<std::thread> threads_;
  std::thread renewer_;
  std::atomic<bool> leasing_{true};
  std::atomic<bool> aborting_{false};
  std::atomic<int> busy_{0};
  std::mutex mu_;
  std::map<std::string, std::string> running_;  // job -> worker
  std::map<std::string, bool> lost_;            // job -> lease lost
  std::map<std::string, bool> cancelled_;       // job -> cancelled, heard at a renewal
  friend class PoolObserverHost;
};

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_WORKER_POOL_H_
