// Sandbox: closes the filesystem to this process but for the paths a job needs, with the
// kernel's Landlock (Linux 5.13 and later). The restriction is for good: it holds for the
// rest of the process and every child it starts. Used by the job child only.
#ifndef SHEETMESH_WORKER_RUNTIME_SANDBOX_H_
#define SHEETMESH_WORKER_RUNTIME_SANDBOX_H_

#include <string>
#include <vector>

#include "absl/status/status.h"

namespace sheetmesh::runtime {

struct SandboxPaths {
  std::vector<std::string> read;        // files or folders it may read (and list)
  std::vector<std::string> read_write;  // folders it may read, write and make files in
};

// Restricts this process to `paths` plus the system's programs, libraries and their data
// (/usr/lib*, /usr/bin, /usr/share, /etc/ld.so.cache), its own /proc entry, the machine's size
// (/proc/cpuinfo, meminfo, stat; /sys CPU topology and cgroup), /dev/null and /dev/urandom. kUnimplemented when the kernel has no
// Landlock (the caller decides whether to go on without); kInternal when a rule could not
// be made. Paths that do not exist are left out.
absl::Status RestrictFilesystem(const SandboxPaths& paths);

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_SANDBOX_H_
