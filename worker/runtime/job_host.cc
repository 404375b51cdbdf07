#include "worker/runtime/job_host.h"

#include <filesystem>

namespace sheetmesh::runtime {

std::string InputFileName(const v1::JobInput& input) {
  if (input.file_name().empty()) return "volume.raw";
  const std::string name = std::filesystem::path(input.file_name()).filename().string();
  return name.empty() || name == "." || name == ".." ? "volume.raw" : name;
}

}  // namespace sheetmesh::runtime
