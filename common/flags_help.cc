#include "common/flags_help.h"

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "absl/flags/commandlineflag.h"
#include "absl/flags/parse.h"
#include "absl/flags/reflection.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "common/version.h"

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

bool WantsVersion(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const absl::string_view a = argv[i];
    if (a == "--") break;
    if (a == "--version" || a == "-version") return true;
  }
  return false;
}

void PrintVersion(absl::string_view program, std::ostream& out) {
  out << program << " " << SHEETMESH_VERSION << "\n";
}

std::vector<char*> ParseFlagsOrExit(int argc, char** argv, absl::string_view program) {
  auto fail = [&](const std::string& why) {
    std::cerr << program << ": " << why << " (" << program << " --help lists the flags)\n";
    std::exit(2);
  };
  for (int i = 1; i < argc; ++i) {
    absl::string_view a = argv[i];
    if (a == "--") break;
    if (a.size() < 2 || a[0] != '-' || a == "-") continue;  // positional
    a.remove_prefix(a[1] == '-' ? 2 : 1);
    const size_t eq = a.find('=');
    const std::string name(a.substr(0, eq));
    absl::CommandLineFlag* flag = absl::FindCommandLineFlag(name);
    bool negated = false;
    if (flag == nullptr && absl::StartsWith(name, "no")) {
      flag = absl::FindCommandLineFlag(name.substr(2));
      negated = flag != nullptr;
    }
    if (flag == nullptr) fail(absl::StrCat("unknown flag --", name));
    const bool boolean = flag->IsOfType<bool>();
    if (negated && (!boolean || eq != absl::string_view::npos)) {
      fail(absl::StrCat("--", name, ": --no only negates a boolean flag, without a value"));
    }
    std::string value;
    if (eq != absl::string_view::npos) {
      value = std::string(a.substr(eq + 1));
    } else if (boolean) {
      continue;
    } else if (i + 1 < argc) {
      value = argv[++i];  // --flag value
    } else {
      fail(absl::StrCat("--", name, " needs a value"));
    }
    std::string error;
    if (!flag->ParseFrom(value, &error)) {
      fail(absl::StrCat("--", name, "=", value, ": ", error));
    }
  }
  return absl::ParseCommandLine(argc, argv);
}

}  // namespace sheetmesh
