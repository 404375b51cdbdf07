// Subprocess: a child program run with limits — its own process group, killed with its
// parent, an address-space and a CPU limit, its output to a file, and optionally a pipe back
// to the parent on fd 3 and one from it on fd 4. TetGen and the isolated job runner are started this way.
#ifndef SHEETMESH_COMMON_SUBPROCESS_H_
#define SHEETMESH_COMMON_SUBPROCESS_H_

#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace sheetmesh {

struct SubprocessOptions {
  std::vector<std::string> argv;    // argv[0] is the program's path
  std::string output_path;          // stdout and stderr go here ("" = /dev/null)
  uint64_t memory_limit_bytes = 0;  // RLIMIT_AS; 0 = none
  uint64_t cpu_limit_seconds = 0;   // RLIMIT_CPU (SIGXCPU, then SIGKILL); 0 = none
  bool report_pipe = false;         // a pipe the child writes on fd 3 (report_fd())
  bool request_pipe = false;        // a pipe the child reads on fd 4 (request_fd())
  std::vector<std::pair<std::string, std::string>> env;  // set in the child's environment
  // With clean_env the child sees only `env` and the variables named in keep_env, not this
  // process's environment (which may hold secrets: a database password, tokens).
  bool clean_env = false;
  std::vector<std::string> keep_env;
};

// How a child ended, from waitpid's status.
struct ChildExit {
  bool signaled = false;
  int code = 0;                  // exit code, or the signal
  std::string ToString() const;  // "exited with code 3", "killed by SIGBUS (signal 7, Bus error)"
};

// Owns a running child: the destructor kills (its process group) and reaps it if it still
// runs. Movable, not copyable. Not thread-safe.
class Subprocess {
 public:
  // Starts the child. kNotFound when the program is not executable; kInternal when fork or
  // pipe fail. The child dies with this process (PR_SET_PDEATHSIG) and leads its own
  // process group, so Kill() takes its children too.
  static absl::StatusOr<Subprocess> Start(const SubprocessOptions& options);

  Subprocess(Subprocess&& other) noexcept;
  Subprocess& operator=(Subprocess&& other) noexcept;
  Subprocess(const Subprocess&) = delete;
  Subprocess& operator=(const Subprocess&) = delete;
  ~Subprocess();

  pid_t pid() const { return pid_; }
  // The read end of the report pipe (-1 without one); closed with this object.
  int report_fd() const { return report_fd_; }
  // The write end of the request pipe (-1 without one); closed with this object.
  int request_fd() const { return request_fd_; }
  // The exit once the child has ended, nullopt while it runs. Never blocks.
  std::optional<ChildExit> Poll();
  // Waits for the end.
  ChildExit Wait();
  // SIGKILL to the child's process group (the child and what it started).
  void Kill();

 private:
  Subprocess() = default;
  void Release();

  pid_t pid_ = -1;
  int report_fd_ = -1;
  int request_fd_ = -1;
  std::optional<ChildExit> exit_;
};

// The absolute path of `program`, searched on PATH when it has no slash. kNotFound naming
// it otherwise.
absl::StatusOr<std::string> FindProgram(const std::string& program);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_SUBPROCESS_H_
