// Retention: stored blobs that no job names (input or artifact; the artifacts of deleted
// jobs among them) and that nobody used for `retention` are removed, with their owners'
// records; uploads left unfinished past their expiry go too (BlobStore::ExpireUploads). A
// blob's age counts from its last use (stored, found by FindMissingBlobs, named by a new
// job), so a blob a client is about to use is never taken.
#ifndef SHEETMESH_SERVER_RETENTION_H_
#define SHEETMESH_SERVER_RETENTION_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "server/blob_store.h"
#include "server/job_store.h"

namespace sheetmesh::server {

struct RetentionReport {
  std::vector<BlobStore::BlobFile> collected;  // removed (or, dry run, to remove)
  int64_t collected_bytes = 0;
  int kept_referenced = 0;  // a job names them
  int kept_recent = 0;      // unreferenced, but used within the retention period
  bool dry_run = false;

  // One line per blob collected and a summary, for the server's log or a terminal.
  std::string Listing() const;
};

// One pass. With `dry_run`, lists what it would remove and removes nothing.
absl::StatusOr<RetentionReport> CollectBlobs(BlobStore& blobs, JobStore& jobs,
                                             absl::Duration retention, bool dry_run);

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_RETENTION_H_
