// Running the Debian Python (/usr/bin/python3) from a test to read a file back with another
// library (meshio, netCDF4, VTK).
#ifndef SHEETMESH_TESTS_TESTING_PYTHON_H_
#define SHEETMESH_TESTS_TESTING_PYTHON_H_

#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <optional>
#include <string>

namespace sheetmesh::testing {

// Runs /usr/bin/python3 on `script` (no single quotes in it); returns the last line it prints
// (libraries may print notices first), or nullopt when `module` does not import.
inline std::optional<std::string> Python(const std::string& script,
                                         const std::string& module = "meshio") {
  if (std::system(("/usr/bin/python3 -c 'import " + module + "' >/dev/null 2>&1").c_str()) != 0) {
    return std::nullopt;
  }
  std::string out;
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(
      popen(("/usr/bin/python3 -W ignore -c '" + script + "'").c_str(), "r"), pclose);
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), pipe.get()) != nullptr) {
    if (std::string(buf.data()) != "\n") out = buf.data();
  }
  return out;
}

}  // namespace sheetmesh::testing

#endif  // SHEETMESH_TESTS_TESTING_PYTHON_H_
