// BlobStore: a filesystem content-addressed store (SHA-256). Blobs live at
// <root>/cas/<hash[0:2]>/<hash>; an upload grows <root>/uploads/<uuid>.part and becomes a
// blob only when its digest checks out (fsync, then rename), so a half-written blob is
// never visible. Uploads resume from their durable committed size, even after a restart.
#ifndef SHEETMESH_SERVER_BLOB_STORE_H_
#define SHEETMESH_SERVER_BLOB_STORE_H_

#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "sheetmesh/v1/common.pb.h"

namespace sheetmesh::server {

// SHA-256 of a file's contents. kNotFound / kInternal on read errors.
absl::StatusOr<v1::Digest> DigestOfFile(const std::string& path);
// "<hash>/<size>", for messages.
std::string DigestString(const v1::Digest& d);
// kInvalidArgument unless the hash is 64 lower-case hex digits and the size not negative.
absl::Status CheckDigest(const v1::Digest& d);

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

  // An upload in progress, keyed by its resource name.
  struct UploadState {
    int64_t committed = 0;  // bytes durably written
    bool complete = false;  // the blob is stored
  };
  // Appends `data` at `offset` to the upload `resource` (uploads/{uuid}/blobs/{hash}/{size}).
  // Bytes before what the upload already holds are skipped (a resumed or concurrent writer
  // of the same content). kInvalidArgument for a malformed name or an offset beyond what
  // the upload holds; kResourceExhausted beyond `max_bytes` (naming the limit). With `finish`,
  // checks the digest (kInvalidArgument on mismatch; the upload is discarded) and stores the blob.
  absl::StatusOr<UploadState> Append(const std::string& resource, int64_t offset,
                                     absl::string_view data, bool finish, int64_t max_bytes);
  // Makes what was written durable (a stream ended or broke).
  absl::Status Sync(const std::string& resource);
  absl::StatusOr<UploadState> Status(const std::string& resource);

  const std::string& root() const { return root_; }

 private:
  struct Upload;
  explicit BlobStore(std::string root) : root_(std::move(root)) {}
  std::string CasPath(const std::string& hash) const;
  absl::StatusOr<std::shared_ptr<Upload>> GetUpload(const std::string& resource, bool create);

  std::string root_;
  mutable std::mutex mu_;
  std::map<std::string, std::shared_ptr<Upload>> uploads_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_BLOB_STORE_H_
