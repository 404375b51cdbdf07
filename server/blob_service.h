// BlobService: uploads (resumable), find-missing and ranged reads over the BlobStore.
#ifndef SHEETMESH_SERVER_BLOB_SERVICE_H_
#define SHEETMESH_SERVER_BLOB_SERVICE_H_

#include "server/service_context.h"
#include "sheetmesh/v1/blobs.grpc.pb.h"

namespace sheetmesh::server {

class BlobServiceImpl final : public v1::BlobService::Service {
 public:
  explicit BlobServiceImpl(const ServiceContext* ctx) : ctx_(ctx) {}

  grpc::Status FindMissingBlobs(grpc::ServerContext* context,
                                const v1::FindMissingBlobsRequest* request,
                                v1::FindMissingBlobsResponse* response) override;
  grpc::Status Write(grpc::ServerContext* context, grpc::ServerReader<v1::WriteRequest>* reader,
                     v1::WriteResponse* response) override;
  grpc::Status QueryWriteStatus(grpc::ServerContext* context,
                                const v1::QueryWriteStatusRequest* request,
                                v1::QueryWriteStatusResponse* response) override;
  grpc::Status Read(grpc::ServerContext* context, const v1::ReadRequest* request,
                    grpc::ServerWriter<v1::ReadResponse>* writer) override;

 private:
  const ServiceContext* ctx_;
};

}  // namespace sheetmesh::server

#endif  // SHEETMESH_SERVER_BLOB_SERVICE_H_
