#include "server/blob_service.h"

#include <vector>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "server/status_util.h"

namespace sheetmesh::server {

constexpr int64_t kMaxPiece = int64_t{1} << 20;

grpc::Status CheckAuth(const grpc::ServerContext* context, const std::string& token) {
  if (token.empty()) return grpc::Status::OK;
  const auto& md = context->client_metadata();
  auto it = md.find("authorization");
  if (it != md.end() && std::string(it->second.data(), it->second.size()) == "Bearer " + token) {
    return grpc::Status::OK;
  }
  return grpc::Status(grpc::StatusCode::UNAUTHENTICATED,
                      "missing or wrong bearer token (metadata 'authorization: Bearer <token>')");
}

grpc::Status BlobServiceImpl::FindMissingBlobs(grpc::ServerContext* context,
                                               const v1::FindMissingBlobsRequest* request,
                                               v1::FindMissingBlobsResponse* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  for (const v1::Digest& d : request->digests()) {
    if (absl::Status st = CheckDigest(d); !st.ok()) return ToGrpcStatus(st);
    if (!ctx_->blobs->Contains(d)) *response->add_missing() = d;
  }
  return grpc::Status::OK;
}

grpc::Status BlobServiceImpl::Write(grpc::ServerContext* context,
                                    grpc::ServerReader<v1::WriteRequest>* reader,
                                    v1::WriteResponse* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  v1::WriteRequest req;
  std::string resource;
  bool finished = false;
  while (reader->Read(&req)) {
    if (resource.empty()) {
      if (req.resource_name().empty()) {
        return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                            "the first WriteRequest must name the resource");
      }
      resource = req.resource_name();
    } else if (!req.resource_name().empty() && req.resource_name() != resource) {
      return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT,
                          absl::StrCat("resource_name changed within a stream: '",
                                       req.resource_name(), "' after '", resource, "'"));
    }
    if (static_cast<int64_t>(req.data().size()) > kMaxPiece) {
      return grpc::Status(
          grpc::StatusCode::INVALID_ARGUMENT,
          absl::StrCat("a piece of ", req.data().size(), " bytes exceeds the 1 MiB limit"));
    }
    absl::StatusOr<BlobStore::UploadState> st = ctx_->blobs->Append(
        resource, req.write_offset(), req.data(), req.finish_write(), ctx_->limits.max_blob_bytes);
    if (!st.ok()) return ToGrpcStatus(st.status());
    response->set_committed_size(st->committed);
    if (req.finish_write()) {
      finished = true;
      break;
    }
  }
  if (resource.empty()) {
    return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "the write stream carried no request");
  }
  if (!finished) {
    // The client stopped early, or the stream broke: keep what arrived, durably.
    if (absl::Status st = ctx_->blobs->Sync(resource); !st.ok()) return ToGrpcStatus(st);
    absl::StatusOr<BlobStore::UploadState> state = ctx_->blobs->Status(resource);
    if (state.ok()) response->set_committed_size(state->committed);
  }
  return grpc::Status::OK;
}

grpc::Status BlobServiceImpl::QueryWriteStatus(grpc::ServerContext* context,
                                               const v1::QueryWriteStatusRequest* request,
                                               v1::QueryWriteStatusResponse* response) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  absl::StatusOr<BlobStore::UploadState> st = ctx_->blobs->Status(request->resource_name());
  if (!st.ok()) return ToGrpcStatus(st.status());
  response->set_committed_size(st->committed);
  response->set_complete(st->complete);
  return grpc::Status::OK;
}

grpc::Status BlobServiceImpl::Read(grpc::ServerContext* context, const v1::ReadRequest* request,
                                   grpc::ServerWriter<v1::ReadResponse>* writer) {
  if (grpc::Status a = CheckAuth(context, ctx_->auth_token); !a.ok()) return a;
  absl::StatusOr<std::string> path = ctx_->blobs->PathOf(request->digest());
  if (!path.ok()) return ToGrpcStatus(path.status());
  const int64_t size = request->digest().size_bytes();
  if (request->read_offset() < 0 || request->read_offset() > size || request->read_limit() < 0) {
    return grpc::Status(
        grpc::StatusCode::OUT_OF_RANGE,
        absl::StrCat("read_offset ", request->read_offset(), " and read_limit ",
                     request->read_limit(), " do not fit a blob of ", size, " bytes"));
  }
  const int64_t end = request->read_limit() == 0
                          ? size
                          : std::min(size, request->read_offset() + request->read_limit());
  absl::StatusOr<ScopedFd> fd = OpenForRead(*path);
  if (!fd.ok()) return ToGrpcStatus(fd.status());
  std::vector<std::byte> buf(kMaxPiece);
  v1::ReadResponse resp;
  for (int64_t off = request->read_offset(); off < end && !context->IsCancelled();) {
    const int64_t n = std::min(kMaxPiece, end - off);
    if (absl::Status st = ReadFullyAt(fd->get(), off, std::span<std::byte>(buf.data(), n), *path);
        !st.ok()) {
      return ToGrpcStatus(st);
    }
    resp.set_data(reinterpret_cast<const char*>(buf.data()), n);
    if (!writer->Write(resp)) break;
    off += n;
  }
  return grpc::Status::OK;
}

}  // namespace sheetmesh::server
