#include "client/client.h"

#include <grpcpp/generic/generic_stub.h>
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <condition_variable>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <set>
#include <thread>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "common/file_util.h"
#include "common/sha256.h"
#include "common/status_macros.h"
#include "sheetmesh/v1/job_states.h"

namespace sheetmesh::client {

absl::Status FromGrpc(const grpc::Status& s, absl::string_view what) {
  if (s.ok()) return absl::OkStatus();
  return absl::Status(
      static_cast<absl::StatusCode>(s.error_code()),
      what.empty() ? s.error_message() : absl::StrCat(what, ": ", s.error_message()));
}

namespace {

constexpr int64_t kPiece = int64_t{1} << 20;

}  // namespace

std::string ConnectionHint(const absl::Status& status, const ClientOptions& o) {
  if (status.code() != absl::StatusCode::kUnavailable) return "";
  const std::string m(status.message());
  const std::string& a = o.address;
  for (const char* scheme : {"http://", "https://", "grpc://", "grpcs://"}) {
    if (a.rfind(scheme, 0) == 0) {
      return absl::StrCat("hint: --server takes HOST:PORT without a scheme (--server=",
                          a.substr(std::strlen(scheme)), ")");
    }
  }
  auto has = [&](const char* s) { return m.find(s) != std::string::npos; };
  if (has("wrong version number") || has("WRONG_VERSION_NUMBER") || has("Handshake failed") ||
      has("handshake")) {
    return o.tls ? absl::StrCat("hint: the server at ", a,
                                " does not speak TLS (drop --tls), or its certificate is not "
                                "trusted (--tls_root_cert)")
                 : absl::StrCat("hint: the server at ", a, " wants TLS: add --tls");
  }
  if (has("Connection refused")) {
    return absl::StrCat("hint: nothing listens at ", a,
                        ": is sheetmesh-server running there, on that port?");
  }
  if (has("DNS resolution failed") || has("Domain name not found")) {
    return absl::StrCat("hint: the host in --server=", a, " does not resolve");
  }
  if (!o.tls && (has("Socket closed") || has("Connection reset"))) {
    return absl::StrCat("hint: the server at ", a,
                        " closed the connection: if it serves TLS, add --tls");
  }
  return absl::StrCat("hint: the server at ", a, " cannot be reached");
}

std::string JobName(const std::string& n) { return n.rfind("jobs/", 0) == 0 ? n : "jobs/" + n; }

absl::StatusOr<std::unique_ptr<SheetmeshClient>> SheetmeshClient::Connect(const ClientOptions& o) {
  std::shared_ptr<grpc::ChannelCredentials> creds = grpc::InsecureChannelCredentials();
  if (o.tls || !o.tls_root_cert.empty()) {
    grpc::SslCredentialsOptions ssl;
    if (!o.tls_root_cert.empty()) {
      SM_ASSIGN_OR_RETURN(ssl.pem_root_certs, ReadFileToString(o.tls_root_cert));
    }
    creds = grpc::SslCredentials(ssl);
  }
  grpc::ChannelArguments args;
  args.SetMaxReceiveMessageSize(4 << 20);
  args.SetInt(GRPC_ARG_KEEPALIVE_TIME_MS, 30000);
  args.SetInt(GRPC_ARG_KEEPALIVE_PERMIT_WITHOUT_CALLS, 1);
  auto c = std::unique_ptr<SheetmeshClient>(new SheetmeshClient());
  c->options_ = o;
  c->channel_ = grpc::CreateCustomChannel(o.address, creds, args);
  c->jobs_ = v1::JobService::NewStub(c->channel_);
  c->blobs_ = v1::BlobService::NewStub(c->channel_);
  c->volumes_ = v1::VolumeService::NewStub(c->channel_);
  return c;
}

std::unique_ptr<grpc::ClientContext> SheetmeshClient::Context() const {
  auto ctx = std::make_unique<grpc::ClientContext>();
  if (!options_.auth_token.empty())
    ctx->AddMetadata("authorization", "Bearer " + options_.auth_token);
  if (!options_.artifact_job.empty()) {
    ctx->AddMetadata("sheetmesh-job", options_.artifact_job);
    ctx->AddMetadata("sheetmesh-worker", options_.artifact_worker);
  }
  return ctx;
}

absl::StatusOr<v1::Digest> SheetmeshClient::Upload(
    const std::string& path, const std::function<void(int64_t, int64_t)>& progress) {
  SM_ASSIGN_OR_RETURN(FileHash h, HashFile(path));
  v1::Digest digest;
  digest.set_hash(h.hex);
  digest.set_size_bytes(h.size);
  {
    v1::FindMissingBlobsRequest req;
    *req.add_digests() = digest;
    v1::FindMissingBlobsResponse resp;
    SM_RETURN_IF_ERROR(FromGrpc(blobs_->FindMissingBlobs(Context().get(), req, &resp)));
    if (resp.missing_size() == 0) {
      if (progress) progress(h.size, h.size);
      return digest;
    }
  }
  return WriteBlob(path, digest, progress);
}

absl::StatusOr<v1::Digest> SheetmeshClient::WriteBlob(
    const std::string& path, const v1::Digest& digest,
    const std::function<void(int64_t, int64_t)>& progress) {
  const std::string& hex = digest.hash();
  const int64_t size = digest.size_bytes();
  // The upload is named by the content, so that running the upload again resumes it.
  const std::string resource =
      absl::StrCat("uploads/u", hex.substr(0, 32), "/blobs/", hex, "/", size);
  SM_ASSIGN_OR_RETURN(ScopedFd fd, OpenForRead(path));
  std::vector<std::byte> buf(kPiece);
  absl::Status last;
  for (int attempt = 0; attempt <= options_.upload_retries; ++attempt) {
    v1::QueryWriteStatusRequest q;
    q.set_resource_name(resource);
    v1::QueryWriteStatusResponse qs;
    SM_RETURN_IF_ERROR(FromGrpc(blobs_->QueryWriteStatus(Context().get(), q, &qs)));
    if (qs.complete()) return digest;
    int64_t offset = qs.committed_size();
    auto ctx = Context();
    v1::WriteResponse resp;
    std::unique_ptr<grpc::ClientWriter<v1::WriteRequest>> writer = blobs_->Write(ctx.get(), &resp);
    bool broken = false;
    v1::WriteRequest req;
    req.set_resource_name(resource);
    do {
      const int64_t n = std::min(kPiece, size - offset);
      SM_RETURN_IF_ERROR(ReadFullyAt(fd.get(), offset, std::span<std::byte>(buf.data(), n), path));
      req.set_write_offset(offset);
      req.set_data(reinterpret_cast<const char*>(buf.data()), n);
      req.set_finish_write(offset + n == size);
      if (!writer->Write(req)) {
        broken = true;
        break;
      }
      req.clear_resource_name();
      offset += n;
      if (progress) progress(offset, size);
    } while (offset < size);
    writer->WritesDone();
    last = FromGrpc(writer->Finish());
    if (last.ok() && !broken) return digest;
    if (!last.ok() && last.code() != absl::StatusCode::kUnavailable &&
        last.code() != absl::StatusCode::kDeadlineExceeded &&
        last.code() != absl::StatusCode::kCancelled) {
      return last;  // the server refused: retrying would not help
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(200 << std::min(attempt, 5)));
  }
  return absl::UnavailableError(absl::StrCat("upload of ", path, " did not complete after ",
                                             options_.upload_retries + 1,
                                             " attempts: ", last.message()));
}

namespace {

// The data file a detached NRRD header names, as written ("" when the header names none).
absl::StatusOr<std::string> NrrdDataFileField(const std::string& header) {
  SM_ASSIGN_OR_RETURN(std::string text, ReadFileToString(header));
  bool first = true;
  for (absl::string_view line : absl::StrSplit(text, '\n')) {
    if (absl::EndsWith(line, "\r")) line.remove_suffix(1);
    if (first) {
      if (!absl::StartsWith(line, "NRRD")) {
        return absl::InvalidArgumentError(absl::StrCat(header, ": not a NRRD header"));
      }
      first = false;
      continue;
    }
    if (line.empty()) break;  // the blank line that closes the header
    if (line[0] == '#') continue;
    const size_t colon = line.find(':');
    if (colon == absl::string_view::npos) continue;
    const std::string key = absl::AsciiStrToLower(line.substr(0, colon));
    if (key != "data file" && key != "datafile") continue;
    absl::string_view value = line.substr(colon + 1);
    if (absl::StartsWith(value, "=")) value.remove_prefix(1);
    return std::string(absl::StripAsciiWhitespace(value));
  }
  return std::string();
}

}  // namespace

absl::StatusOr<VolumeOnDisk> VolumeFilesOf(const std::string& path) {
  namespace fs = std::filesystem;
  VolumeOnDisk v;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    for (const auto& entry : fs::directory_iterator(path, ec)) {
      const std::string name = entry.path().filename().string();
      if (name.empty() || name[0] == '.' || !entry.is_regular_file()) continue;
      v.files.push_back({name, entry.path().string()});
    }
    if (ec) return ErrnoStatus(ec.value(), path);
    if (v.files.empty()) {
      return absl::InvalidArgumentError(absl::StrCat(path, ": the folder holds no files"));
    }
    std::sort(v.files.begin(), v.files.end(),
              [](const LocalVolumeFile& a, const LocalVolumeFile& b) { return a.name < b.name; });
    return v;
  }
  const std::string name = fs::path(path).filename().string();
  v.files.push_back({name, path});
  v.main = name;
  if (absl::AsciiStrToLower(fs::path(path).extension().string()) != ".nhdr") return v;
  SM_ASSIGN_OR_RETURN(const std::string data, NrrdDataFileField(path));
  if (data.empty()) return v;
  if (absl::StartsWith(data, "LIST") || data.find('%') != std::string::npos) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": field 'data file' = '", data,
                                                   "' lists several files; only one is read"));
  }
  fs::path rel = fs::path(data).lexically_normal();
  const std::string r = rel.generic_string();
  if (rel.is_absolute() || r == "." || r == ".." || absl::StartsWith(r, "../")) {
    return absl::InvalidArgumentError(absl::StrCat(
        path, ": field 'data file' = '", data,
        "' lies outside the header's folder; an upload carries files beside the header only "
        "(name the data file relative to it)"));
  }
  const fs::path file = fs::path(path).parent_path() / rel;
  if (!fs::is_regular_file(file, ec)) {
    return absl::NotFoundError(absl::StrCat(path, ": field 'data file' = '", data,
                                            "': ", file.string(), " is not a file"));
  }
  if (r != name) v.files.push_back({r, file.string()});
  return v;
}

absl::StatusOr<VolumeUpload> SheetmeshClient::UploadVolumeFiles(
    const std::vector<LocalVolumeFile>& files,
    const std::function<void(int64_t, int64_t)>& progress) {
  VolumeUpload out;
  std::vector<std::string> paths;
  for (const LocalVolumeFile& f : files) {
    SM_ASSIGN_OR_RETURN(FileHash h, HashFile(f.path));
    v1::VolumeFiles::File* e = out.files.add_files();
    e->set_name(f.name);
    e->mutable_digest()->set_hash(h.hex);
    e->mutable_digest()->set_size_bytes(h.size);
    paths.push_back(f.path);
    out.total_bytes += h.size;
  }
  // Ask which the server lacks, a thousand digests at a time; send only those.
  std::set<std::string> missing;
  constexpr int kBatch = 1000;
  for (int i = 0; i < out.files.files_size(); i += kBatch) {
    v1::FindMissingBlobsRequest req;
    for (int k = i; k < std::min(i + kBatch, out.files.files_size()); ++k) {
      *req.add_digests() = out.files.files(k).digest();
    }
    v1::FindMissingBlobsResponse resp;
    SM_RETURN_IF_ERROR(FromGrpc(blobs_->FindMissingBlobs(Context().get(), req, &resp)));
    for (const v1::Digest& d : resp.missing()) missing.insert(d.hash());
  }
  int64_t to_send = 0;
  for (const v1::VolumeFiles::File& f : out.files.files()) {
    if (missing.count(f.digest().hash())) to_send += f.digest().size_bytes();
  }
  int64_t sent = 0;
  std::set<std::string> done;
  for (int i = 0; i < out.files.files_size(); ++i) {
    const v1::Digest& d = out.files.files(i).digest();
    if (!missing.count(d.hash()) || !done.insert(d.hash()).second) continue;
    SM_RETURN_IF_ERROR(WriteBlob(paths[i], d, [&](int64_t n, int64_t) {
                         if (progress) progress(sent + n, to_send);
                       }).status());
    sent += d.size_bytes();
    ++out.files_sent;
    out.bytes_sent += d.size_bytes();
  }
  if (progress) progress(to_send, to_send);
  return out;
}

absl::StatusOr<v1::Job> SheetmeshClient::CreateJob(const v1::CreateJobRequest& request) {
  v1::Job job;
  SM_RETURN_IF_ERROR(FromGrpc(jobs_->CreateJob(Context().get(), request, &job)));
  return job;
}

absl::StatusOr<v1::Job> SheetmeshClient::GetJob(const std::string& name) {
  v1::GetJobRequest req;
  req.set_name(JobName(name));
  v1::Job job;
  SM_RETURN_IF_ERROR(FromGrpc(jobs_->GetJob(Context().get(), req, &job)));
  return job;
}

absl::StatusOr<v1::ListJobsResponse> SheetmeshClient::ListJobs(const v1::ListJobsRequest& request) {
  v1::ListJobsResponse resp;
  SM_RETURN_IF_ERROR(FromGrpc(jobs_->ListJobs(Context().get(), request, &resp)));
  return resp;
}

absl::StatusOr<v1::Job> SheetmeshClient::CancelJob(const std::string& name) {
  v1::CancelJobRequest req;
  req.set_name(JobName(name));
  v1::Job job;
  SM_RETURN_IF_ERROR(FromGrpc(jobs_->CancelJob(Context().get(), req, &job)));
  return job;
}

absl::Status SheetmeshClient::DeleteJob(const std::string& name) {
  v1::DeleteJobRequest req;
  req.set_name(JobName(name));
  v1::DeleteJobResponse resp;
  return FromGrpc(jobs_->DeleteJob(Context().get(), req, &resp));
}

absl::StatusOr<v1::Job> SheetmeshClient::Watch(
    const std::string& name, const std::function<void(const v1::WatchJobResponse&)>& on_update) {
  v1::WatchJobRequest req;
  req.set_name(JobName(name));
  for (int retry = 0;; ++retry) {
    auto ctx = Context();
    std::unique_ptr<grpc::ClientReader<v1::WatchJobResponse>> reader =
        jobs_->WatchJob(ctx.get(), req);
    v1::WatchJobResponse msg;
    v1::Job last;
    while (reader->Read(&msg)) {
      last = msg.job();
      if (on_update) on_update(msg);
    }
    const grpc::Status st = reader->Finish();
    const v1::JobState s = last.state();
    if (v1::IsTerminal(s)) return last;
    if (!st.ok() && st.error_code() != grpc::StatusCode::UNAVAILABLE) return FromGrpc(st);
    if (retry >= 30) return absl::UnavailableError("the watch kept breaking; the job goes on");
    std::this_thread::sleep_for(std::chrono::seconds(1));
  }
}

absl::Status SheetmeshClient::ReadRange(
    const v1::Digest& digest, int64_t offset, int64_t length,
    const std::function<absl::Status(absl::string_view)>& sink) {
  const int64_t end = std::min(digest.size_bytes(), offset + std::max<int64_t>(0, length));
  // Ranged reads of 64 MiB, each resumable where the last stopped.
  constexpr int64_t kRange = int64_t{64} << 20;
  int failures = 0;
  while (offset < end) {
    v1::ReadRequest req;
    *req.mutable_digest() = digest;
    req.set_read_offset(offset);
    req.set_read_limit(std::min(kRange, end - offset));
    auto ctx = Context();
    std::unique_ptr<grpc::ClientReader<v1::ReadResponse>> reader = blobs_->Read(ctx.get(), req);
    v1::ReadResponse resp;
    absl::Status taken;
    while (taken.ok() && reader->Read(&resp)) {
      taken = sink(resp.data());
      offset += static_cast<int64_t>(resp.data().size());
    }
    if (!taken.ok()) {
      ctx->TryCancel();
      reader->Finish().IgnoreError();
      return taken;
    }
    const grpc::Status st = reader->Finish();
    if (!st.ok()) {
      if (st.error_code() != grpc::StatusCode::UNAVAILABLE || ++failures > 5) return FromGrpc(st);
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
  }
  return absl::OkStatus();
}

absl::Status SheetmeshClient::Download(const v1::Digest& digest, const std::string& path) {
  SM_ASSIGN_OR_RETURN(AtomicFileWriter out, AtomicFileWriter::Create(path));
  Sha256 sha;
  SM_RETURN_IF_ERROR(ReadRange(digest, 0, digest.size_bytes(), [&](absl::string_view data) {
    sha.Update(data.data(), data.size());
    return out.Append(data);
  }));
  if (sha.Hex() != digest.hash()) {
    return absl::DataLossError(
        absl::StrCat(path, ": the downloaded bytes do not match digest ", digest.hash()));
  }
  return out.Commit();
}

absl::StatusOr<std::string> SheetmeshClient::Health() {
  // The health service's messages are hand-encoded: a HealthCheckRequest with an empty
  // service name is an empty message; the response's field 1 is the status enum.
  grpc::GenericStub stub(channel_);
  auto ctx = Context();
  ctx->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(5));
  grpc::ByteBuffer request;
  grpc::Slice empty("", 0);
  request = grpc::ByteBuffer(&empty, 1);
  grpc::ByteBuffer response;
  std::mutex mu;
  std::condition_variable cv;
  bool done = false;
  grpc::Status status;
  stub.UnaryCall(ctx.get(), "/grpc.health.v1.Health/Check", grpc::StubOptions(), &request,
                 &response, [&](grpc::Status s) {
                   std::lock_guard<std::mutex> lock(mu);
                   status = s;
                   done = true;
                   cv.notify_all();
                 });
  std::unique_lock<std::mutex> lock(mu);
  cv.wait(lock, [&] { return done; });
  SM_RETURN_IF_ERROR(FromGrpc(status));
  std::vector<grpc::Slice> slices;
  response.Dump(&slices);
  std::string bytes;
  for (const auto& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  // 0x08 <status>: 1 SERVING, 2 NOT_SERVING.
  if (bytes.size() >= 2 && bytes[0] == 0x08) {
    return bytes[1] == 1 ? std::string("SERVING") : (bytes[1] == 2 ? "NOT_SERVING" : "UNKNOWN");
  }
  return std::string("UNKNOWN");
}

}  // namespace sheetmesh::client
