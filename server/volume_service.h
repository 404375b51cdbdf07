// VolumeService: volumes on the server's storage, by path under the allowed roots.
#ifndef SHEETMESH_SERVER_VOLUME_SERVICE_H_
#define SHEETMESH_SERVER_VOLUME_SERVICE_H_

#include "server/service_context.h"
#include "sheetmesh/v1/volumes.grpc.pb.h"

namespace sheetmesh::server {

class VolumeServiceImpl final : public v1::VolumeService::Service {
 public:
  explicit VolumeServiceImpl(const ServiceContext* ctx) : ctx_(ctx) {}

  grpc::Status InspectVolume(grpc::ServerContext* context, const v1::InspectVolumeRequest* request,
                             v1::InspectVolumeResponse* response) override;
  grpc::Status ImportVolume(grpc::ServerContext* context, const v1::ImportVolumeRequest* request,
                            v1::ImportVolumeResponse* response) override;

 private:
  const ServiceContext* ctx_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_VOLUME_SERVICE_H_
