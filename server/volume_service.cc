#include "server/volume_service.h"

#include <sys/stat.h>

#include "server/references.h"
#include "server/status_util.h"
#include "worker/runtime/job_parameters.h"

namespace sheetmesh::server {

grpc::Status VolumeServiceImpl::InspectVolume(grpc::ServerContext* context,
                                              const v1::InspectVolumeRequest* r,
                                              v1::InspectVolumeResponse* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  absl::StatusOr<std::string> path = ResolveReference(r->path(), ctx_->allowed_roots);
  if (!path.ok()) return ToGrpcStatus(path.status());
  v1::JobInput input;
  *input.mutable_format() = r->format();
  absl::StatusOr<std::string> parameters = runtime::ResolveJobParameters({}, input);
  if (!parameters.ok()) return ToGrpcStatus(parameters.status());
  absl::StatusOr<PipelineOptions> o = runtime::OptionsFromResolved(*parameters, *path);
  if (!o.ok()) return ToGrpcStatus(o.status());
  absl::StatusOr<std::unique_ptr<VolumeSource>> source = OpenVolume(*path, o->input.open);
  if (!source.ok()) return ToGrpcStatus(source.status());
  const VolumeInfo& info = (*source)->info();
  response->set_path(*path);
  response->add_dims(info.dims.nx);
  response->add_dims(info.dims.ny);
  response->add_dims(info.dims.nz);
  response->set_dtype(std::string(DTypeName(info.dtype)));
  for (int k = 0; k < 3; ++k) response->add_spacing(info.placement.spacing[k]);
  struct stat st;
  if (::stat(path->c_str(), &st) == 0) response->set_size_bytes(st.st_size);
  return grpc::Status::OK;
}

grpc::Status VolumeServiceImpl::ImportVolume(grpc::ServerContext* context,
                                             const v1::ImportVolumeRequest* r,
                                             v1::ImportVolumeResponse* response) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  absl::StatusOr<std::string> path = ResolveReference(r->path(), ctx_->allowed_roots);
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
