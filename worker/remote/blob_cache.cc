#include "worker/remote/blob_cache.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "common/file_util.h"
#include "common/status_macros.h"

namespace sheetmesh::remote {
namespace {

using runtime::ByteRange;

// What `have` lacks of `want` (both joined).
std::vector<ByteRange> Missing(const std::vector<ByteRange>& want,
                               const std::vector<ByteRange>& have) {
  std::vector<ByteRange> out;
  size_t h = 0;
  for (const ByteRange& w : want) {
    int64_t at = w.offset;
    const int64_t end = w.offset + w.length;
    while (h < have.size() && have[h].offset + have[h].length <= at) ++h;
    for (size_t k = h; k < have.size() && have[k].offset < end && at < end; ++k) {
      if (have[k].offset > at) out.push_back({at, have[k].offset - at});
      at = std::max(at, have[k].offset + have[k].length);
    }
    if (at < end) out.push_back({at, end - at});
  }
  return out;
}

// The listing beside a part file: "offset length" a line; empty when it is not one.
std::vector<ByteRange> ReadListing(const std::string& path, int64_t size) {
  absl::StatusOr<std::string> text = ReadFileToString(path, int64_t{1} << 24);
  std::vector<ByteRange> out;
  if (!text.ok()) return out;
  for (absl::string_view line : absl::StrSplit(*text, '\n', absl::SkipEmpty())) {
    const std::vector<absl::string_view> f = absl::StrSplit(line, ' ');
    ByteRange r;
    if (f.size() != 2 || !absl::SimpleAtoi(f[0], &r.offset) || !absl::SimpleAtoi(f[1], &r.length)) {
      return {};  // not ours: fetch again
    }
    out.push_back(r);
  }
  return JoinRanges(std::move(out), size);
}

}  // namespace

std::vector<ByteRange> JoinRanges(std::vector<ByteRange> ranges, int64_t size) {
  std::vector<ByteRange> clipped;
  for (ByteRange r : ranges) {
    const int64_t lo = std::clamp<int64_t>(r.offset, 0, size);
    const int64_t hi = std::clamp<int64_t>(r.offset + std::max<int64_t>(0, r.length), lo, size);
    if (hi > lo) clipped.push_back({lo, hi - lo});
  }
  std::sort(clipped.begin(), clipped.end(),
            [](const ByteRange& a, const ByteRange& b) { return a.offset < b.offset; });
  std::vector<ByteRange> out;
  for (const ByteRange& r : clipped) {
    if (!out.empty() && r.offset <= out.back().offset + out.back().length) {
      out.back().length = std::max(out.back().length, r.offset + r.length - out.back().offset);
    } else {
      out.push_back(r);
    }
  }
  return out;
}

BlobCache::BlobCache(std::string dir, Download download, ReadRange read_range)
    : dir_(std::move(dir)), download_(std::move(download)), read_range_(std::move(read_range)) {}

absl::StatusOr<std::string> BlobCache::Get(const std::string& task, const v1::Digest& digest,
                                           const std::vector<ByteRange>* only) {
  SM_RETURN_IF_ERROR(MakeDirs(dir_));
  const std::string& hash = digest.hash();
  {
    std::lock_guard<std::mutex> lock(mu_);
    ++users_[hash];
    of_task_[task] = hash;
    if (idle_ == hash) idle_.clear();
  }
  const std::string whole = Whole(hash);
  std::error_code ec;
  if (std::filesystem::file_size(whole, ec) == static_cast<uintmax_t>(digest.size_bytes()) && !ec) {
    return whole;
  }
  if (only != nullptr) return GetPart(digest, *only);
  // Two tasks of one volume at once may both download it: each writes its own temporary
  // file and the second rename leaves the same bytes.
  SM_RETURN_IF_ERROR(download_(digest, whole));
  {
    std::lock_guard<std::mutex> lock(mu_);
    fetched_ += digest.size_bytes();
  }
  // The whole file serves every task now: its part goes.
  std::lock_guard<std::mutex> part(part_mu_);
  std::filesystem::remove(Part(hash), ec);
  std::filesystem::remove(Listing(hash), ec);
  return whole;
}

absl::StatusOr<std::string> BlobCache::GetPart(const v1::Digest& digest,
                                               const std::vector<ByteRange>& only) {
  std::lock_guard<std::mutex> part(part_mu_);
  const int64_t size = digest.size_bytes();
  const std::string path = Part(digest.hash());
  const std::string listing = Listing(digest.hash());
  std::error_code ec;
  std::vector<ByteRange> have;
  if (std::filesystem::file_size(path, ec) == static_cast<uintmax_t>(size) && !ec) {
    have = ReadListing(listing, size);
  }
  const std::vector<ByteRange> missing = Missing(JoinRanges(only, size), have);
  if (missing.empty() && std::filesystem::exists(path, ec)) return path;
  const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) return ErrnoStatus(errno, path);
  ScopedFd file(fd);
  // As large as the volume: the bytes not fetched are holes (zeros), read by no brick.
  if (::ftruncate(fd, size) != 0) return ErrnoStatus(errno, path);
  int64_t fetched = 0;
  for (const ByteRange& r : missing) {
    int64_t at = r.offset;
    SM_RETURN_IF_ERROR(read_range_(digest, r.offset, r.length, [&](absl::string_view data) {
      const char* p = data.data();
      size_t left = data.size();
      while (left > 0) {
        const ssize_t n = ::pwrite(fd, p, left, at);
        if (n < 0) {
          if (errno == EINTR) continue;
          return ErrnoStatus(errno, path);
        }
        p += n;
        left -= static_cast<size_t>(n);
        at += n;
      }
      return absl::OkStatus();
    }));
    if (at != r.offset + r.length) {
      return absl::DataLossError(absl::StrCat(path, ": the server sent ", at - r.offset,
                                              " bytes of the range at ", r.offset, ", not ",
                                              r.length));
    }
    fetched += r.length;
    // Listed once its bytes are in: a fetch that breaks off lists what came before.
    have.push_back(r);
    have = JoinRanges(std::move(have), size);
    std::string text;
    for (const ByteRange& h : have) absl::StrAppend(&text, h.offset, " ", h.length, "\n");
    SM_RETURN_IF_ERROR(WriteFileAtomically(listing, text));
  }
  std::lock_guard<std::mutex> lock(mu_);
  fetched_ += fetched;
  return path;
}

void BlobCache::Release(const std::string& task) {
  std::string drop;
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = of_task_.find(task);
    if (it == of_task_.end()) return;
    const std::string hash = it->second;
    of_task_.erase(it);
    if (--users_[hash] > 0) return;
    users_.erase(hash);
    // The last volume stays for the next task of its job; the one before goes.
    if (!idle_.empty() && idle_ != hash) drop = idle_;
    idle_ = hash;
  }
  if (drop.empty()) return;
  std::lock_guard<std::mutex> part(part_mu_);
  std::error_code ec;
  for (const std::string& f : {Whole(drop), Part(drop), Listing(drop)}) {
    std::filesystem::remove(f, ec);
  }
}

int64_t BlobCache::fetched_bytes() const {
  std::lock_guard<std::mutex> lock(mu_);
  return fetched_;
}

}  // namespace sheetmesh::remote
