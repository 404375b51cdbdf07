#include "worker/runtime/sandbox.h"

#include <fcntl.h>
#include <linux/landlock.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"

// Debian 12's kernel headers (6.1) predate Landlock ABI 3; the kernel may have it.
#ifndef LANDLOCK_ACCESS_FS_TRUNCATE
#define LANDLOCK_ACCESS_FS_TRUNCATE (1ULL << 14)
#endif

namespace sheetmesh::runtime {
namespace {

constexpr uint64_t kRead = LANDLOCK_ACCESS_FS_READ_FILE | LANDLOCK_ACCESS_FS_READ_DIR;
constexpr uint64_t kExecute = LANDLOCK_ACCESS_FS_EXECUTE;
constexpr uint64_t kWrite = LANDLOCK_ACCESS_FS_WRITE_FILE | LANDLOCK_ACCESS_FS_REMOVE_DIR |
                            LANDLOCK_ACCESS_FS_REMOVE_FILE | LANDLOCK_ACCESS_FS_MAKE_DIR |
                            LANDLOCK_ACCESS_FS_MAKE_REG | LANDLOCK_ACCESS_FS_MAKE_SYM;
// Rights that only make sense on a folder; a rule on a file may hold only the others.
constexpr uint64_t kDirOnly =
    LANDLOCK_ACCESS_FS_READ_DIR | LANDLOCK_ACCESS_FS_REMOVE_DIR | LANDLOCK_ACCESS_FS_REMOVE_FILE |
    LANDLOCK_ACCESS_FS_MAKE_DIR | LANDLOCK_ACCESS_FS_MAKE_REG | LANDLOCK_ACCESS_FS_MAKE_SYM |
    LANDLOCK_ACCESS_FS_MAKE_CHAR | LANDLOCK_ACCESS_FS_MAKE_SOCK | LANDLOCK_ACCESS_FS_MAKE_FIFO |
    LANDLOCK_ACCESS_FS_MAKE_BLOCK | LANDLOCK_ACCESS_FS_REFER;

// Adds a rule granting `access` beneath `path` (within `handled`); a missing path is skipped.
absl::Status AddRule(int ruleset, const std::string& path, uint64_t access, uint64_t handled) {
  const int fd = ::open(path.c_str(), O_PATH | O_CLOEXEC);
  if (fd < 0) return absl::OkStatus();
  struct stat st;
  if (::fstat(fd, &st) == 0 && !S_ISDIR(st.st_mode)) access &= ~kDirOnly;
  struct landlock_path_beneath_attr rule = {};
  rule.allowed_access = access & handled;
  rule.parent_fd = fd;
  const long r = ::syscall(SYS_landlock_add_rule, ruleset, LANDLOCK_RULE_PATH_BENEATH, &rule, 0);
  const int err = errno;
  ::close(fd);
  if (r != 0) return ErrnoStatus(err, absl::StrCat("sandbox rule for ", path));
  return absl::OkStatus();
}

}  // namespace

absl::Status RestrictFilesystem(const SandboxPaths& paths) {
  const long abi =
      ::syscall(SYS_landlock_create_ruleset, nullptr, 0, LANDLOCK_CREATE_RULESET_VERSION);
  if (abi < 1) {
    return absl::UnimplementedError("the kernel has no Landlock: the job's files are not fenced");
  }
  uint64_t handled = kRead | kExecute | kWrite | LANDLOCK_ACCESS_FS_MAKE_CHAR |
                     LANDLOCK_ACCESS_FS_MAKE_SOCK | LANDLOCK_ACCESS_FS_MAKE_FIFO |
                     LANDLOCK_ACCESS_FS_MAKE_BLOCK;
  if (abi >= 2) handled |= LANDLOCK_ACCESS_FS_REFER;
  if (abi >= 3) handled |= LANDLOCK_ACCESS_FS_TRUNCATE;
  struct landlock_ruleset_attr attr = {};
  attr.handled_access_fs = handled;
  const int ruleset =
      static_cast<int>(::syscall(SYS_landlock_create_ruleset, &attr, sizeof(attr), 0));
  if (ruleset < 0) return ErrnoStatus(errno, "sandbox ruleset");
  absl::Status st;
  auto add = [&](const std::string& p, uint64_t access) {
    if (st.ok()) st = AddRule(ruleset, p, access, handled);
  };
  // The libraries and programs a job loads (TetGen's among them), and the data files of
  // libraries (/usr/share): no configuration, home or data folder. /lib, /lib64 and /bin are
  // links into /usr on current systems; a rule on a link holds for its target.
  for (const char* system :
       {"/usr/lib", "/usr/lib64", "/usr/lib32", "/usr/libexec", "/usr/bin", "/usr/share",
        "/usr/local/lib", "/usr/local/bin", "/lib", "/lib64", "/bin"}) {
    add(system, kRead | kExecute);
  }
  add("/etc/ld.so.cache", kRead);
  // Of /proc only this process's own entries (not its parent's environment nor anyone
  // else's) and the machine's size; of /sys the CPU topology the thread pools read.
  add(absl::StrCat("/proc/", ::getpid()), kRead);
  for (const char* machine : {"/proc/cpuinfo", "/proc/meminfo", "/proc/stat",
                              "/sys/devices/system/cpu", "/sys/fs/cgroup"}) {
    add(machine, kRead);
  }
  add("/dev/null", kRead | LANDLOCK_ACCESS_FS_WRITE_FILE);
  add("/dev/urandom", kRead);
  for (const std::string& p : paths.read) add(p, kRead);
  uint64_t rw = kRead | kWrite;
  if (abi >= 2) rw |= LANDLOCK_ACCESS_FS_REFER;
  if (abi >= 3) rw |= LANDLOCK_ACCESS_FS_TRUNCATE;
  for (const std::string& p : paths.read_write) add(p, rw);
  if (st.ok() && ::prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0) {
    st = ErrnoStatus(errno, "no_new_privs for the sandbox");
  }
  if (st.ok() && ::syscall(SYS_landlock_restrict_self, ruleset, 0) != 0) {
    st = ErrnoStatus(errno, "sandbox");
  }
  ::close(ruleset);
  if (!st.ok()) return absl::InternalError(st.message());
  return absl::OkStatus();
}

}  // namespace sheetmesh::runtime
