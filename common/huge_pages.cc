#include "common/huge_pages.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <string>
#include <vector>

namespace sheetmesh {

void UseTransparentHugePages(int argc, char** argv, int max_arenas) {
  (void)argc;
  if (getenv("SHEETMESH_NO_HUGE_PAGES") != nullptr) return;
  const char* current = getenv("GLIBC_TUNABLES");
  if (current != nullptr && strstr(current, "glibc.malloc.hugetlb") != nullptr) return;
  std::string tunables = "glibc.malloc.hugetlb=1";
  std::vector<std::string> wanted = {"glibc.malloc.mmap_threshold=67108864",
                                     "glibc.malloc.trim_threshold=268435456"};
  if (max_arenas > 0) wanted.push_back("glibc.malloc.arena_max=" + std::to_string(max_arenas));
  for (const std::string& t : wanted) {
    const std::string name = t.substr(0, t.find('='));
    if (current == nullptr || strstr(current, name.c_str()) == nullptr) tunables += ":" + t;
  }
  if (current != nullptr && current[0] != '\0') tunables = std::string(current) + ":" + tunables;
  setenv("GLIBC_TUNABLES", tunables.c_str(), 1);
  execv("/proc/self/exe", argv);
  // The exec failed (no /proc?): carry on without huge pages. Unset the variable so that
  // child processes are not surprised by it.
  if (current == nullptr) unsetenv("GLIBC_TUNABLES");
}

}  // namespace sheetmesh
