// BlobStore: a filesystem content-addressed store (SHA-256). Blobs live at
// <root>/cas/<hash[0:2]>/<hash>; an upload of a tenant grows
// <root>/uploads/<tenant>/<uuid>-<hash>.part and becomes a blob only when its digest checks
// out (fsync, then rename), so a half-written blob is never visible. Uploads resume from
// their durable committed size, even after a restart; an upload holds file descriptors only
// while a stream writes it, and one left alone past an expiry is removed.
// Servers may share the folder (replicas over one database): a .part file is locked
// (flock) while a stream writes it, a server that finds it locked writes a private copy
// of the same content beside it, and a state that a replica changed is read again from
// the disk (Status, and a write that reopens the file).
#ifndef SHEETMESH_SERVER_BLOB_STORE_H_
#define SHEETMESH_SERVER_BLOB_STORE_H_

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "sheetmesh/v1/common.pb.h"

namespace sheetmesh::server {

// SHA-256 of a file's contents. kNotFound / kInternal on read errors.
absl::StatusOr<v1::Digest> DigestOfFile(const std::string& path);
// "<hash>/<size>", for messages.
std::string DigestString(const v1::Digest& d);
// kInvalidArgument unless the hash is 64 lower-case hex digits and the size not negative.
absl::Status CheckDigest(const v1::Digest& d);

// The digest an upload's resource name declares (uploads/{uuid}/blobs/{hash}/{size});
// kInvalidArgument naming the resource when it is malformed.
absl::StatusOr<v1::Digest> DigestOfResource(const std::string& resource);

// Thread-safe.
class BlobStore {
 public:
  // Opens (creating) the store under `root`. Uploads older than a restart are kept for
  // resumption.
  static absl::StatusOr<std::unique_ptr<BlobStore>> Open(const std::string& root);

  bool Contains(const v1::Digest& digest) const;
  // The blob's file, for reading. kNotFound when absent.
  absl::StatusOr<std::string> PathOf(const v1::Digest& digest) const;

  // Stores the file at `path` (copied) and returns its digest.
  absl::StatusOr<v1::Digest> PutFile(const std::string& path);

  // Marks the blob used now: retention (CollectBlobs) counts a blob's age from its last use.
  void Touch(const v1::Digest& digest);

  // A stored blob, for retention.
  struct BlobFile {
    std::string hash;
    int64_t size = 0;
    absl::Time last_used;  // the file's modification time (Touch)
  };
  std::vector<BlobFile> ListBlobs() const;
  // Removes a stored blob (retention). kNotFound when absent.
  absl::Status Remove(const std::string& hash);

  // An upload in progress, keyed by its tenant and resource name.
  struct UploadState {
    int64_t committed = 0;  // bytes durably written
    bool complete = false;  // the blob is stored
  };
  // Appends `data` at `offset` to `tenant`'s upload `resource`
  // (uploads/{uuid}/blobs/{hash}/{size}). Bytes before what the upload already holds are
  // skipped (a resumed or concurrent writer of the same content). kInvalidArgument for a
  // malformed name or an offset beyond what the upload holds; kResourceExhausted beyond
  // `max_bytes` (naming the limit), before anything is written. With `finish`, checks the
  // digest (kInvalidArgument on mismatch; the upload is discarded) and stores the blob. A
  // blob already stored completes the upload at once only when `stored_counts` (the tenant
  // owns it); otherwise its bytes must come, so that nobody gains a blob by naming it.
  absl::StatusOr<UploadState> Append(const std::string& tenant, const std::string& resource,
                                     int64_t offset, absl::string_view data, bool finish,
                                     int64_t max_bytes, bool stored_counts);
  // A stream writing the upload ended or broke: what was written is made durable and the
  // upload's files are closed (it keeps its place, and reopens when written again).
  absl::Status EndStream(const std::string& tenant, const std::string& resource);
  absl::StatusOr<UploadState> Status(const std::string& tenant, const std::string& resource,
                                     bool stored_counts);
  // Removes uploads nobody has written for `max_age` (their .part files too, also those a
  // previous process left). Returns how many.
  int ExpireUploads(absl::Duration max_age);
  // Uploads with open files (a stream is writing them).
  int open_uploads() const;

  // What unfinished uploads may take: a tenant's bytes in uploads not yet stored, and the
  // free space an append must leave in the folder (for the job store and the jobs'
  // outputs). An append beyond either is kResourceExhausted naming the limit and its flag,
  // before anything is written. 0: no limit.
  void SetUploadLimits(int64_t max_unfinished_bytes_per_tenant, int64_t min_free_bytes);
  // The bytes of `tenant`'s unfinished uploads in the folder (all servers sharing it).
  int64_t UnfinishedBytes(const std::string& tenant) const;

  const std::string& root() const { return root_; }

 private:
  struct Upload;
  explicit BlobStore(std::string root) : root_(std::move(root)) {}
  std::string CasPath(const std::string& hash) const;
  absl::StatusOr<std::shared_ptr<Upload>> GetUpload(const std::string& tenant,
                                                    const std::string& resource, bool create,
                                                    bool stored_counts, int64_t max_bytes);
  absl::Status OpenPart(Upload& up, bool lock, bool* moved);
  UploadState Stored(Upload& up);

  absl::Status CheckRoom(const std::string& tenant, int64_t bytes);

  std::string root_;
  mutable std::mutex mu_;
  std::map<std::string, std::shared_ptr<Upload>> uploads_;
  int64_t max_unfinished_per_tenant_ = 0;
  int64_t min_free_bytes_ = 0;
  // A tenant's unfinished bytes as last measured on disk, and what was appended since.
  struct Usage {
    int64_t on_disk = 0;
    int64_t since = 0;
    absl::Time measured = absl::InfinitePast();
  };
  std::map<std::string, Usage> usage_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_BLOB_STORE_H_
