// --help for the three programs: their own flags with defaults and help, exit 0. (Abseil's
// --help looks for flags in a file named after the program, finds none in main.cc files,
// and exits 1.)
#ifndef SHEETMESH_COMMON_FLAGS_HELP_H_
#define SHEETMESH_COMMON_FLAGS_HELP_H_

#include <ostream>

#include "absl/strings/string_view.h"

namespace sheetmesh {

// Whether the command line asks for help: --help, -help, -h or --helpfull.
bool WantsHelp(int argc, char** argv);

// Every flag defined in a file whose path ends in `file_suffix`, sorted by name:
// "  --name (default 'x')\n      help\n".
void PrintFlagsOf(absl::string_view file_suffix, std::ostream& out);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_FLAGS_HELP_H_
