#include "server/blob_service.h"

#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "server/status_util.h"

namespace sheetmesh::server {

constexpr int64_t kMaxPiece = int64_t{1} << 20;

// Registers an open Write stream for the idle reaper for as long as it lives.
class BlobServiceImpl::ActiveWrite {
 public:
  ActiveWrite(BlobServiceImpl* s, grpc::ServerContext* c) : s_(s), c_(c) {
    std::lock_guard<std::mutex> lock(s_->mu_);
    s_->writes_[c_] = absl::Now();
  }
  ~ActiveWrite() {
    std::lock_guard<std::mutex> lock(s_->mu_);
    s_->writes_.erase(c_);
  }
  void Progress() {
    std::lock_guard<std::mutex> lock(s_->mu_);
    s_->writes_[c_] = absl::Now();
  }

 private:
  BlobServiceImpl* s_;
  grpc::ServerContext* c_;
};

BlobServiceImpl::BlobServiceImpl(const ServiceContext* ctx) : ctx_(ctx) {
  reaper_ = std::thread([this] { Reap(); });
}

BlobServiceImpl::~BlobServiceImpl() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  reaper_.join();
}

int64_t BlobServiceImpl::idle_closed() const {
  std::lock_guard<std::mutex> lock(mu_);
  return idle_closed_;
}

void BlobServiceImpl::Reap() {
  const absl::Duration idle = ctx_->limits.upload_idle_timeout;
  const absl::Duration tick = std::clamp(idle / 4, absl::Milliseconds(50), absl::Seconds(5));
  absl::Time next_expiry = absl::InfinitePast();
  std::unique_lock<std::mutex> lock(mu_);
  while (!stopping_) {
    cv_.wait_for(lock, absl::ToChronoMilliseconds(tick), [&] { return stopping_; });
    if (stopping_) break;
    const absl::Time now = absl::Now();
    for (auto& [context, last] : writes_) {
      // The stream's Read returns false; its handler ends, closing the upload's files.
      if (now - last > idle) {
        context->TryCancel();
        last = absl::InfiniteFuture();  // once
        ++idle_closed_;
      }
    }
    if (now >= next_expiry) {
      next_expiry = now + std::min(ctx_->limits.upload_expiry / 4, absl::Minutes(10));
      lock.unlock();
      ctx_->blobs->ExpireUploads(ctx_->limits.upload_expiry);
      lock.lock();
    }
  }
}

absl::StatusOr<bool> BlobServiceImpl::Owns(const std::string& tenant,
                                           const v1::Digest& digest) const {
  if (!ctx_->blobs->Contains(digest)) return false;
  // A job's artifacts are its worker's uploads for it, on an open server too (FinishJob
  // takes no other blob).
  const bool job_owner = absl::StartsWith(tenant, "@job.");
  if (!job_owner && (ctx_->tenants->open() || tenant == Tenants::kWorkerTenant)) return true;
  return ctx_->jobs->OwnsBlob(tenant, digest.hash());
}

std::string ArtifactOwner(const std::string& job) {
  return absl::StrCat("@job.", absl::StripPrefix(job, "jobs/"));
}

namespace {

std::string Metadata(const grpc::ServerContext& context, const char* key) {
  const auto& m = context.client_metadata();
  auto it = m.find(key);
  return it == m.end() ? "" : std::string(it->second.data(), it->second.size());
}

}  // namespace

grpc::Status BlobServiceImpl::Caller(grpc::ServerContext* context, std::string* owner) const {
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, owner); !a.ok()) return a;
  if (*owner != Tenants::kWorkerTenant) return grpc::Status::OK;
  const std::string job = Metadata(*context, kArtifactJobHeader);
  if (job.empty()) return grpc::Status::OK;  // a worker reading a job's input
  const std::string worker = Metadata(*context, kArtifactWorkerHeader);
  bool plain = absl::StartsWith(job, "jobs/") && job.size() > 5 && job.size() < 200;
  for (char c : job.substr(std::min<size_t>(5, job.size()))) {
    plain &= absl::ascii_isalnum(c) || c == '-' || c == '_';
  }
  if (!plain || worker.empty()) {
    return ToGrpcStatus(absl::InvalidArgumentError(
        absl::StrCat("an artifact upload names job '", job, "' and worker '", worker,
                     "'; both are needed, the job as jobs/ID")));
  }
  // The job must be this worker's now (renewing its lease is what a working worker does).
  const absl::Status leased = ctx_->jobs->Renew(job, worker, ctx_->worker_lease);
  if (!leased.ok()) {
    return ToGrpcStatus(absl::PermissionDeniedError(absl::StrCat(
        "worker ", worker, " uploads for ", job, ", which it does not hold: ", leased.message())));
  }
  *owner = ArtifactOwner(job);
  return grpc::Status::OK;
}

grpc::Status BlobServiceImpl::FindMissingBlobs(grpc::ServerContext* context,
                                               const v1::FindMissingBlobsRequest* request,
                                               v1::FindMissingBlobsResponse* response) {
  std::string tenant;
  if (grpc::Status a = Caller(context, &tenant); !a.ok()) return a;
  for (const v1::Digest& d : request->digests()) {
    if (absl::Status st = CheckDigest(d); !st.ok()) return ToGrpcStatus(st);
    absl::StatusOr<bool> owned = Owns(tenant, d);
    if (!owned.ok()) return ToGrpcStatus(owned.status());
    if (*owned) {
      ctx_->blobs->Touch(d);  // about to be used: retention starts again
    } else {
      *response->add_missing() = d;
    }
  }
  return grpc::Status::OK;
}

grpc::Status BlobServiceImpl::Write(grpc::ServerContext* context,
                                    grpc::ServerReader<v1::WriteRequest>* reader,
                                    v1::WriteResponse* response) {
  std::string tenant;
  if (grpc::Status a = Caller(context, &tenant); !a.ok()) return a;
  absl::StatusOr<StreamLimits::Slot> slot =
      ctx_->upload_streams->Acquire(ClientOf(*context, ctx_->tenants->open() ? "" : tenant));
  if (!slot.ok()) return ToGrpcStatus(slot.status());
  ActiveWrite active(this, context);
  v1::WriteRequest req;
  std::string resource;
  bool finished = false;
  bool stored_counts = false;
  grpc::Status result = grpc::Status::OK;
  while (reader->Read(&req)) {
    active.Progress();
    if (resource.empty()) {
      if (req.resource_name().empty()) {
        return ToGrpcStatus(
            absl::InvalidArgumentError("the first WriteRequest must name the resource"));
      }
      resource = req.resource_name();
      absl::StatusOr<v1::Digest> digest = DigestOfResource(resource);
      if (!digest.ok()) return ToGrpcStatus(digest.status());
      absl::StatusOr<bool> owned = Owns(tenant, *digest);
      if (!owned.ok()) return ToGrpcStatus(owned.status());
      stored_counts = *owned;
    } else if (!req.resource_name().empty() && req.resource_name() != resource) {
      result = ToGrpcStatus(absl::InvalidArgumentError(
          absl::StrCat("resource_name changed within a stream: '", req.resource_name(), "' after '",
                       resource, "'")));
      break;
    }
    if (static_cast<int64_t>(req.data().size()) > kMaxPiece) {
      result = ToGrpcStatus(absl::InvalidArgumentError(
          absl::StrCat("a piece of ", req.data().size(), " bytes exceeds the 1 MiB limit")));
      break;
    }
    absl::StatusOr<BlobStore::UploadState> st =
        ctx_->blobs->Append(tenant, resource, req.write_offset(), req.data(), req.finish_write(),
                            ctx_->limits.max_blob_bytes, stored_counts);
    if (!st.ok()) {
      result = ToGrpcStatus(st.status());
      break;
    }
    response->set_committed_size(st->committed);
    if (req.finish_write()) {
      finished = true;
      break;
    }
  }
  if (resource.empty()) {
    return ToGrpcStatus(absl::InvalidArgumentError("the write stream carried no request"));
  }
  if (finished) {
    // The blob is stored; it is the tenant's now.
    absl::StatusOr<v1::Digest> digest = DigestOfResource(resource);
    if (!digest.ok()) return ToGrpcStatus(digest.status());
    if (absl::Status st = ctx_->jobs->AddUploadedBlob(tenant, digest->hash()); !st.ok()) {
      return ToGrpcStatus(st);
    }
    return grpc::Status::OK;
  }
  // The client stopped early, the stream broke or stalled, or a piece was refused: keep
  // what arrived, durably, and close the upload's files until a stream resumes it.
  if (absl::Status st = ctx_->blobs->EndStream(tenant, resource); !st.ok() && result.ok()) {
    return ToGrpcStatus(st);
  }
  absl::StatusOr<BlobStore::UploadState> state =
      ctx_->blobs->Status(tenant, resource, stored_counts);
  if (state.ok()) response->set_committed_size(state->committed);
  return result;
}

grpc::Status BlobServiceImpl::QueryWriteStatus(grpc::ServerContext* context,
                                               const v1::QueryWriteStatusRequest* request,
                                               v1::QueryWriteStatusResponse* response) {
  std::string tenant;
  if (grpc::Status a = Caller(context, &tenant); !a.ok()) return a;
  absl::StatusOr<v1::Digest> digest = DigestOfResource(request->resource_name());
  if (!digest.ok()) return ToGrpcStatus(digest.status());
  absl::StatusOr<bool> owned = Owns(tenant, *digest);
  if (!owned.ok()) return ToGrpcStatus(owned.status());
  absl::StatusOr<BlobStore::UploadState> st =
      ctx_->blobs->Status(tenant, request->resource_name(), *owned);
  if (!st.ok()) return ToGrpcStatus(st.status());
  response->set_committed_size(st->committed);
  response->set_complete(st->complete);
  return grpc::Status::OK;
}

grpc::Status BlobServiceImpl::Read(grpc::ServerContext* context, const v1::ReadRequest* request,
                                   grpc::ServerWriter<v1::ReadResponse>* writer) {
  std::string tenant;
  if (grpc::Status a = ctx_->tenants->Authenticate(*context, &tenant); !a.ok()) return a;
  if (absl::Status st = CheckDigest(request->digest()); !st.ok()) return ToGrpcStatus(st);
  // Another tenant's blob is, to this one, not stored.
  absl::StatusOr<bool> owned = Owns(tenant, request->digest());
  if (!owned.ok()) return ToGrpcStatus(owned.status());
  if (!*owned) {
    return ToGrpcStatus(absl::NotFoundError(
        absl::StrCat("blob ", DigestString(request->digest()), " is not stored")));
  }
  absl::StatusOr<std::string> path = ctx_->blobs->PathOf(request->digest());
  if (!path.ok()) return ToGrpcStatus(path.status());
  const int64_t size = request->digest().size_bytes();
  if (request->read_offset() < 0 || request->read_offset() > size || request->read_limit() < 0) {
    return ToGrpcStatus(absl::OutOfRangeError(
        absl::StrCat("read_offset ", request->read_offset(), " and read_limit ",
                     request->read_limit(), " do not fit a blob of ", size, " bytes")));
  }
  // A limit past the blob's end reads to its end (offset + limit may not fit 64 bits).
  const int64_t end =
      request->read_limit() == 0 || request->read_limit() > size - request->read_offset()
          ? size
          : request->read_offset() + request->read_limit();
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
