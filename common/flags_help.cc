#include "common/flags_help.h"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "absl/flags/reflection.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"

namespace sheetmesh {

bool WantsHelp(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const absl::string_view a = argv[i];
    if (a == "--") break;
    if (a == "--help" || a == "-help" || a == "-h" || a == "--helpfull") return true;
  }
  return false;
}

void PrintFlagsOf(absl::string_view file_suffix, std::ostream& out) {
  std::vector<std::pair<std::string, std::string>> own;
  for (const auto& [name, flag] : absl::GetAllFlags()) {
    if (!absl::EndsWith(flag->Filename(), file_suffix)) continue;
    own.emplace_back(std::string(name),
                     absl::StrCat("  --", name, " (default '", flag->DefaultValue(), "')\n      ",
                                  flag->Help(), "\n"));
  }
  std::sort(own.begin(), own.end());
  for (const auto& [_, text] : own) out << text;
}

}  // namespace sheetmesh
