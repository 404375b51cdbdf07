#include "worker/runtime/job_host.h"

#include <filesystem>
#include <set>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh::runtime {

std::string InputFileName(const v1::JobInput& input) {
  if (input.file_name().empty()) return "volume.raw";
  const std::string name = std::filesystem::path(input.file_name()).filename().string();
  return name.empty() || name == "." || name == ".." ? "volume.raw" : name;
}

std::string InputFolderName(const v1::JobInput& input) {
  const std::string name = std::filesystem::path(input.file_name()).filename().string();
  return name.empty() || name == "." || name == ".." ? "volume" : name;
}

absl::Status CheckVolumeFiles(const v1::VolumeFiles& files, const std::string& field) {
  if (files.files_size() == 0) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".files is empty"));
  }
  if (files.files_size() > kMaxVolumeFiles) {
    return absl::InvalidArgumentError(absl::StrCat(field, ".files has ", files.files_size(),
                                                   " entries; at most ", kMaxVolumeFiles));
  }
  std::set<std::string> names;
  for (int i = 0; i < files.files_size(); ++i) {
    const std::string& n = files.files(i).name();
    const std::string where = absl::StrCat(field, ".files[", i, "].name '", n, "'");
    bool plain = !n.empty() && n.size() <= 4096 && n[0] != '/' && n.find('\0') == std::string::npos;
    if (plain) {
      for (absl::string_view part : absl::StrSplit(n, '/')) {
        if (part.empty() || part == "." || part == ".." || part.size() > 255) plain = false;
      }
    }
    if (!plain) {
      return absl::InvalidArgumentError(absl::StrCat(
          where, " must be a relative path of plain names (like slice_0001.tif or data/a.raw)"));
    }
    if (!names.insert(n).second) {
      return absl::InvalidArgumentError(absl::StrCat(where, " is given twice"));
    }
  }
  // A name that is also another's folder ("a" and "a/b") cannot be laid out.
  for (const std::string& n : names) {
    auto it = names.lower_bound(n + "/");
    if (it != names.end() && it->rfind(n + "/", 0) == 0) {
      return absl::InvalidArgumentError(
          absl::StrCat(field, ": '", n, "' is both a file and the folder of '", *it, "'"));
    }
  }
  if (!files.main().empty() && names.count(files.main()) == 0) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ".main '", files.main(), "' is not one of the files"));
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> LayOutVolumeFiles(
    const v1::VolumeFiles& files, const std::string& dir,
    const std::function<absl::Status(const v1::Digest&, const std::string&)>& place) {
  SM_RETURN_IF_ERROR(CheckVolumeFiles(files, "input.volume_files"));
  SM_RETURN_IF_ERROR(MakeDirs(dir));
  for (const v1::VolumeFiles::File& f : files.files()) {
    const std::filesystem::path path = std::filesystem::path(dir) / f.name();
    if (path.has_parent_path() && path.parent_path() != std::filesystem::path(dir)) {
      SM_RETURN_IF_ERROR(MakeDirs(path.parent_path().string()));
    }
    SM_RETURN_IF_ERROR(place(f.digest(), path.string()));
  }
  return files.main().empty() ? dir : (std::filesystem::path(dir) / files.main()).string();
}

}  // namespace sheetmesh::runtime
