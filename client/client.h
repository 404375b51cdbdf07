// SheetmeshClient: the sheetmesh service from a program — resumable uploads, jobs,
// watching, artifact downloads. The CLI `sheetmesh` is built on it.
#ifndef SHEETMESH_CLIENT_CLIENT_H_
#define SHEETMESH_CLIENT_CLIENT_H_

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "sheetmesh/v1/blobs.grpc.pb.h"
#include "sheetmesh/v1/jobs.grpc.pb.h"
#include "sheetmesh/v1/volumes.grpc.pb.h"

namespace sheetmesh::client {

// A gRPC status as an absl one, the same code, its message after "`what`: " (the one
// conversion for every caller of the services: this client and the remote worker).
absl::Status FromGrpc(const grpc::Status& status, absl::string_view what = "");

struct ClientOptions {
  std::string address = "127.0.0.1:50051";
  std::string auth_token;     // sent as "authorization: Bearer <token>"
  bool tls = false;           // TLS with the system's roots, or...
  std::string tls_root_cert;  // ...with this PEM file
  int upload_retries = 5;     // broken upload streams resumed this many times
  // A worker uploading a job's outputs: the job (jobs/ID) and the worker holding it, sent
  // with every call so that the server records the uploads as that job's.
  std::string artifact_job;
  std::string artifact_worker;
};

// A one-line hint for an error that says the server could not be reached ("" for any
// other): the address with a scheme it does not take, nothing listening there, a name that
// does not resolve, or TLS on one side only.
std::string ConnectionHint(const absl::Status& status, const ClientOptions& options);

// One file of a volume on the client's disk, and its name in the volume.
struct LocalVolumeFile {
  std::string name;  // "slice_0001.tif", "scan.raw"
  std::string path;
};

// The files that make one volume: every visible regular file of a folder (its slices),
// or a detached NRRD header (.nhdr) and the data file it names; `main` is the file to
// open ("" for a folder). kInvalidArgument naming the header and field for a data file
// the upload cannot carry beside it (an absolute path, "..", a list of files).
struct VolumeOnDisk {
  std::vector<LocalVolumeFile> files;
  std::string main;
};
absl::StatusOr<VolumeOnDisk> VolumeFilesOf(const std::string& path);

// What UploadVolumeFiles sent.
struct VolumeUpload {
  v1::VolumeFiles files;  // the manifest for JobInput.volume_files
  int64_t total_bytes = 0;
  int files_sent = 0;  // the rest were stored already
  int64_t bytes_sent = 0;
};

// Thread-compatible: one client per thread, or guard it.
class SheetmeshClient {
 public:
  static absl::StatusOr<std::unique_ptr<SheetmeshClient>> Connect(const ClientOptions& options);

  // Uploads `path` unless the server holds it already; resumes an interrupted upload of
  // the same file. `progress(sent, total)` is called as pieces go.
  absl::StatusOr<v1::Digest> Upload(const std::string& path,
                                    const std::function<void(int64_t, int64_t)>& progress = {});
  // Uploads the files of one volume, sending only those the server lacks (one
  // FindMissingBlobs per thousand files); `progress(sent, total)` counts the bytes that
  // travel.
  absl::StatusOr<VolumeUpload> UploadVolumeFiles(
      const std::vector<LocalVolumeFile>& files,
      const std::function<void(int64_t, int64_t)>& progress = {});
  absl::StatusOr<v1::Job> CreateJob(const v1::CreateJobRequest& request);
  absl::StatusOr<v1::Job> GetJob(const std::string& name);
  absl::StatusOr<v1::ListJobsResponse> ListJobs(const v1::ListJobsRequest& request);
  absl::StatusOr<v1::Job> CancelJob(const std::string& name);
  absl::Status DeleteJob(const std::string& name);
  // Watches until the job ends, calling `on_update` for every message; returns the final
  // job. A stream that breaks is watched again (a watch never cancels the job).
  absl::StatusOr<v1::Job> Watch(const std::string& name,
                                const std::function<void(const v1::WatchJobResponse&)>& on_update);
  // Downloads a blob to `path` (atomically), by ranged reads.
  absl::Status Download(const v1::Digest& digest, const std::string& path);
  // Reads bytes [offset, offset + length) of a blob (clipped to its end), handing them to
  // `sink` in order; a broken stream is resumed where it stopped. No digest is checked: the
  // server's blobs were when they were stored.
  absl::Status ReadRange(const v1::Digest& digest, int64_t offset, int64_t length,
                         const std::function<absl::Status(absl::string_view)>& sink);
  // grpc.health.v1 status of the server ("SERVING").
  absl::StatusOr<std::string> Health();

  v1::JobService::Stub* jobs() { return jobs_.get(); }
  v1::BlobService::Stub* blobs() { return blobs_.get(); }
  v1::VolumeService::Stub* volumes() { return volumes_.get(); }
  std::shared_ptr<grpc::Channel> channel() const { return channel_; }
  // A context carrying the token.
  std::unique_ptr<grpc::ClientContext> Context() const;

 private:
  // Writes a blob the server lacks, resuming where an earlier write stopped.
  absl::StatusOr<v1::Digest> WriteBlob(const std::string& path, const v1::Digest& digest,
                                       const std::function<void(int64_t, int64_t)>& progress);

  ClientOptions options_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::JobService::Stub> jobs_;
  std::unique_ptr<v1::BlobService::Stub> blobs_;
  std::unique_ptr<v1::VolumeService::Stub> volumes_;
};

// "jobs/..." from "jobs/..." or a bare id.
std::string JobName(const std::string& name_or_id);

}  // namespace sheetmesh::client

#endif  // SHEETMESH_CLIENT_CLIENT_H_
