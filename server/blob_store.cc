#include "server/blob_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "worker/pipeline/core/file_util.h"
#include "worker/pipeline/core/sha256.h"
#include "worker/pipeline/core/status_macros.h"

namespace sheetmesh::server {
namespace {

void SyncDir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

}  // namespace

// An upload: its file, the hash of its committed bytes, and the declared digest.
struct BlobStore::Upload {
  std::mutex mu;
  std::string part_path;
  v1::Digest expected;
  ScopedFd fd;
  std::unique_ptr<Sha256> sha;  // over [0, written)
  int64_t written = 0;
  int64_t committed = 0;        // fsynced
  bool complete = false;
};

std::string DigestString(const v1::Digest& d) { return absl::StrCat(d.hash(), "/", d.size_bytes()); }

absl::Status CheckDigest(const v1::Digest& d) {
  bool hex = d.hash().size() == 64;
  for (char c : d.hash()) hex &= absl::ascii_isdigit(c) || (c >= 'a' && c <= 'f');
  if (!hex) {
    return absl::InvalidArgumentError(absl::StrCat("digest hash '", d.hash(),
                                                   "' is not 64 lower-case hex digits (SHA-256)"));
  }
  if (d.size_bytes() < 0) {
    return absl::InvalidArgumentError(absl::StrCat("digest size_bytes ", d.size_bytes(), " is negative"));
  }
  return absl::OkStatus();
}

absl::StatusOr<v1::Digest> DigestOfFile(const std::string& path) {
  SM_ASSIGN_OR_RETURN(FileHash h, HashFile(path));
  v1::Digest d;
  d.set_hash(h.hex);
  d.set_size_bytes(h.size);
  return d;
}

absl::StatusOr<std::unique_ptr<BlobStore>> BlobStore::Open(const std::string& root) {
  SM_RETURN_IF_ERROR(MakeDirs(root + "/cas"));
  SM_RETURN_IF_ERROR(MakeDirs(root + "/uploads"));
  return std::unique_ptr<BlobStore>(new BlobStore(root));
}

std::string BlobStore::CasPath(const std::string& hash) const {
  return absl::StrCat(root_, "/cas/", hash.substr(0, 2), "/", hash);
}

bool BlobStore::Contains(const v1::Digest& d) const {
  if (!CheckDigest(d).ok()) return false;
  struct stat st;
  return ::stat(CasPath(d.hash()).c_str(), &st) == 0 && st.st_size == d.size_bytes();
}

absl::StatusOr<std::string> BlobStore::PathOf(const v1::Digest& d) const {
  SM_RETURN_IF_ERROR(CheckDigest(d));
  if (!Contains(d)) return absl::NotFoundError(absl::StrCat("blob ", DigestString(d), " is not stored"));
  return CasPath(d.hash());
}

absl::StatusOr<v1::Digest> BlobStore::PutFile(const std::string& path) {
  SM_ASSIGN_OR_RETURN(v1::Digest d, DigestOfFile(path));
  if (Contains(d)) return d;
  const std::string dest = CasPath(d.hash());
  SM_RETURN_IF_ERROR(MakeDirs(std::filesystem::path(dest).parent_path().string()));
  SM_ASSIGN_OR_RETURN(ScopedFd in, OpenForRead(path));
  SM_ASSIGN_OR_RETURN(AtomicFileWriter out, AtomicFileWriter::Create(dest));
  std::vector<std::byte> buf(1 << 20);
  for (int64_t off = 0; off < d.size_bytes();) {
    const int64_t n = std::min<int64_t>(buf.size(), d.size_bytes() - off);
    SM_RETURN_IF_ERROR(ReadFullyAt(in.get(), off, std::span<std::byte>(buf.data(), n), path));
    SM_RETURN_IF_ERROR(out.Append(std::span<const std::byte>(buf.data(), n)));
    off += n;
  }
  SM_RETURN_IF_ERROR(out.Commit());
  return d;
}

absl::StatusOr<std::shared_ptr<BlobStore::Upload>> BlobStore::GetUpload(const std::string& resource,
                                                                        bool create) {
  // uploads/{uuid}/blobs/{hash}/{size}
  std::vector<std::string> parts = absl::StrSplit(resource, '/');
  int64_t size = 0;
  if (parts.size() != 5 || parts[0] != "uploads" || parts[2] != "blobs" || parts[1].empty() ||
      !absl::SimpleAtoi(parts[4], &size)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "resource_name '", resource, "' must look like uploads/{uuid}/blobs/{hash}/{size}"));
  }
  for (char c : parts[1]) {
    if (!absl::ascii_isalnum(c) && c != '-' && c != '_') {
      return absl::InvalidArgumentError(
          absl::StrCat("resource_name '", resource, "': the upload id may hold letters, digits, - and _ only"));
    }
  }
  v1::Digest expected;
  expected.set_hash(parts[3]);
  expected.set_size_bytes(size);
  SM_RETURN_IF_ERROR(CheckDigest(expected));
  std::lock_guard<std::mutex> lock(mu_);
  auto it = uploads_.find(resource);
  if (it != uploads_.end()) return it->second;
  auto up = std::make_shared<Upload>();
  up->expected = expected;
  up->part_path = absl::StrCat(root_, "/uploads/", parts[1], "-", parts[3], ".part");
  if (Contains(expected)) {
    up->complete = true;
    up->committed = up->written = size;
  } else {
    struct stat st;
    const bool exists = ::stat(up->part_path.c_str(), &st) == 0;
    if (!exists && !create) return up;
    // An upload from before a restart resumes from its durable length: hash that prefix.
    const int fd = ::open(up->part_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) return ErrnoStatus(errno, up->part_path);
    up->fd = ScopedFd(fd);
    up->sha = std::make_unique<Sha256>();
    const int64_t have = exists ? st.st_size : 0;
    SM_RETURN_IF_ERROR(HashFilePrefix(fd, have, up->sha.get(), up->part_path));
    up->written = up->committed = have;
  }
  uploads_[resource] = up;
  return up;
}

absl::StatusOr<BlobStore::UploadState> BlobStore::Append(const std::string& resource,
                                                         int64_t offset, absl::string_view data,
                                                         bool finish, int64_t max_bytes) {
  SM_ASSIGN_OR_RETURN(std::shared_ptr<Upload> up, GetUpload(resource, true));
  std::lock_guard<std::mutex> lock(up->mu);
  if (up->expected.size_bytes() > max_bytes) {
    return absl::ResourceExhaustedError(absl::StrCat("a blob of ", up->expected.size_bytes(),
                                                     " bytes exceeds the server's limit of ",
                                                     max_bytes, " bytes (max_blob_bytes)"));
  }
  if (up->complete) return UploadState{up->expected.size_bytes(), true};
  if (offset < 0 || offset > up->written) {
    return absl::InvalidArgumentError(absl::StrCat("write_offset ", offset, " for ", resource,
                                                   " must be at most the committed size ", up->written));
  }
  // A resumed (or a second, concurrent) writer may send bytes the upload already has: the
  // content is named by its digest, so they are the same bytes (the digest check at the end
  // catches any that are not) and are skipped.
  data.remove_prefix(std::min<int64_t>(up->written - offset, data.size()));
  offset = up->written;
  if (up->written + static_cast<int64_t>(data.size()) > up->expected.size_bytes()) {
    return absl::InvalidArgumentError(absl::StrCat(resource, ": ", up->written + data.size(),
                                                   " bytes written exceed the declared size ",
                                                   up->expected.size_bytes()));
  }
  if (!data.empty()) {
    if (::pwrite(up->fd.get(), data.data(), data.size(), up->written) != static_cast<ssize_t>(data.size())) {
      return ErrnoStatus(errno, up->part_path);
    }
    up->sha->Update(data.data(), data.size());
    up->written += data.size();
    // Durable in steps of 64 MiB, so that a resumed upload loses little.
    if (up->written - up->committed >= (int64_t{64} << 20)) {
      if (::fdatasync(up->fd.get()) != 0) return ErrnoStatus(errno, up->part_path);
      up->committed = up->written;
    }
  }
  if (!finish) return UploadState{up->committed, false};
  const std::string got = up->sha->Hex();
  if (up->written != up->expected.size_bytes() || got != up->expected.hash()) {
    const std::string why = absl::StrCat(
        "upload ", resource, " has ", up->written, " bytes of SHA-256 ", got,
        ", not the declared ", DigestString(up->expected), "; it is discarded");
    up->fd = ScopedFd();
    ::unlink(up->part_path.c_str());
    std::lock_guard<std::mutex> l(mu_);
    uploads_.erase(resource);
    return absl::InvalidArgumentError(why);
  }
  if (::fsync(up->fd.get()) != 0) return ErrnoStatus(errno, up->part_path);
  up->fd = ScopedFd();
  const std::string dest = CasPath(up->expected.hash());
  SM_RETURN_IF_ERROR(MakeDirs(std::filesystem::path(dest).parent_path().string()));
  if (::rename(up->part_path.c_str(), dest.c_str()) != 0) return ErrnoStatus(errno, dest);
  SyncDir(std::filesystem::path(dest).parent_path().string());
  up->complete = true;
  up->committed = up->written;
  return UploadState{up->committed, true};
}

absl::Status BlobStore::Sync(const std::string& resource) {
  SM_ASSIGN_OR_RETURN(std::shared_ptr<Upload> up, GetUpload(resource, false));
  std::lock_guard<std::mutex> lock(up->mu);
  if (up->complete || !up->fd.valid()) return absl::OkStatus();
  if (::fdatasync(up->fd.get()) != 0) return ErrnoStatus(errno, up->part_path);
  up->committed = up->written;
  return absl::OkStatus();
}

absl::StatusOr<BlobStore::UploadState> BlobStore::Status(const std::string& resource) {
  SM_ASSIGN_OR_RETURN(std::shared_ptr<Upload> up, GetUpload(resource, false));
  std::lock_guard<std::mutex> lock(up->mu);
  return UploadState{up->complete ? up->expected.size_bytes() : up->committed, up->complete};
}

}  // namespace sheetmesh::server
