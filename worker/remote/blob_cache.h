// Uploaded volumes a remote worker keeps under their digests in one folder (SCRATCH/cache),
// so that the tasks of one volume it runs one after another (a job's bricks) fetch it once.
// A volume is kept whole (downloaded and checked against its digest), or in part: a brick
// of a raw or NRRD volume reads only some of its bytes (Brick::fetch), and those alone are
// fetched into a file as large as the volume, listed beside it (<hash>.ranges) so that the
// next brick fetches only what that file does not hold yet. The last volume no task uses
// stays until another replaces it.
#ifndef SHEETMESH_WORKER_REMOTE_BLOB_CACHE_H_
#define SHEETMESH_WORKER_REMOTE_BLOB_CACHE_H_

#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "sheetmesh/v1/blobs.pb.h"
#include "worker/runtime/job_host.h"

namespace sheetmesh::remote {

// Thread-safe.
class BlobCache {
 public:
  // Downloads a whole blob to a path (atomically, checking its digest).
  using Download = std::function<absl::Status(const v1::Digest&, const std::string& path)>;
  // Reads a range of a blob (clipped to its end), its bytes handed to the sink in order.
  using ReadRange =
      std::function<absl::Status(const v1::Digest&, int64_t offset, int64_t length,
                                 const std::function<absl::Status(absl::string_view)>& sink)>;

  BlobCache(std::string dir, Download download, ReadRange read_range);

  // The local file of `digest` for `task`, holding every byte (`only` null) or at least
  // `only`'s (the others may be absent: zeros). The errors of the reads pass through; a
  // failed fetch leaves what was fetched before it listed, and nothing else.
  absl::StatusOr<std::string> Get(const std::string& task, const v1::Digest& digest,
                                  const std::vector<runtime::ByteRange>* only);
  // `task` no longer uses its blob.
  void Release(const std::string& task);

  // Bytes fetched so far, whole or in ranges (for the log and tests).
  int64_t fetched_bytes() const;

 private:
  std::string Whole(const std::string& hash) const { return dir_ + "/" + hash; }
  std::string Part(const std::string& hash) const { return dir_ + "/" + hash + ".part"; }
  std::string Listing(const std::string& hash) const { return dir_ + "/" + hash + ".ranges"; }
  absl::StatusOr<std::string> GetPart(const v1::Digest& digest,
                                      const std::vector<runtime::ByteRange>& only);

  const std::string dir_;
  const Download download_;
  const ReadRange read_range_;
  mutable std::mutex mu_;                       // the maps below, and fetched_
  std::mutex part_mu_;                          // one fetch into a part file at a time
  std::map<std::string, int> users_;            // hash -> tasks using it
  std::map<std::string, std::string> of_task_;  // task -> the hash it uses
  std::string idle_;                            // the hash kept with no task using it
  int64_t fetched_ = 0;
};

// Sorted, clipped to [0, size), with ranges that touch or overlap joined.
std::vector<runtime::ByteRange> JoinRanges(std::vector<runtime::ByteRange> ranges, int64_t size);

}  // namespace sheetmesh::remote

#endif  // SHEETMESH_WORKER_REMOTE_BLOB_CACHE_H_
