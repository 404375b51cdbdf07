#include "server/volume_service.h"

#include <stdlib.h>
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

#include "common/file_util.h"
#include "common/status_macros.h"
#include "server/references.h"
#include "server/status_util.h"
#include "worker/runtime/job_parameters.h"

namespace sheetmesh::server {

namespace {

// Opens `path` in a child process (InspectOptions) and says what it holds.
absl::StatusOr<runtime::InspectedVolume> InspectIsolated(const InspectOptions& o,
                                                         const std::string& path,
                                                         const std::string& display,
                                                         const std::string& parameters,
                                                         const std::vector<std::string>& roots) {
  std::string program = o.program;
  if (program.empty()) {
    SM_ASSIGN_OR_RETURN(program, runtime::SelfPath());
  }
  SM_RETURN_IF_ERROR(MakeDirs(o.scratch_dir));
  std::string dir = o.scratch_dir + "/inspect-XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) {
    return absl::InternalError(
        absl::StrCat(o.scratch_dir, ": cannot make a folder: ", std::strerror(errno)));
  }
  struct Cleanup {
    std::string dir;
    ~Cleanup() {
      std::error_code ec;
      std::filesystem::remove_all(dir, ec);
    }
  } cleanup{dir};
  runtime::JobSpec spec;
  spec.volume_path = path;
  spec.display_name = display;
  spec.output_dir = dir;
  spec.parameters = parameters;
  spec.allowed_roots = roots;
  spec.data_files = true;  // a named volume's detached data may lie in any allowed root
  return runtime::InspectVolumeInChild(program, spec, o.limits);
}

// Opens `path` here; the files it names must lie under `roots`, as in a child.
absl::StatusOr<runtime::InspectedVolume> InspectHere(const std::string& path,
                                                     const std::string& parameters,
                                                     const std::vector<std::string>& roots) {
  SM_ASSIGN_OR_RETURN(PipelineOptions o, runtime::OptionsFromResolved(parameters, path));
  o.input.open.limits.confine_named_files = true;
  o.input.open.limits.named_file_roots = roots;
  SM_ASSIGN_OR_RETURN(std::unique_ptr<VolumeSource> source, OpenVolume(path, o.input.open));
  return runtime::InspectedOf(source->info());
}

}  // namespace

grpc::Status VolumeServiceImpl::InspectVolume(grpc::ServerContext* context,
                                              const v1::InspectVolumeRequest* r,
                                              v1::InspectVolumeResponse* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  absl::StatusOr<std::string> path = ResolveReference(r->path(), ctx_->allowed_roots, "path");
  if (!path.ok()) return ToGrpcStatus(path.status());
  v1::JobInput input;
  *input.mutable_format() = r->format();
  absl::StatusOr<std::string> parameters = runtime::ResolveJobParameters({}, input);
  if (!parameters.ok()) return ToGrpcStatus(parameters.status());
  // Checks the format fields before a child is started for them.
  absl::StatusOr<PipelineOptions> o = runtime::OptionsFromResolved(*parameters, *path);
  if (!o.ok()) return ToGrpcStatus(o.status());
  absl::StatusOr<runtime::InspectedVolume> v =
      ctx_->inspect.isolate
          ? InspectIsolated(ctx_->inspect, *path, r->path(), *parameters, ctx_->allowed_roots)
          : InspectHere(*path, *parameters, ctx_->allowed_roots);
  if (!v.ok()) return ToGrpcStatus(v.status());
  response->set_path(*path);
  for (int k = 0; k < 3; ++k) response->add_dims(v->dims[k]);
  response->set_dtype(v->dtype);
  for (int k = 0; k < 3; ++k) response->add_spacing(v->spacing[k]);
  struct stat st;
  if (::stat(path->c_str(), &st) == 0) response->set_size_bytes(st.st_size);
  return grpc::Status::OK;
}

grpc::Status VolumeServiceImpl::ImportVolume(grpc::ServerContext* context,
                                             const v1::ImportVolumeRequest* r,
                                             v1::ImportVolumeResponse* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  absl::StatusOr<std::string> path = ResolveReference(r->path(), ctx_->allowed_roots, "path");
  if (!path.ok()) return ToGrpcStatus(path.status());
  struct stat st;
  if (::stat(path->c_str(), &st) == 0 && st.st_size > ctx_->limits.max_blob_bytes) {
    return ToGrpcStatus(absl::ResourceExhaustedError(
        absl::StrCat(r->path(), " has ", st.st_size, " bytes, above the server's limit of ",
                     ctx_->limits.max_blob_bytes, " bytes (max_blob_bytes)")));
  }
  absl::StatusOr<v1::Digest> d = ctx_->blobs->PutFile(*path);
  if (!d.ok()) return ToGrpcStatus(d.status());
  if (absl::Status st = ctx_->jobs->AddUploadedBlob(tenant, d->hash()); !st.ok()) {
    return ToGrpcStatus(st);
  }
  *response->mutable_digest() = *d;
  return grpc::Status::OK;
}

}  // namespace sheetmesh::server
