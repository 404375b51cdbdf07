#include "common/file_util.h"

#include <errno.h>
#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <filesystem>

#include "absl/strings/str_cat.h"

namespace sheetmesh {

ScopedFd& ScopedFd::operator=(ScopedFd&& o) noexcept {
  if (this != &o) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = o.release();
  }
  return *this;
}

ScopedFd::~ScopedFd() {
  if (fd_ >= 0) ::close(fd_);
}

absl::Status ErrnoStatus(int err, absl::string_view what) {
  const std::string msg = absl::StrCat(what, ": ", strerror(err));
  switch (err) {
    case ENOENT:
    case ENOTDIR:
      return absl::NotFoundError(msg);
    case EACCES:
    case EPERM:
      return absl::PermissionDeniedError(msg);
    case ENOSPC:
    case EDQUOT:
    case ENOMEM:
    case EMFILE:
      return absl::ResourceExhaustedError(msg);
    case EISDIR:
    case EINVAL:
      return absl::InvalidArgumentError(msg);
    default:
      return absl::InternalError(msg);
  }
}

absl::StatusOr<ScopedFd> OpenForRead(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return ErrnoStatus(errno, path);
  ScopedFd owned(fd);
  struct stat st;
  if (::fstat(fd, &st) != 0) return ErrnoStatus(errno, path);
  if (S_ISDIR(st.st_mode)) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": is a folder, not a file"));
  }
  return owned;
}

absl::StatusOr<int64_t> FileSizeOf(int fd, const std::string& path) {
  struct stat st;
  if (::fstat(fd, &st) != 0) return ErrnoStatus(errno, path);
  return static_cast<int64_t>(st.st_size);
}

absl::Status ReadFullyAt(int fd, int64_t offset, std::span<std::byte> out,
                         const std::string& path) {
  size_t done = 0;
  while (done < out.size()) {
    const ssize_t n = ::pread(fd, out.data() + done, out.size() - done, offset + done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return ErrnoStatus(errno, path);
    }
    if (n == 0) {
      return absl::DataLossError(absl::StrCat(path, ": file ends at byte ", offset + done, " but ",
                                              out.size() - done, " more bytes were expected"));
    }
    done += static_cast<size_t>(n);
  }
  return absl::OkStatus();
}

absl::Status WriteFully(int fd, std::span<const std::byte> data, const std::string& path) {
  size_t done = 0;
  while (done < data.size()) {
    const ssize_t n = ::write(fd, data.data() + done, data.size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      return ErrnoStatus(errno, path);
    }
    done += static_cast<size_t>(n);
  }
  return absl::OkStatus();
}

absl::StatusOr<std::string> ReadFileToString(const std::string& path, int64_t max_bytes) {
  auto fd = OpenForRead(path);
  if (!fd.ok()) return fd.status();
  auto size = FileSizeOf(fd->get(), path);
  if (!size.ok()) return size.status();
  if (*size > max_bytes) {
    return absl::ResourceExhaustedError(
        absl::StrCat(path, ": ", *size, " bytes, above the limit of ", max_bytes));
  }
  std::string out(static_cast<size_t>(*size), '\0');
  absl::Status st = ReadFullyAt(fd->get(), 0, std::as_writable_bytes(std::span<char>(out)), path);
  if (!st.ok()) return st;
  return out;
}

absl::Status MakeDirs(const std::string& path) {
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) return ErrnoStatus(ec.value(), path);
  return absl::OkStatus();
}

AtomicFileWriter::~AtomicFileWriter() {
  if (fd_.valid() && !committed_) {
    fd_ = ScopedFd();
    ::unlink(part_path_.c_str());
  }
}

absl::StatusOr<AtomicFileWriter> AtomicFileWriter::Create(const std::string& path) {
  AtomicFileWriter w;
  w.path_ = path;
  // A name of its own, so that writers of the same path (two jobs storing one artifact)
  // never share a part file; the last rename wins with complete contents either way.
  static std::atomic<uint64_t> counter{0};
  w.part_path_ = absl::StrCat(path, ".", ::getpid(), "-", counter.fetch_add(1), ".part");
  const int fd = ::open(w.part_path_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd < 0) return ErrnoStatus(errno, w.part_path_);
  w.fd_ = ScopedFd(fd);
  return w;
}

absl::Status AtomicFileWriter::Append(std::span<const std::byte> data) {
  if (!fd_.valid()) return absl::FailedPreconditionError(path_ + ": writer is not open");
  return WriteFully(fd_.get(), data, part_path_);
}

absl::Status AtomicFileWriter::Commit() {
  if (!fd_.valid()) return absl::FailedPreconditionError(path_ + ": writer is not open");
  if (::fsync(fd_.get()) != 0) return ErrnoStatus(errno, part_path_);
  if (::close(fd_.release()) != 0) return ErrnoStatus(errno, part_path_);
  if (::rename(part_path_.c_str(), path_.c_str()) != 0) {
    const int err = errno;
    ::unlink(part_path_.c_str());
    return ErrnoStatus(err, path_);
  }
  committed_ = true;
  // The rename is durable only once the folder entry is on disk.
  const std::string dir = std::filesystem::path(path_).parent_path().string();
  const int dfd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dfd >= 0) {
    ::fsync(dfd);
    ::close(dfd);
  }
  return absl::OkStatus();
}

absl::Status WriteFileAtomically(const std::string& path, absl::string_view data) {
  auto w = AtomicFileWriter::Create(path);
  if (!w.ok()) return w.status();
  absl::Status st = w->Append(data);
  if (!st.ok()) return st;
  return w->Commit();
}

}  // namespace sheetmesh
