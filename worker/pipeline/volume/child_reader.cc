#include "worker/pipeline/volume/child_reader.h"

#include <poll.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "common/excerpt.h"
#include "common/status_macros.h"
#include "common/subprocess.h"

namespace sheetmesh {
namespace {

using Clock = std::chrono::steady_clock;
constexpr int kAnswerFd = 3;   // child -> parent
constexpr int kRequestFd = 4;  // parent -> child
constexpr uint32_t kMaxMessage = 1 << 20;

const char* LibraryOf(const std::string& format) {
  if (format == "vdb") return "OpenVDB";
  if (format == "hdf5") return "libhdf5";
  if (format == "dicom") return "GDCM";
  if (format == "png") return "libpng";
  if (format == "jpeg") return "libjpeg";
  if (format == "tiff") return "libtiff";
  return "the image libraries";
}

// Writes all of `data` to `fd`; false when the other end has gone.
bool WriteAll(int fd, const void* data, size_t n) {
  const char* p = static_cast<const char*>(data);
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return false;
    p += w;
    n -= static_cast<size_t>(w);
  }
  return true;
}

// Reads exactly `n` bytes from `fd`; false at its end or on an error.
bool ReadAll(int fd, void* data, size_t n) {
  char* p = static_cast<char*>(data);
  while (n > 0) {
    const ssize_t r = ::read(fd, p, n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return false;
    p += r;
    n -= static_cast<size_t>(r);
  }
  return true;
}

bool WriteStatus(int fd, const absl::Status& status) {
  const int32_t code = static_cast<int32_t>(status.code());
  const std::string message(status.message().substr(0, kMaxMessage));
  const uint32_t length = static_cast<uint32_t>(message.size());
  return WriteAll(fd, &code, 4) && WriteAll(fd, &length, 4) &&
         WriteAll(fd, message.data(), message.size());
}

nlohmann::json InfoToJson(const VolumeInfo& info) {
  const Placement& p = info.placement;
  return {{"path", info.path},
          {"format", info.format},
          {"dims", {info.dims.nx, info.dims.ny, info.dims.nz}},
          {"dtype", std::string(DTypeName(info.dtype))},
          {"spacing", {p.spacing.x, p.spacing.y, p.spacing.z}},
          {"origin", {p.origin.x, p.origin.y, p.origin.z}},
          {"unit", p.unit}};
}

absl::StatusOr<VolumeInfo> InfoFromJson(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  try {
    VolumeInfo info;
    info.path = j.at("path").get<std::string>();
    info.format = j.at("format").get<std::string>();
    const auto d = j.at("dims");
    info.dims = {d.at(0).get<int64_t>(), d.at(1).get<int64_t>(), d.at(2).get<int64_t>()};
    SM_ASSIGN_OR_RETURN(info.dtype, ParseDType(j.at("dtype").get<std::string>()));
    const auto s = j.at("spacing"), o = j.at("origin");
    info.placement.spacing = {s.at(0).get<double>(), s.at(1).get<double>(), s.at(2).get<double>()};
    info.placement.origin = {o.at(0).get<double>(), o.at(1).get<double>(), o.at(2).get<double>()};
    info.placement.unit = j.at("unit").get<std::string>();
    return info;
  } catch (const nlohmann::json::exception& e) {
    return absl::InternalError(absl::StrCat("a child reader's answer: ", Excerpt(e.what())));
  }
}

// The parent's side: slices asked of the child.
class ChildSource : public VolumeSource {
 public:
  ChildSource(Subprocess child, std::string path, std::string format, ChildReaderOptions options)
      : child_(std::move(child)),
        path_(std::move(path)),
        format_(std::move(format)),
        options_(std::move(options)) {}

  // Reads the child's answer to the opening.
  absl::Status Open() {
    const double seconds = OpenSeconds();
    SM_RETURN_IF_ERROR(Answer(seconds, "opening it"));
    uint32_t length = 0;
    const auto deadline = Deadline(seconds);
    SM_RETURN_IF_ERROR(Receive(&length, 4, deadline, "opening it"));
    if (length > kMaxMessage) return Broken("opening it");
    std::string text(length, '\0');
    SM_RETURN_IF_ERROR(Receive(text.data(), length, deadline, "opening it"));
    SM_ASSIGN_OR_RETURN(info_, InfoFromJson(text));
    return absl::OkStatus();
  }

  absl::Status ReadSlices(int64_t z0, int64_t count, std::span<std::byte> out) override {
    SM_RETURN_IF_ERROR(CheckSliceRequest(z0, count, out.size()));
    if (!failed_.ok()) return failed_;
    const std::string what = absl::StrCat("reading slices ", z0, "-", z0 + count - 1);
    const int64_t request[2] = {z0, count};
    if (!WriteAll(child_.request_fd(), request, sizeof(request))) return Died(what);
    const double seconds =
        options_.read_seconds + static_cast<double>(out.size()) / double(16 << 20);
    SM_RETURN_IF_ERROR(Answer(seconds, what));
    return Receive(out.data(), out.size(), Deadline(seconds), what);
  }

 private:
  // The time opening may take: by the file's size, or a folder's file count.
  double OpenSeconds() const {
    std::error_code ec;
    const std::string file = path_.substr(0, path_.find(".h5:"));  // "scan.h5:/data"
    double bytes = 0;
    if (std::filesystem::is_directory(path_, ec)) {
      for (auto it = std::filesystem::directory_iterator(path_, ec);
           !ec && it != std::filesystem::directory_iterator(); it.increment(ec)) {
        bytes += options_.open_bytes_per_second / 100;  // a hundred files a second
      }
    } else {
      const auto size = std::filesystem::file_size(file, ec);
      if (!ec) bytes = static_cast<double>(size);
    }
    return options_.open_seconds + bytes / options_.open_bytes_per_second;
  }

  static Clock::time_point Deadline(double seconds) {
    return Clock::now() + std::chrono::microseconds(static_cast<int64_t>(seconds * 1e6));
  }

  // A status the child sent: ok, or its reader's error as it was.
  absl::Status Answer(double seconds, const std::string& what) {
    const auto deadline = Deadline(seconds);
    int32_t code = 0;
    uint32_t length = 0;
    SM_RETURN_IF_ERROR(Receive(&code, 4, deadline, what));
    SM_RETURN_IF_ERROR(Receive(&length, 4, deadline, what));
    if (length > kMaxMessage) return Broken(what);
    std::string message(length, '\0');
    SM_RETURN_IF_ERROR(Receive(message.data(), length, deadline, what));
    if (code == 0) return absl::OkStatus();
    return absl::Status(static_cast<absl::StatusCode>(code), message);
  }

  absl::Status Receive(void* data, size_t n, Clock::time_point deadline, const std::string& what) {
    char* p = static_cast<char*>(data);
    while (n > 0) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) return TimedOut(what);
      struct pollfd pfd = {child_.report_fd(), POLLIN, 0};
      const int ready = ::poll(&pfd, 1, static_cast<int>(std::min<int64_t>(left, 1 << 30)));
      if (ready < 0 && errno == EINTR) continue;
      if (ready == 0) return TimedOut(what);
      const ssize_t r = ::read(child_.report_fd(), p, n);
      if (r < 0 && errno == EINTR) continue;
      if (r <= 0) return Died(what);
      p += r;
      n -= static_cast<size_t>(r);
    }
    return absl::OkStatus();
  }

  absl::Status Died(const std::string& what) {
    // The pipe ended: the child has ended or is ending; wait a little for its status.
    std::optional<ChildExit> exit;
    for (int i = 0; i < 200 && !(exit = child_.Poll()); ++i) ::usleep(10000);
    if (!exit) {
      child_.Kill();
      exit = child_.Wait();
    }
    return failed_ = absl::InvalidArgumentError(absl::StrCat(
        path_, ": its reader (", LibraryOf(format_), ", in a child process) ", exit->ToString(),
        " while ", what,
        ": the file is damaged, or meets a bug of that library (nothing else was harmed)"));
  }

  absl::Status TimedOut(const std::string& what) {
    child_.Kill();
    child_.Wait();
    return failed_ = absl::DeadlineExceededError(
               absl::StrCat(path_, ": its reader (", LibraryOf(format_),
                            ", in a child process) did not answer in time while ", what,
                            "; it was stopped: the file is damaged or far larger than it "
                            "looks"));
  }

  absl::Status Broken(const std::string& what) {
    child_.Kill();
    child_.Wait();
    return failed_ = absl::InternalError(
               absl::StrCat(path_, ": its child reader answered out of turn while ", what));
  }

  Subprocess child_;
  std::string path_;
  std::string format_;
  ChildReaderOptions options_;
  absl::Status failed_;
};

}  // namespace

bool ReadByLibrary(const std::string& format) {
  return format == "vdb" || format == "hdf5" || format == "dicom" || format == "png" ||
         format == "jpeg" || format == "tiff" || format == "folder";
}

absl::StatusOr<std::unique_ptr<VolumeSource>> OpenVolumeInChild(const std::string& path,
                                                                const std::string& format,
                                                                const std::string& vdb_grid,
                                                                const VolumeLimits& limits,
                                                                const ChildReaderOptions& options) {
  const int64_t budget = MemoryBudget(limits);
  const nlohmann::json spec = {
      {"path", path},
      {"format", format},
      {"vdb_grid", vdb_grid},
      {"max_voxels", limits.max_voxels},
      {"max_extent", limits.max_extent},
      {"memory_bytes", budget},
      {"confine_named_files", limits.confine_named_files},
      {"named_file_roots", limits.named_file_roots}};
  SubprocessOptions so;
  so.argv = {options.program, "_serve-volume", spec.dump()};
  so.report_pipe = true;
  so.request_pipe = true;
  so.memory_limit_bytes = static_cast<uint64_t>(budget + options.memory_slack);
  SM_ASSIGN_OR_RETURN(Subprocess child, Subprocess::Start(so));
  auto source = std::make_unique<ChildSource>(std::move(child), path, format, options);
  SM_RETURN_IF_ERROR(source->Open());
  return source;
}

absl::StatusOr<ChildReaderSpec> ParseChildReaderSpec(const std::string& text) {
  const nlohmann::json spec = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  ChildReaderSpec out;
  try {
    out.path = spec.at("path").get<std::string>();
    out.format = spec.at("format").get<std::string>();
    out.vdb_grid = spec.at("vdb_grid").get<std::string>();
    out.limits.max_voxels = spec.at("max_voxels").get<int64_t>();
    out.limits.max_extent = spec.at("max_extent").get<int64_t>();
    out.limits.memory_bytes = spec.at("memory_bytes").get<int64_t>();
    out.limits.confine_named_files = spec.at("confine_named_files").get<bool>();
    out.limits.named_file_roots = spec.at("named_file_roots").get<std::vector<std::string>>();
  } catch (const nlohmann::json::exception& e) {
    return absl::InvalidArgumentError(
        absl::StrCat("not a child reader's spec: ", Excerpt(e.what())));
  }
  return out;
}

absl::Status ServeVolume(absl::StatusOr<std::unique_ptr<VolumeSource>> source) {
  // A parent that has gone leaves writes failing, not this process killed.
  ::signal(SIGPIPE, SIG_IGN);
  const absl::Status gone = absl::AbortedError("the parent has gone");
  if (!WriteStatus(kAnswerFd, source.status())) return gone;
  if (!source.ok()) return source.status();
  const std::string info = InfoToJson((*source)->info()).dump();
  const uint32_t length = static_cast<uint32_t>(info.size());
  if (!WriteAll(kAnswerFd, &length, 4) || !WriteAll(kAnswerFd, info.data(), info.size())) {
    return gone;
  }
  const VolumeInfo& v = (*source)->info();
  const int64_t slice = v.dims.nx * v.dims.ny * BytesPerVoxel(v.dtype);
  std::vector<std::byte> buffer;
  int64_t request[2];
  while (ReadAll(kRequestFd, request, sizeof(request))) {
    const int64_t z0 = request[0], count = request[1];
    absl::Status status;
    if (z0 < 0 || count < 0 || z0 + count > v.dims.nz) {
      status = absl::InvalidArgumentError(absl::StrCat("slices ", z0, "+", count, " asked"));
    } else {
      buffer.resize(static_cast<size_t>(count * slice));
      status = (*source)->ReadSlices(z0, count, buffer);
    }
    if (!WriteStatus(kAnswerFd, status)) return gone;
    if (status.ok() && !WriteAll(kAnswerFd, buffer.data(), buffer.size())) return gone;
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh
