#include "server/blob_store.h"

#include <fcntl.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <future>
#include <random>
#include <set>
#include <span>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "common/sha256.h"
#include "common/status_macros.h"
#include "server/part_file.h"

namespace sheetmesh::server {
namespace {

// The folder of a tenant's unfinished uploads.
std::string TenantFolder(const std::string& root, const std::string& tenant) {
  return absl::StrCat(root, "/uploads/", tenant.empty() ? "_" : tenant);
}

void SyncDir(const std::string& dir) {
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd >= 0) {
    ::fsync(fd);
    ::close(fd);
  }
}

// Names this process's private upload files: replicas may share the folder (and a host).
const std::string& ProcessTag() {
  static const std::string tag = [] {
    std::random_device rd;
    return absl::StrCat(::getpid(), "-", absl::Hex(uint64_t{rd()} << 32 | rd(), absl::kZeroPad16));
  }();
  return tag;
}

// Removes a .part file unless another process holds its lock (a replica writing it). The
// lock is held while unlinking: a writer that takes it next finds the path gone and starts
// a new file.
bool UnlinkUnlessHeld(const std::string& path) {
  ScopedFd fd(::open(path.c_str(), O_RDONLY | O_CLOEXEC));
  if (!fd.valid()) return errno == ENOENT;
  if (::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) return false;
  return ::unlink(path.c_str()) == 0;
}

}  // namespace

// An upload: its file (open only while a stream writes it), the hash of the bytes written,
// and the declared digest.
struct BlobStore::Upload {
  std::mutex mu;
  std::string key;  // in uploads_
  std::string part_path;
  v1::Digest expected;
  std::unique_ptr<PartFile> file;
  std::unique_ptr<Sha256> sha;  // over [0, written)
  int64_t written = 0;
  int64_t committed = 0;  // durable (the stream ended, or a restart found it on disk)
  bool complete = false;
  // Another server sharing the folder held the upload's file: this one writes its own copy.
  bool private_copy = false;
  absl::Time last_write = absl::Now();
};

std::string DigestString(const v1::Digest& d) {
  return absl::StrCat(d.hash(), "/", d.size_bytes());
}

absl::Status CheckDigest(const v1::Digest& d) {
  bool hex = d.hash().size() == 64;
  for (char c : d.hash()) hex &= absl::ascii_isdigit(c) || (c >= 'a' && c <= 'f');
  if (!hex) {
    return absl::InvalidArgumentError(
        absl::StrCat("digest hash '", d.hash(), "' is not 64 lower-case hex digits (SHA-256)"));
  }
  if (d.size_bytes() < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("digest size_bytes ", d.size_bytes(), " is negative"));
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
  if (!Contains(d))
    return absl::NotFoundError(absl::StrCat("blob ", DigestString(d), " is not stored"));
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

absl::StatusOr<v1::Digest> DigestOfResource(const std::string& resource) {
  std::vector<std::string> parts = absl::StrSplit(resource, '/');
  int64_t size = 0;
  if (parts.size() != 5 || parts[0] != "uploads" || parts[2] != "blobs" || parts[1].empty() ||
      parts[1].size() > 128 || !absl::SimpleAtoi(parts[4], &size)) {
    return absl::InvalidArgumentError(absl::StrCat(
        "resource_name '", resource, "' must look like uploads/{uuid}/blobs/{hash}/{size}"));
  }
  for (char c : parts[1]) {
    if (!absl::ascii_isalnum(c) && c != '-' && c != '_') {
      return absl::InvalidArgumentError(absl::StrCat(
          "resource_name '", resource, "': the upload id may hold letters, digits, - and _ only"));
    }
  }
  v1::Digest d;
  d.set_hash(parts[3]);
  d.set_size_bytes(size);
  SM_RETURN_IF_ERROR(CheckDigest(d));
  return d;
}

absl::StatusOr<std::shared_ptr<BlobStore::Upload>> BlobStore::GetUpload(const std::string& tenant,
                                                                        const std::string& resource,
                                                                        bool create,
                                                                        bool stored_counts,
                                                                        int64_t max_bytes) {
  SM_ASSIGN_OR_RETURN(const v1::Digest expected, DigestOfResource(resource));
  const int64_t size = expected.size_bytes();
  const std::vector<std::string> parts = absl::StrSplit(resource, '/');
  // Refused before anything is created: a refused upload leaves no file and no entry.
  if (size > max_bytes) {
    return absl::ResourceExhaustedError(absl::StrCat("a blob of ", size,
                                                     " bytes exceeds the server's limit of ",
                                                     max_bytes, " bytes (max_blob_bytes)"));
  }
  const std::string key = absl::StrCat(tenant, "\n", resource);
  std::lock_guard<std::mutex> lock(mu_);
  auto it = uploads_.find(key);
  if (it != uploads_.end()) return it->second;
  auto up = std::make_shared<Upload>();
  up->key = key;
  up->expected = expected;
  up->part_path = absl::StrCat(TenantFolder(root_, tenant), "/", parts[1], "-", parts[3], ".part");
  if (stored_counts && Contains(expected)) {
    up->complete = true;
    up->committed = up->written = size;
    return up;  // nothing to keep
  }
  struct stat st;
  const bool exists = ::stat(up->part_path.c_str(), &st) == 0;
  if (!exists && !create) return up;
  SM_RETURN_IF_ERROR(MakeDirs(std::filesystem::path(up->part_path).parent_path().string()));
  SM_RETURN_IF_ERROR(OpenPart(*up, /*lock=*/create, nullptr));
  // Only a stream keeps the files open (a status query found this upload on disk).
  if (!create) up->file.reset();
  uploads_[key] = up;
  return up;
}

// Opens the upload's .part file, for writing when `lock`. An upload from before a restart,
// or whose file changed under it (a replica sharing the folder wrote it, or stored it),
// resumes from its length on disk: that prefix is hashed again, and `*moved` says the
// upload is not where its last state said. A file another replica is writing is left to
// it: this server writes a private copy beside it (the same bytes; whichever is stored
// last replaces the other with itself).
absl::Status BlobStore::OpenPart(Upload& up, bool lock, bool* moved) {
  auto file = std::make_unique<PartFile>();
  int64_t have = 0;
  bool busy = false;
  const int64_t before = up.sha != nullptr ? up.written : 0;
  SM_RETURN_IF_ERROR(file->Open(up.part_path, lock, &have, &busy));
  if (busy) {
    up.part_path =
        absl::StrCat(absl::StripSuffix(up.part_path, ".part"), ".", ProcessTag(), ".part");
    up.private_copy = true;
    up.sha.reset();
    SM_RETURN_IF_ERROR(file->Open(up.part_path, lock, &have, &busy));
    if (busy) return absl::UnavailableError(absl::StrCat(up.part_path, " is busy; retry"));
  }
  up.file = std::move(file);
  if (up.sha == nullptr || have != up.written) {
    if (have > up.expected.size_bytes()) {  // not this upload's bytes: start again
      if (lock && ::ftruncate(up.file->fd(), 0) != 0) return ErrnoStatus(errno, up.part_path);
      have = 0;
    }
    up.sha = std::make_unique<Sha256>();
    SM_RETURN_IF_ERROR(HashFilePrefix(up.file->fd(), have, up.sha.get(), up.part_path));
    up.written = up.committed = have;
  }
  if (moved != nullptr) *moved = busy || have != before;
  return absl::OkStatus();
}

absl::StatusOr<BlobStore::UploadState> BlobStore::Append(const std::string& tenant,
                                                         const std::string& resource,
                                                         int64_t offset, absl::string_view data,
                                                         bool finish, int64_t max_bytes,
                                                         bool stored_counts) {
  SM_ASSIGN_OR_RETURN(std::shared_ptr<Upload> up,
                      GetUpload(tenant, resource, true, stored_counts, max_bytes));
  std::lock_guard<std::mutex> lock(up->mu);
  if (up->complete) return UploadState{up->expected.size_bytes(), true};
  up->last_write = absl::Now();
  bool moved = false;
  if (up->file == nullptr) {
    if (stored_counts && Contains(up->expected)) return Stored(*up);  // by a replica
    SM_RETURN_IF_ERROR(OpenPart(*up, /*lock=*/true, &moved));
  }
  if (offset > up->written && (moved || up->private_copy)) {
    // The writer's offset came from a state this server no longer holds: a replica sharing
    // the folder has the upload's file, or stored it. The writer asks again and resumes.
    return absl::UnavailableError(absl::StrCat(
        "upload ", resource, " holds ", up->written, " bytes here, not the ", offset,
        " the write starts at (another server shares it); query the status and resume"));
  }
  if (offset < 0 || offset > up->written) {
    return absl::InvalidArgumentError(absl::StrCat("write_offset ", offset, " for ", resource,
                                                   " must be at most the committed size ",
                                                   up->written));
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
    SM_RETURN_IF_ERROR(CheckRoom(tenant, static_cast<int64_t>(data.size())));
    SM_RETURN_IF_ERROR(up->file->Append(data));
    up->sha->Update(data.data(), data.size());
    up->written += data.size();
  }
  if (!finish) return UploadState{up->committed, false};
  const std::string got = up->sha->Hex();
  if (up->written != up->expected.size_bytes() || got != up->expected.hash()) {
    const std::string why =
        absl::StrCat("upload ", resource, " has ", up->written, " bytes of SHA-256 ", got,
                     ", not the declared ", DigestString(up->expected), "; it is discarded");
    ::unlink(up->part_path.c_str());  // before its lock goes with the file
    up->file->Close();
    up->file.reset();
    std::lock_guard<std::mutex> l(mu_);
    uploads_.erase(up->key);
    return absl::InvalidArgumentError(why);
  }
  SM_RETURN_IF_ERROR(up->file->Flush());
  if (::fsync(up->file->fd()) != 0) return ErrnoStatus(errno, up->part_path);
  const std::string dest = CasPath(up->expected.hash());
  SM_RETURN_IF_ERROR(MakeDirs(std::filesystem::path(dest).parent_path().string()));
  // The same bytes may be stored already (a tenant that did not own them sent them): the
  // rename replaces them with themselves.
  if (::rename(up->part_path.c_str(), dest.c_str()) != 0) return ErrnoStatus(errno, dest);
  SyncDir(std::filesystem::path(dest).parent_path().string());
  up->file.reset();  // its lock kept the file this server's until it was renamed
  return Stored(*up);
}

// The upload's blob is stored (by this server or a replica): later calls find the blob.
// Its file (a private copy, or one a status query reopened) goes unless a replica is
// writing it.
BlobStore::UploadState BlobStore::Stored(Upload& up) {
  UnlinkUnlessHeld(up.part_path);
  up.complete = true;
  up.committed = up.written = up.expected.size_bytes();
  up.sha.reset();
  std::lock_guard<std::mutex> l(mu_);
  uploads_.erase(up.key);
  return UploadState{up.committed, true};
}

absl::Status BlobStore::EndStream(const std::string& tenant, const std::string& resource) {
  SM_ASSIGN_OR_RETURN(std::shared_ptr<Upload> up,
                      GetUpload(tenant, resource, false, false, INT64_MAX));
  std::lock_guard<std::mutex> lock(up->mu);
  if (up->complete || up->file == nullptr) return absl::OkStatus();
  absl::Status st = up->file->Flush();
  if (st.ok()) up->committed = up->written;
  // Closed even when the flush failed: a stream that ended holds no descriptor.
  up->file->Close();
  up->file.reset();
  up->last_write = absl::Now();
  return st;
}

absl::StatusOr<BlobStore::UploadState> BlobStore::Status(const std::string& tenant,
                                                         const std::string& resource,
                                                         bool stored_counts) {
  SM_ASSIGN_OR_RETURN(std::shared_ptr<Upload> up,
                      GetUpload(tenant, resource, false, stored_counts, INT64_MAX));
  std::lock_guard<std::mutex> lock(up->mu);
  if (!up->complete && up->file == nullptr) {
    // No stream writes it here: a replica sharing the folder may have written or stored it
    // since. The state is read again from the disk.
    if (stored_counts && Contains(up->expected)) return Stored(*up);
    struct stat st;
    if (up->sha == nullptr || ::stat(up->part_path.c_str(), &st) != 0 ||
        st.st_size != up->committed) {
      SM_RETURN_IF_ERROR(OpenPart(*up, /*lock=*/false, nullptr));  // a missing file is empty
      up->file.reset();
    }
  }
  // While a stream writes it, the blocks already written out count: a kill of this process
  // would leave them, and a restart would report them.
  const int64_t durable =
      up->file != nullptr ? std::max(up->committed, up->file->on_disk()) : up->committed;
  return UploadState{up->complete ? up->expected.size_bytes() : durable, up->complete};
}

int BlobStore::ExpireUploads(absl::Duration max_age) {
  const absl::Time cutoff = absl::Now() - max_age;
  int removed = 0;
  std::lock_guard<std::mutex> lock(mu_);
  for (auto it = uploads_.begin(); it != uploads_.end();) {
    Upload& up = *it->second;
    std::unique_lock<std::mutex> l(up.mu, std::try_to_lock);
    // A replica sharing the folder may be writing the file: it is left to it.
    if (l.owns_lock() && up.file == nullptr && up.last_write < cutoff &&
        UnlinkUnlessHeld(up.part_path)) {
      it = uploads_.erase(it);
      ++removed;
    } else {
      ++it;
    }
  }
  // .part files no entry knows: a previous process's, or an older layout's.
  std::set<std::string> known;
  for (const auto& [key, up] : uploads_) known.insert(up->part_path);
  std::error_code ec;
  for (auto e = std::filesystem::recursive_directory_iterator(root_ + "/uploads", ec);
       !ec && e != std::filesystem::recursive_directory_iterator(); e.increment(ec)) {
    const std::string path = e->path().string();
    if (!e->is_regular_file(ec) || e->path().extension() != ".part" || known.count(path)) continue;
    struct stat st;
    if (::stat(path.c_str(), &st) != 0) continue;
    if (absl::FromUnixSeconds(st.st_mtim.tv_sec) < cutoff && UnlinkUnlessHeld(path)) {
      ++removed;
    }
  }
  return removed;
}

void BlobStore::SetUploadLimits(int64_t max_unfinished_bytes_per_tenant, int64_t min_free_bytes) {
  std::lock_guard<std::mutex> lock(mu_);
  max_unfinished_per_tenant_ = max_unfinished_bytes_per_tenant;
  min_free_bytes_ = min_free_bytes;
}

int64_t BlobStore::UnfinishedBytes(const std::string& tenant) const {
  int64_t bytes = 0;
  std::error_code ec;
  for (auto e = std::filesystem::directory_iterator(TenantFolder(root_, tenant), ec);
       !ec && e != std::filesystem::directory_iterator(); e.increment(ec)) {
    struct stat st;
    if (e->path().extension() == ".part" && ::stat(e->path().c_str(), &st) == 0) {
      bytes += st.st_size;
    }
  }
  return bytes;
}

absl::Status BlobStore::CheckRoom(const std::string& tenant, int64_t bytes) {
  int64_t per_tenant, min_free;
  {
    std::lock_guard<std::mutex> lock(mu_);
    per_tenant = max_unfinished_per_tenant_;
    min_free = min_free_bytes_;
  }
  if (min_free > 0) {
    struct statvfs fs;
    if (::statvfs(root_.c_str(), &fs) == 0) {
      const int64_t free_bytes = static_cast<int64_t>(fs.f_bavail) * fs.f_frsize;
      if (free_bytes - bytes < min_free) {
        return absl::ResourceExhaustedError(
            absl::StrCat("the server's data folder has ", free_bytes, " bytes free; ", bytes,
                         " more would leave less than its floor of ", min_free,
                         " bytes (--min_free_disk_mb): uploads wait until space is freed"));
      }
    }
  }
  if (per_tenant <= 0) return absl::OkStatus();
  // Measured on disk at most once a second (replicas sharing the folder write there too),
  // counting this server's appends in between.
  const absl::Time now = absl::Now();
  bool measure;
  {
    std::lock_guard<std::mutex> lock(mu_);
    measure = now - usage_[tenant].measured > absl::Seconds(1);
  }
  const int64_t on_disk = measure ? UnfinishedBytes(tenant) : 0;
  std::lock_guard<std::mutex> lock(mu_);
  Usage& u = usage_[tenant];
  if (measure) u = {on_disk, 0, now};
  if (u.on_disk + u.since + bytes > per_tenant) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "tenant ", tenant.empty() ? "default" : tenant, " has ", u.on_disk + u.since,
        " bytes in unfinished uploads; ", bytes, " more would pass the limit of ", per_tenant,
        " bytes (--max_unfinished_upload_mb): finish or abandon an upload first"));
  }
  u.since += bytes;
  return absl::OkStatus();
}

int BlobStore::open_uploads() const {
  std::lock_guard<std::mutex> lock(mu_);
  int n = 0;
  for (const auto& [key, up] : uploads_) {
    std::unique_lock<std::mutex> l(up->mu, std::try_to_lock);
    n += !l.owns_lock() || up->file != nullptr;
  }
  return n;
}

void BlobStore::Touch(const v1::Digest& digest) {
  if (!CheckDigest(digest).ok()) return;
  ::utimensat(AT_FDCWD, CasPath(digest.hash()).c_str(), nullptr, 0);
}

std::vector<BlobStore::BlobFile> BlobStore::ListBlobs() const {
  std::vector<BlobFile> out;
  std::error_code ec;
  for (auto e = std::filesystem::recursive_directory_iterator(root_ + "/cas", ec);
       !ec && e != std::filesystem::recursive_directory_iterator(); e.increment(ec)) {
    if (!e->is_regular_file(ec)) continue;
    const std::string name = e->path().filename().string();
    struct stat st;
    if (name.size() != 64 || ::stat(e->path().c_str(), &st) != 0) continue;
    out.push_back({name, st.st_size, absl::FromUnixSeconds(st.st_mtim.tv_sec)});
  }
  return out;
}

absl::Status BlobStore::Remove(const std::string& hash) {
  if (hash.size() != 64) return absl::InvalidArgumentError(absl::StrCat("'", hash, "' is no hash"));
  const std::string path = CasPath(hash);
  if (::unlink(path.c_str()) != 0) return ErrnoStatus(errno, path);
  return absl::OkStatus();
}

}  // namespace sheetmesh::server
