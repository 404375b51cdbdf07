// The job-limit flags every program that runs jobs takes (sheetmesh-server,
// sheetmesh-worker): --isolate_jobs, --job_memory_gb, --job_cpu_seconds and
// --job_time_limit_seconds, defined once here.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_LIMIT_FLAGS_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_LIMIT_FLAGS_H_

#include "worker/runtime/job_process.h"

namespace sheetmesh::runtime {

// The file that defines the flags, for a program's --help (PrintFlagsOf).
inline constexpr char kJobLimitFlagsFile[] = "worker/runtime/job_limit_flags.cc";

// The limits the flags set: memory (0: three quarters of the machine's), CPU time (0: none)
// and wall-clock time (at least a second).
JobLimits JobLimitsFromFlags();

// --isolate_jobs: each job's pipeline in a child process with those limits.
bool IsolateJobsFromFlags();

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_LIMIT_FLAGS_H_
