// Start-up tuning for processes that hold large arrays: ask glibc's malloc for transparent
// huge pages. On virtual machines page faults cost more than the work on sparse voxels.
#ifndef SHEETMESH_WORKER_PIPELINE_CORE_HUGE_PAGES_H_
#define SHEETMESH_WORKER_PIPELINE_CORE_HUGE_PAGES_H_

namespace sheetmesh {

// If the environment does not set glibc.malloc.hugetlb yet, sets it to 1 and re-executes
// the program with the same arguments (glibc reads tunables only at start-up). Returns
// normally when nothing needs doing, when SHEETMESH_NO_HUGE_PAGES is set, or when the
// re-exec fails. Call first thing in main(), before any thread starts.
void UseTransparentHugePages(int argc, char** argv);

}  // namespace sheetmesh

#endif  // SHEETMESH_WORKER_PIPELINE_CORE_HUGE_PAGES_H_
