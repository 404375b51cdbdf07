// What a job's child can reach: only its input, its scratch folder and the libraries (the
// filesystem fence), and none of the server's environment (the clean environment). Each
// probe runs in a forked child, as jobs do, so the fence never closes on the test itself.
#include "worker/runtime/sandbox.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/subprocess.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh::runtime {
namespace {

using ::sheetmesh::testing::TempDir;

bool CanRead(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return false;
  char c;
  const bool ok = ::read(fd, &c, 1) >= 0;
  ::close(fd);
  return ok;
}

// Forks, fences the child to `paths`, and returns for each of `probes` whether the child
// could read it (the child's exit status carries one bit per probe).
std::vector<bool> ReadableInFence(const SandboxPaths& paths, const std::vector<std::string>& probes) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const absl::Status fenced = RestrictFilesystem(paths);
    if (absl::IsUnimplemented(fenced)) ::_exit(255);  // no Landlock here
    if (!fenced.ok()) ::_exit(254);
    int bits = 0;
    for (size_t i = 0; i < probes.size(); ++i) bits |= CanRead(probes[i]) ? 1 << i : 0;
    ::_exit(bits);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : 253;
  if (code == 255) return {};
  EXPECT_NE(code, 254) << "the fence could not be made";
  std::vector<bool> out;
  for (size_t i = 0; i < probes.size(); ++i) out.push_back((code >> i) & 1);
  return out;
}

TEST(SandboxTest, AJobReadsItsInputAndScratchAndNothingOfTheServer) {
  TempDir tmp;
  const std::string input = tmp.File("input.raw");
  const std::string scratch = tmp.File("scratch/job-1");
  const std::string other = tmp.File("scratch/job-2");
  const std::string db = tmp.File("jobs.db");
  std::filesystem::create_directories(scratch);
  std::filesystem::create_directories(other);
  for (const std::string& f : {input, db, other + "/surface.ply", scratch + "/own.txt"}) {
    std::ofstream(f) << "x";
  }
  SandboxPaths paths;
  paths.read = {input};
  paths.read_write = {scratch};
  const std::vector<std::string> probes = {
      input,                                  // 0: its input
      scratch + "/own.txt",                   // 1: its scratch
      "/usr/lib/os-release",                  // 2: the system's files it loads
      "/proc/self/status",                    // 3: its own /proc entry
      "/etc/passwd",                          // 4: the system's configuration
      absl::StrCat("/proc/", ::getpid(), "/environ"),  // 5: the server's environment
      db,                                     // 6: the data folder's job store
      other + "/surface.ply",                 // 7: another job's scratch
      "/proc/1/environ",                      // 8: anyone else's environment
  };
  const std::vector<bool> readable = ReadableInFence(paths, probes);
  if (readable.empty()) GTEST_SKIP() << "the kernel has no Landlock: the fence cannot be tested";
  const std::vector<bool> want = {true, true, true, true, false, false, false, false, false};
  for (size_t i = 0; i < probes.size(); ++i) {
    EXPECT_EQ(readable[i], want[i]) << probes[i];
  }
}

TEST(SandboxTest, AJobChildSeesNoneOfTheServersEnvironment) {
  ASSERT_EQ(::setenv("PGPASSWORD", "server-secret-123", 1), 0);
  ASSERT_EQ(::setenv("SHEETMESH_TOKEN", "tenant-token-456", 1), 0);
  TempDir tmp;
  SubprocessOptions o;
  o.argv = {"/usr/bin/env"};
  o.output_path = tmp.File("env.txt");
  o.env = {{"TMPDIR", tmp.path()}};
  o.clean_env = true;
  o.keep_env = {"PATH"};
  auto child = Subprocess::Start(o);
  ASSERT_TRUE(child.ok()) << child.status();
  ASSERT_EQ(child->Wait().code, 0);
  const std::string env = *ReadFileToString(tmp.File("env.txt"));
  EXPECT_EQ(env.find("server-secret-123"), std::string::npos) << env;
  EXPECT_EQ(env.find("tenant-token-456"), std::string::npos) << env;
  EXPECT_NE(env.find("TMPDIR="), std::string::npos) << env;
  EXPECT_NE(env.find("PATH="), std::string::npos) << env;
  ::unsetenv("PGPASSWORD");
  ::unsetenv("SHEETMESH_TOKEN");
}

}  // namespace
}  // namespace sheetmesh::runtime
