#include "server/retention.h"

#include <sys/stat.h>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "common/status_macros.h"

namespace sheetmesh::server {

std::string RetentionReport::Listing() const {
  std::string out;
  for (const BlobStore::BlobFile& b : collected) {
    absl::StrAppend(&out, dry_run ? "would remove " : "removed ", b.hash, " (", b.size,
                    " bytes, unreferenced, last used ",
                    absl::FormatTime("%Y-%m-%d %H:%M:%S UTC", b.last_used, absl::UTCTimeZone()),
                    ")\n");
  }
  absl::StrAppend(&out, "retention: ", dry_run ? "would remove " : "removed ", collected.size(),
                  " blobs (", collected_bytes, " bytes); kept ", kept_referenced,
                  " that jobs name and ", kept_recent, " used within the retention period\n");
  return out;
}

absl::StatusOr<RetentionReport> CollectBlobs(BlobStore& blobs, JobStore& jobs,
                                             absl::Duration retention, bool dry_run) {
  RetentionReport report;
  report.dry_run = dry_run;
  // References first, then the files: a blob stored or used after this looks recent.
  SM_ASSIGN_OR_RETURN(const std::set<std::string> referenced, jobs.ReferencedBlobs());
  const absl::Time cutoff = absl::Now() - retention;
  for (const BlobStore::BlobFile& b : blobs.ListBlobs()) {
    if (referenced.count(b.hash)) {
      ++report.kept_referenced;
      continue;
    }
    if (b.last_used >= cutoff) {
      ++report.kept_recent;
      continue;
    }
    if (!dry_run) {
      // Used again since it was listed? Then it stays.
      v1::Digest d;
      d.set_hash(b.hash);
      d.set_size_bytes(b.size);
      absl::StatusOr<std::string> path = blobs.PathOf(d);
      struct stat st;
      if (!path.ok() || ::stat(path->c_str(), &st) != 0 ||
          absl::FromUnixSeconds(st.st_mtim.tv_sec) >= cutoff) {
        ++report.kept_recent;
        continue;
      }
      SM_RETURN_IF_ERROR(jobs.ForgetBlob(b.hash));
      SM_RETURN_IF_ERROR(blobs.Remove(b.hash));
    }
    report.collected.push_back(b);
    report.collected_bytes += b.size;
  }
  return report;
}

}  // namespace sheetmesh::server
