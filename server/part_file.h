// PartFile: the file of an upload in progress (blob_store.cc), written in large aligned
// blocks straight to the disk while the stream fills the next one.
#ifndef SHEETMESH_SERVER_PART_FILE_H_
#define SHEETMESH_SERVER_PART_FILE_H_

#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <future>
#include <memory>
#include <span>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh::server {

// The file of an upload in progress. Pieces are gathered in an aligned buffer and written
// with O_DIRECT in large blocks: the bytes go from the network to the disk without a
// copy into the page cache (which costs more than the disk itself on small machines) and
// the server's memory stays flat however large the blob. Two buffers alternate: one is
// written by a helper thread while the stream fills the other, so the disk and the
// network overlap. The unaligned tail is written through the page cache when the stream
// stops. Where O_DIRECT is refused (tmpfs), plain writes are used.
class PartFile {
 public:
  static constexpr int64_t kBlock = 4096;
  static constexpr int64_t kStage = int64_t{8} << 20;

  ~PartFile() { (void)WaitForWrite(); }

  // With `lock`, opens (creating) the file for writing and takes its lock: the servers
  // sharing a blob folder (replicas) write one .part file one at a time. `*busy` says
  // another process holds it (nothing is opened then). The lock is taken on the file the
  // path names when it is held: a file the holder renamed into the store meanwhile is not
  // this upload's any more. Without, opens it for reading; a missing file is empty.
  absl::Status Open(const std::string& path, bool lock, int64_t* size, bool* busy) {
    path_ = path;
    *busy = false;
    for (int tries = 0;; ++tries) {
      const int fd =
          ::open(path.c_str(), lock ? O_RDWR | O_CREAT | O_CLOEXEC : O_RDONLY | O_CLOEXEC, 0644);
      if (fd < 0 && !lock && errno == ENOENT) {
        *size = end_ = 0;
        return absl::OkStatus();
      }
      if (fd < 0) return ErrnoStatus(errno, path);
      fd_ = ScopedFd(fd);
      if (!lock) break;
      if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
        fd_ = ScopedFd();
        if (errno == EWOULDBLOCK) {
          *busy = true;
          return absl::OkStatus();
        }
        return ErrnoStatus(errno, path);
      }
      struct stat held, named;
      if (::fstat(fd, &held) != 0) return ErrnoStatus(errno, path);
      if (::stat(path.c_str(), &named) == 0 && named.st_ino == held.st_ino &&
          named.st_dev == held.st_dev) {
        break;
      }
      fd_ = ScopedFd();
      if (tries == 8) {
        return absl::UnavailableError(absl::StrCat(path, " keeps being replaced; retry"));
      }
    }
    const int dfd = lock ? ::open(path.c_str(), O_WRONLY | O_DIRECT | O_CLOEXEC) : -1;
    if (dfd >= 0) direct_ = ScopedFd(dfd);
    SM_ASSIGN_OR_RETURN(*size, FileSizeOf(fd_.get(), path));
    end_ = *size;
    on_disk_ = *size;
    return absl::OkStatus();
  }
  int fd() const { return fd_.get(); }

  // The bytes written out to the file so far: what a restart after a kill of this
  // process finds, while the stream still fills the buffers.
  int64_t on_disk() const { return on_disk_.load(); }

  // Appends at the end of what was written.
  absl::Status Append(absl::string_view data) {
    while (!data.empty()) {
      if (stage_ == nullptr) SM_RETURN_IF_ERROR(LoadStage());
      const int64_t n = std::min<int64_t>(data.size(), kStage - stage_len_);
      memcpy(stage_.get() + stage_len_, data.data(), n);
      stage_len_ += n;
      end_ += n;
      data.remove_prefix(n);
      if (stage_len_ == kStage) {
        // The previous block must be out before its buffer is reused.
        SM_RETURN_IF_ERROR(WaitForWrite());
        if (spare_ == nullptr) {
          SM_ASSIGN_OR_RETURN(spare_, NewBuffer());
        }
        std::swap(stage_, spare_);
        const char* full = spare_.get();
        const int64_t at = stage_start_;
        writing_ = std::async(std::launch::async, [this, full, at] {
          absl::Status st = WriteAt(full, kStage, at, true);
          if (st.ok()) on_disk_ = at + kStage;
          return st;
        });
        stage_start_ += kStage;
        stage_len_ = 0;
      }
    }
    return absl::OkStatus();
  }

  // Writes out everything and makes it durable (fdatasync); the buffers are released.
  absl::Status Flush() {
    SM_RETURN_IF_ERROR(WaitForWrite());
    if (stage_ != nullptr && stage_len_ > 0) {
      const int64_t aligned = stage_len_ / kBlock * kBlock;
      if (aligned > 0) SM_RETURN_IF_ERROR(WriteAt(stage_.get(), aligned, stage_start_, true));
      if (stage_len_ > aligned) {
        SM_RETURN_IF_ERROR(
            WriteAt(stage_.get() + aligned, stage_len_ - aligned, stage_start_ + aligned, false));
      }
    }
    stage_.reset();
    spare_.reset();
    stage_len_ = 0;
    if (::fdatasync(fd_.get()) != 0) return ErrnoStatus(errno, path_);
    on_disk_ = end_;
    return absl::OkStatus();
  }

  void Close() {
    (void)WaitForWrite();
    stage_.reset();
    spare_.reset();
    direct_ = ScopedFd();
    fd_ = ScopedFd();
  }

 private:
  struct FreeDeleter {
    void operator()(char* p) const { free(p); }
  };
  using Buffer = std::unique_ptr<char, FreeDeleter>;

  static absl::StatusOr<Buffer> NewBuffer() {
    void* mem = nullptr;
    if (posix_memalign(&mem, kBlock, kStage) != 0)
      return absl::ResourceExhaustedError("no memory for an upload buffer");
    return Buffer(static_cast<char*>(mem));
  }

  absl::Status WaitForWrite() {
    if (!writing_.valid()) return absl::OkStatus();
    return writing_.get();
  }

  // The buffer starts at the block holding the end of the file; a partial block already
  // in the file is read back into it, so that direct writes stay aligned.
  absl::Status LoadStage() {
    SM_ASSIGN_OR_RETURN(stage_, NewBuffer());
    stage_start_ = end_ / kBlock * kBlock;
    stage_len_ = end_ - stage_start_;
    if (stage_len_ > 0) {
      SM_RETURN_IF_ERROR(
          ReadFullyAt(fd_.get(), stage_start_,
                      std::as_writable_bytes(std::span<char>(stage_.get(), stage_len_)), path_));
    }
    return absl::OkStatus();
  }

  // At most one write runs at a time (the helper's, or the caller's after waiting for
  // it), so direct_ is never touched by two threads at once.
  absl::Status WriteAt(const char* p, int64_t n, int64_t offset, bool want_direct) {
    bool direct = want_direct && direct_.valid();
    while (n > 0) {
      const ssize_t w = ::pwrite(direct ? direct_.get() : fd_.get(), p, n, offset);
      if (w < 0 && errno == EINTR) continue;
      if (w < 0 && direct && errno == EINVAL) {  // this file system refuses O_DIRECT
        direct_ = ScopedFd();
        direct = false;
        continue;
      }
      if (w <= 0) return ErrnoStatus(w < 0 ? errno : EIO, path_);
      p += w;
      n -= w;
      offset += w;
    }
    return absl::OkStatus();
  }

  std::string path_;
  ScopedFd fd_, direct_;
  Buffer stage_, spare_;
  std::future<absl::Status> writing_;
  int64_t stage_start_ = 0;  // file offset of stage_[0], block-aligned
  int64_t stage_len_ = 0;
  int64_t end_ = 0;  // bytes in the file and the buffers together
  std::atomic<int64_t> on_disk_{0};
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_PART_FILE_H_
