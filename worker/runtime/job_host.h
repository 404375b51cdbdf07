// What a worker needs from whoever hands it jobs — the embedded server in-process, or a
// server over gRPC when scaled out: jobs to lease, their inputs, a place for their outputs.
#ifndef SHEETMESH_WORKER_RUNTIME_JOB_HOST_H_
#define SHEETMESH_WORKER_RUNTIME_JOB_HOST_H_

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/time/time.h"
#include "sheetmesh/v1/jobs.pb.h"

namespace sheetmesh::runtime {

struct ProgressUpdate {
  std::string stage;
  int stage_index = 0;  // 1-based
  int stage_count = 0;
  double fraction = 0;
  std::string message;
};

// A volume readable on this machine.
// A span of a file's bytes.
struct ByteRange {
  int64_t offset = 0;
  int64_t length = 0;
  friend bool operator==(const ByteRange&, const ByteRange&) = default;
};

struct LocalVolume {
  std::string path;
  std::string display_name;  // for messages: the name the client gave
  // Files the volume names itself (a detached NRRD's data file) may be read when
  // `data_files`, under these roots only; an upload may name none.
  bool data_files = false;
  std::vector<std::string> data_file_roots;
};

// How a run's result ends its job: SUCCEEDED when OK, CANCELLED for kCancelled, FAILED
// otherwise, with the status as the job's error.
inline v1::JobState EndStateOf(const absl::Status& result) {
  if (result.ok()) return v1::SUCCEEDED;
  return result.code() == absl::StatusCode::kCancelled ? v1::CANCELLED : v1::FAILED;
}
inline v1::JobError ErrorOf(const absl::Status& result) {
  v1::JobError e;
  if (!result.ok()) {
    e.set_code(static_cast<int>(result.code()));
    e.set_message(std::string(result.message()));
  }
  return e;
}

// The name an uploaded input gets on disk (readers tell formats by name): the client's
// file name without folders, or volume.raw.
std::string InputFileName(const v1::JobInput& input);
// The folder an input of several files is laid out in: the client's file name (the
// folder's or the header's name) without folders, or "volume".
std::string InputFolderName(const v1::JobInput& input);

// The most bricks one job run as bricks may be cut into.
inline constexpr int kMaxJobBricks = 1 << 16;

// The most files one volume may have (a stack of slices).
inline constexpr int kMaxVolumeFiles = 1 << 17;

// kInvalidArgument naming `field` ("input.volume_files") and the entry unless every name is
// a relative path of plain parts, no two alike, at most kMaxVolumeFiles of them, and
// `main` is empty or one of them. Digests are the caller's to check.
absl::Status CheckVolumeFiles(const v1::VolumeFiles& files, const std::string& field);

// Lays out a checked manifest's files in `dir` (created; each by `place(digest, path)`,
// with the folders of its name made first) and returns the path to open: dir/main, or
// `dir` for a folder of slices.
absl::StatusOr<std::string> LayOutVolumeFiles(
    const v1::VolumeFiles& files, const std::string& dir,
    const std::function<absl::Status(const v1::Digest&, const std::string&)>& place);

// Implementations must be thread-safe: every worker thread calls them.
class JobHost {
 public:
  virtual ~JobHost() = default;

  // Leases the oldest queued job for `worker`, waiting up to `wait` for one. nullopt when
  // none came.
  virtual absl::StatusOr<std::optional<v1::Job>> Lease(const std::string& worker,
                                                       absl::Duration wait) = 0;
  // Extends the lease. kNotFound / kFailedPrecondition when the job is gone, finished, or
  // leased to another worker: the worker must stop and report nothing. kCancelled when the
  // job was cancelled and the lease is still the worker's: stop it and end it CANCELLED.
  virtual absl::Status Renew(const std::string& job, const std::string& worker) = 0;
  // Progress of a leased job. Returns false when the job should stop (cancelled, lease
  // lost).
  virtual bool ReportProgress(const std::string& job, const std::string& worker,
                              const ProgressUpdate& update) = 0;
  // Makes the job's input readable locally. With `only` (a brick's bytes of its volume,
  // BrickInputBytes), a host that copies an uploaded volume from elsewhere may copy those
  // bytes only: the local file is as large as the volume, its other bytes absent.
  virtual absl::StatusOr<LocalVolume> ResolveInput(const v1::Job& job,
                                                   const std::vector<ByteRange>* only) = 0;
  // Stores an output file of `job`, run by `worker`, as a blob.
  virtual absl::StatusOr<v1::Artifact> PutArtifact(const std::string& job,
                                                   const std::string& worker,
                                                   const std::string& path,
                                                   const std::string& media_type) = 0;
  // Ends the job with its `artifacts`: SUCCEEDED when result is OK, CANCELLED when it is
  // kCancelled, FAILED otherwise (a failed job's artifacts are what its run kept).
  virtual absl::Status Finish(const std::string& job, const std::string& worker,
                              const absl::Status& result,
                              const std::vector<v1::Artifact>& artifacts) = 0;
  // Gives a leased job back to the queue without counting it as a failure (shutdown).
  virtual absl::Status Release(const std::string& job, const std::string& worker) = 0;
  // Splits a leased job run as bricks into `count` brick tasks, with its plan stored first
  // (PutArtifact) as `plan`: the job goes back to the queue until they have all ended, and
  // the worker reports nothing more for this lease.
  virtual absl::Status Split(const std::string& job, const std::string& worker,
                             const v1::Artifact& plan, int count) = 0;
  // Copies a stored blob a leased job names (its plan, a brick's output) to `path`.
  virtual absl::Status FetchBlob(const v1::Digest& digest, const std::string& path) = 0;
};

}  // namespace sheetmesh::runtime

#endif  // SHEETMESH_WORKER_RUNTIME_JOB_HOST_H_
