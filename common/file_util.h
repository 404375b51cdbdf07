// Small POSIX file helpers: an owned descriptor, full reads and writes, and a writer that
// makes a file appear atomically (write `.part`, fsync, rename) so that nobody ever sees a
// half-written output.
#ifndef SHEETMESH_COMMON_FILE_UTIL_H_
#define SHEETMESH_COMMON_FILE_UTIL_H_

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"

namespace sheetmesh {

// Owns a file descriptor; closes it on destruction. Movable, not copyable.
class ScopedFd {
 public:
  ScopedFd() = default;
  explicit ScopedFd(int fd) : fd_(fd) {}
  ScopedFd(ScopedFd&& o) noexcept : fd_(o.release()) {}
  ScopedFd& operator=(ScopedFd&& o) noexcept;
  ScopedFd(const ScopedFd&) = delete;
  ScopedFd& operator=(const ScopedFd&) = delete;
  ~ScopedFd();

  int get() const { return fd_; }
  bool valid() const { return fd_ >= 0; }
  int release() {
    const int fd = fd_;
    fd_ = -1;
    return fd;
  }

 private:
  int fd_ = -1;
};

// Opens `path` read-only. kNotFound / kPermissionDenied / kInvalidArgument (a directory)
// with the path and the system's reason.
absl::StatusOr<ScopedFd> OpenForRead(const std::string& path);
// Size in bytes of an open file.
absl::StatusOr<int64_t> FileSizeOf(int fd, const std::string& path);
// Reads exactly out.size() bytes at `offset`. kDataLoss if the file ends first.
absl::Status ReadFullyAt(int fd, int64_t offset, std::span<std::byte> out, const std::string& path);
// Writes all of `data` to `fd`.
absl::Status WriteFully(int fd, std::span<const std::byte> data, const std::string& path);
// Whole file as a string (for small files: headers, configs). kResourceExhausted above
// `max_bytes`.
absl::StatusOr<std::string> ReadFileToString(const std::string& path,
                                             int64_t max_bytes = int64_t{64} << 20);
// Creates `path` and its parents if missing.
absl::Status MakeDirs(const std::string& path);

// Writes a file that appears at its final path only when Commit() succeeds: data goes to
// `<path>.part`, is fsynced, then renamed over `path`. Destroying an uncommitted writer
// removes the `.part`. Not thread-safe.
class AtomicFileWriter {
 public:
  AtomicFileWriter() = default;
  AtomicFileWriter(AtomicFileWriter&&) = default;
  AtomicFileWriter& operator=(AtomicFileWriter&&) = default;
  ~AtomicFileWriter();

  // Starts writing `path` (through `path`.<pid>-<n>.part, so concurrent writers of one
  // path do not collide). kPermissionDenied / kNotFound (no parent folder) on failure.
  static absl::StatusOr<AtomicFileWriter> Create(const std::string& path);

  absl::Status Append(std::span<const std::byte> data);
  absl::Status Append(absl::string_view data) {
    return Append(std::as_bytes(std::span<const char>(data.data(), data.size())));
  }
  // Flushes, fsyncs, renames into place and fsyncs the folder.
  absl::Status Commit();

  const std::string& path() const { return path_; }
  int fd() const { return fd_.get(); }

 private:
  std::string path_;
  std::string part_path_;
  ScopedFd fd_;
  bool committed_ = false;
};

// Writes `data` to `path` atomically.
absl::Status WriteFileAtomically(const std::string& path, absl::string_view data);

// "path: <strerror(errno)>" as a Status with a code chosen from errno.
absl::Status ErrnoStatus(int err, absl::string_view what);

}  // namespace sheetmesh

#endif  // SHEETMESH_COMMON_FILE_UTIL_H_
