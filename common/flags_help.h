// The command lines of the programs: --help with their own flags and defaults (exit 0),
// --version (exit 0), and usage errors (an unknown flag, a bad value) that exit 2 naming the
// flag, as every other usage error does. (Abseil's --help looks for flags in a file named
// after the program, finds none in main.cc files, and exits 1; its parser exits 1 on an
// unknown flag.)
#ifndef SHEETMESH_COMMON_FLAGS_HELP_H_
#define SHEETMESH_COMMON_FLAGS_HELP_H_

#include <ostream>
#include <vector>

#include "absl/strings/string_view.h"

namespace sheetmesh {

// Whether the command line asks for help: --help, -help, -h or --helpfull.
bool WantsHelp(int argc, char** argv);

// Every flag defined in a file whose path ends in `file_suffix`, sorted by name:
// "  --name (default 'x')\n      help\n".
void PrintFlagsOf(absl::string_view file_suffix, std::ostream& out);

// Whether the command line asks for the version: --version.
bool WantsVersion(int argc, char** argv);

// "PROGRAM VERSION\n" on `out`.
void PrintVersion(absl::string_view program, std::ostream& out);

// absl::ParseCommandLine, after checking every flag names a defined flag and its value
// parses: otherwise prints "PROGRAM: ..." naming the flag and the value on stderr and exits
// with 2. Returns the positional arguments (argv[0] first).
std::vector<char*> ParseFlagsOrExit(int argc, char** argv, absl::string_view program);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_FLAGS_HELP_H_
