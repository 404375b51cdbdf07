#include "worker/runtime/job_limit_flags.h"

#include <algorithm>
#include <cstdint>

#include "absl/flags/flag.h"
#include "absl/time/time.h"
#include "worker/runtime/job_process.h"

ABSL_FLAG(bool, isolate_jobs, true,
          "run each job's pipeline in a child process with the limits below (false: in a "
          "worker thread)");
ABSL_FLAG(double, job_memory_gb, 0,
          "each job's memory limit, GiB (0: three quarters of the machine's memory)");
ABSL_FLAG(int64_t, job_cpu_seconds, sheetmesh::runtime::JobLimits().cpu_seconds,
          "each job's CPU time limit, seconds (0: none)");
ABSL_FLAG(int64_t, job_time_limit_seconds,
          absl::ToInt64Seconds(sheetmesh::runtime::JobLimits().wall),
          "each job's wall-clock limit, seconds");

namespace sheetmesh::runtime {

JobLimits JobLimitsFromFlags() {
  JobLimits limits;
  const double gb = absl::GetFlag(FLAGS_job_memory_gb);
  limits.memory_bytes =
      gb > 0 ? static_cast<uint64_t>(gb * double(uint64_t{1} << 30)) : DefaultJobMemory();
  limits.cpu_seconds =
      static_cast<uint64_t>(std::max<int64_t>(0, absl::GetFlag(FLAGS_job_cpu_seconds)));
  limits.wall = absl::Seconds(std::max<int64_t>(1, absl::GetFlag(FLAGS_job_time_limit_seconds)));
  return limits;
}

bool IsolateJobsFromFlags() { return absl::GetFlag(FLAGS_isolate_jobs); }

}  // namespace sheetmesh::runtime
