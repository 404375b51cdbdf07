#include "common/types.h"

#include "absl/strings/str_cat.h"

namespace sheetmesh {

std::string Dims::ToString() const { return absl::StrCat(nx, "x", ny, "x", nz); }

}  // namespace sheetmesh
