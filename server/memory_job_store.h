// An in-memory JobStore with a clock the caller gives: for unit tests of the layers above
// the store, and for tests of leases that should not wait for real time to pass. The jobs
// live in MemoryJobTables, which outlive any store opened on them as a database file
// outlives its process: opening a second store on the same tables is a restart, or
// another replica.
#ifndef SHEETMESH_SERVER_MEMORY_JOB_STORE_H_
#define SHEETMESH_SERVER_MEMORY_JOB_STORE_H_

#include <functional>
#include <memory>
#include <mutex>

#include "absl/time/time.h"
#include "server/job_store.h"

namespace sheetmesh::server {

struct MemoryJobTables;

// Empty tables.
std::shared_ptr<MemoryJobTables> NewMemoryJobTables();

// What time it is for a store: absl::Now, or a test's clock.
using StoreClock = std::function<absl::Time()>;

// A store over `tables` (thread-safe, as every JobStore; stores on the same tables share
// one lock). Leases end, and times are stamped, by `clock`.
std::unique_ptr<JobStore> OpenMemoryJobStore(std::shared_ptr<MemoryJobTables> tables,
                                             StoreClock clock = &absl::Now);

// A clock that stands still until advanced, for tests. Thread-safe.
class ManualClock {
 public:
  explicit ManualClock(absl::Time start = absl::FromUnixSeconds(1767225600)) : now_(start) {}
  absl::Time Now() const;
  void Advance(absl::Duration d);
  // The clock as a StoreClock (this object must outlive the stores that use it).
  StoreClock AsStoreClock() {
    return [this] { return Now(); };
  }

 private:
  mutable std::mutex mu_;
  absl::Time now_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_MEMORY_JOB_STORE_H_
