#include "common/subprocess.h"

#include <fcntl.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"

namespace sheetmesh {
namespace {

ChildExit FromStatus(int status) {
  ChildExit e;
  if (WIFSIGNALED(status)) {
    e.signaled = true;
    e.code = WTERMSIG(status);
  } else {
    e.code = WEXITSTATUS(status);
  }
  return e;
}

}  // namespace

std::string ChildExit::ToString() const {
  if (signaled) {
    const char* abbrev = sigabbrev_np(code);
    return absl::StrCat("killed by ", abbrev ? absl::StrCat("SIG", abbrev) : "a signal",
                        " (signal ", code, ", ", strsignal(code), ")");
  }
  return absl::StrCat("exited with code ", code);
}

absl::StatusOr<std::string> FindProgram(const std::string& program) {
  if (program.find('/') != std::string::npos) {
    if (::access(program.c_str(), X_OK) == 0) return program;
    return absl::NotFoundError(absl::StrCat("program '", program, "' is not executable"));
  }
  const char* path = getenv("PATH");
  for (absl::string_view dir :
       absl::StrSplit(path ? path : "/usr/bin:/bin", ':', absl::SkipEmpty())) {
    const std::string candidate = absl::StrCat(dir, "/", program);
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return absl::NotFoundError(absl::StrCat("program '", program, "' was not found on PATH"));
}

absl::StatusOr<Subprocess> Subprocess::Start(const SubprocessOptions& o) {
  if (o.argv.empty()) return absl::InvalidArgumentError("a subprocess needs a program");
  if (::access(o.argv[0].c_str(), X_OK) != 0) {
    return absl::NotFoundError(absl::StrCat("program '", o.argv[0], "' is not executable"));
  }
  // Everything the child needs is made before fork: after it, only async-signal-safe calls
  // until exec.
  const std::string out_path = o.output_path.empty() ? "/dev/null" : o.output_path;
  const int out = ::open(out_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (out < 0) return ErrnoStatus(errno, out_path);
  int pipe_fds[2] = {-1, -1};
  int request_fds[2] = {-1, -1};
  if ((o.report_pipe && ::pipe2(pipe_fds, O_CLOEXEC) != 0) ||
      (o.request_pipe && ::pipe2(request_fds, O_CLOEXEC) != 0)) {
    const int err = errno;
    ::close(out);
    for (int fd : {pipe_fds[0], pipe_fds[1], request_fds[0], request_fds[1]}) {
      if (fd >= 0) ::close(fd);
    }
    return ErrnoStatus(err, "pipe for a subprocess");
  }
  std::vector<std::string> args = o.argv;
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> env_strings;
  for (char** e = environ; *e != nullptr; ++e) {
    bool replaced = false;
    for (const auto& [k, _] : o.env) replaced |= absl::StartsWith(*e, k + "=");
    bool kept = !o.clean_env;
    for (const std::string& k : o.keep_env) kept |= absl::StartsWith(*e, k + "=");
    if (!replaced && kept) env_strings.emplace_back(*e);
  }
  for (const auto& [k, v] : o.env) env_strings.push_back(k + "=" + v);
  std::vector<char*> envp;
  for (std::string& e : env_strings) envp.push_back(e.data());
  envp.push_back(nullptr);
  struct rlimit mem, cpu;
  mem.rlim_cur = mem.rlim_max = o.memory_limit_bytes;
  cpu.rlim_cur = o.cpu_limit_seconds;
  cpu.rlim_max = o.cpu_limit_seconds + 5;  // SIGXCPU first, SIGKILL a little later
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(out);
    for (int fd : {pipe_fds[0], pipe_fds[1], request_fds[0], request_fds[1]}) {
      if (fd >= 0) ::close(fd);
    }
    return ErrnoStatus(err, "fork");
  }
  if (pid == 0) {
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(126);  // the parent died before the line above
    ::dup2(out, 1);
    ::dup2(out, 2);
    if (pipe_fds[1] >= 0) ::dup2(pipe_fds[1], 3);  // dup2 clears FD_CLOEXEC
    if (request_fds[0] >= 0) ::dup2(request_fds[0], 4);
    if (o.memory_limit_bytes > 0) ::setrlimit(RLIMIT_AS, &mem);
    if (o.cpu_limit_seconds > 0) ::setrlimit(RLIMIT_CPU, &cpu);
    ::execve(argv[0], argv.data(), envp.data());
    ::_exit(127);
  }
  ::close(out);
  Subprocess s;
  s.pid_ = pid;
  if (pipe_fds[0] >= 0) {
    ::close(pipe_fds[1]);
    s.report_fd_ = pipe_fds[0];
  }
  if (request_fds[1] >= 0) {
    ::close(request_fds[0]);
    s.request_fd_ = request_fds[1];
  }
  return s;
}

Subprocess::Subprocess(Subprocess&& o) noexcept
    : pid_(o.pid_), report_fd_(o.report_fd_), request_fd_(o.request_fd_), exit_(o.exit_) {
  o.pid_ = -1;
  o.report_fd_ = -1;
  o.request_fd_ = -1;
}

Subprocess& Subprocess::operator=(Subprocess&& o) noexcept {
  if (this != &o) {
    Release();
    pid_ = o.pid_;
    report_fd_ = o.report_fd_;
    request_fd_ = o.request_fd_;
    exit_ = o.exit_;
    o.pid_ = -1;
    o.report_fd_ = -1;
    o.request_fd_ = -1;
  }
  return *this;
}

Subprocess::~Subprocess() { Release(); }

void Subprocess::Release() {
  if (pid_ > 0 && !exit_) {
    Kill();
    Wait();
  }
  if (report_fd_ >= 0) ::close(report_fd_);
  if (request_fd_ >= 0) ::close(request_fd_);
  pid_ = -1;
  report_fd_ = -1;
  request_fd_ = -1;
}

std::optional<ChildExit> Subprocess::Poll() {
  if (exit_ || pid_ <= 0) return exit_;
  int status = 0;
  const pid_t r = ::waitpid(pid_, &status, WNOHANG);
  if (r == pid_) exit_ = FromStatus(status);
  return exit_;
}

ChildExit Subprocess::Wait() {
  while (!exit_ && pid_ > 0) {
    int status = 0;
    const pid_t r = ::waitpid(pid_, &status, 0);
    if (r == pid_) {
      exit_ = FromStatus(status);
    } else if (r < 0 && errno != EINTR) {
      exit_ = ChildExit{true, SIGKILL};  // lost: treat as killed
    }
  }
  return exit_.value_or(ChildExit{});
}

void Subprocess::Kill() {
  if (pid_ > 0 && !exit_) {
    ::kill(-pid_, SIGKILL);
    ::kill(pid_, SIGKILL);
  }
}

}  // namespace sheetmesh
