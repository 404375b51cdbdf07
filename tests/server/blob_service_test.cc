// The blob service over real gRPC on loopback: uploads whole and resumed, digests checked,
// find-missing, ranged reads and the size limit.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <random>
#include <thread>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "absl/time/clock.h"
#include "common/file_util.h"
#include "nlohmann/json.hpp"
#include "server/blob_store.h"
#include "tests/server/service_fixture.h"

namespace sheetmesh::testing {
namespace {

using ::testing::HasSubstr;

// The bytes of upload `resource` the server holds durably (-1 when it cannot say).
int64_t Committed(client::SheetmeshClient& c, const std::string& resource) {
  v1::QueryWriteStatusRequest q;
  q.set_resource_name(resource);
  v1::QueryWriteStatusResponse qs;
  return c.blobs()->QueryWriteStatus(c.Context().get(), q, &qs).ok() ? qs.committed_size() : -1;
}

// ---------------------------------------------------------------------------------------
// Uploads

TEST_F(ServiceTest, UploadWholeThenFindMissingAndRangedRead) {
  StartServer();
  const std::string path = dir_.File("blob.bin");
  const std::string bytes = WriteRandomFile(path, 3 * (1 << 20) + 12345, 7);
  auto digest = server::DigestOfFile(path);
  ASSERT_TRUE(digest.ok());
  EXPECT_EQ(Missing(*client_, *digest).size(), 1u);
  auto up = client_->Upload(path);
  ASSERT_TRUE(up.ok()) << up.status();
  EXPECT_EQ(up->hash(), digest->hash());
  EXPECT_TRUE(Missing(*client_, *digest).empty());
  // The whole blob back.
  ASSERT_TRUE(client_->Download(*digest, dir_.File("back.bin")).ok());
  EXPECT_EQ(Slurp(dir_.File("back.bin")), bytes);
  // A range across a piece boundary.
  v1::ReadRequest req;
  *req.mutable_digest() = *digest;
  req.set_read_offset((1 << 20) - 100);
  req.set_read_limit(5000);
  auto ctx = client_->Context();
  auto reader = client_->blobs()->Read(ctx.get(), req);
  std::string got;
  v1::ReadResponse resp;
  while (reader->Read(&resp)) got += resp.data();
  ASSERT_TRUE(reader->Finish().ok());
  EXPECT_EQ(got, bytes.substr((1 << 20) - 100, 5000));
  // Uploading again sends nothing and answers the same digest.
  int64_t reported = -1;
  auto again = client_->Upload(path, [&](int64_t sent, int64_t) { reported = sent; });
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(reported, digest->size_bytes());
}

TEST_F(ServiceTest, UploadResumesAfterBrokenStream) {
  StartServer();
  const std::string path = dir_.File("big.bin");
  const std::string bytes = WriteRandomFile(path, 11 * (1 << 20) + 77, 8);
  auto digest = server::DigestOfFile(path);
  ASSERT_TRUE(digest.ok());
  // The client library names the upload by the content: break a stream of that name
  // after eight pieces, once the server reports them durable: it writes its 8 MiB buffer
  // out as the eighth fills it, so all eight have arrived then and nothing is left over.
  const std::string resource = absl::StrCat("uploads/u", digest->hash().substr(0, 32), "/blobs/",
                                            digest->hash(), "/", digest->size_bytes());
  {
    auto ctx = client_->Context();
    v1::WriteResponse resp;
    auto writer = client_->blobs()->Write(ctx.get(), &resp);
    for (int i = 0; i < 8; ++i) {
      v1::WriteRequest req;
      if (i == 0) req.set_resource_name(resource);
      req.set_write_offset(int64_t{i} << 20);
      req.set_data(bytes.substr(static_cast<size_t>(i) << 20, size_t{1} << 20));
      ASSERT_TRUE(writer->Write(req));
    }
    const absl::Time deadline = absl::Now() + absl::Seconds(30);
    while (Committed(*client_, resource) < 8 << 20 && absl::Now() < deadline) {
      absl::SleepFor(absl::Milliseconds(20));
    }
    ASSERT_GE(Committed(*client_, resource), 8 << 20);
    ctx->TryCancel();
    EXPECT_FALSE(writer->Finish().ok());
  }
  // The broken upload is durable up to what arrived, and no blob is visible.
  v1::QueryWriteStatusRequest q;
  q.set_resource_name(resource);
  v1::QueryWriteStatusResponse qs;
  ASSERT_TRUE(client_->blobs()->QueryWriteStatus(client_->Context().get(), q, &qs).ok());
  EXPECT_EQ(qs.committed_size(), 8 << 20);
  EXPECT_FALSE(qs.complete());
  EXPECT_EQ(Missing(*client_, *digest).size(), 1u);
  // The client resumes where the server stopped: its first report is past that point.
  int64_t first_report = -1;
  auto up = client_->Upload(path, [&](int64_t sent, int64_t) {
    if (first_report < 0) first_report = sent;
  });
  ASSERT_TRUE(up.ok()) << up.status();
  EXPECT_EQ(first_report, 9 << 20);
  ASSERT_TRUE(client_->Download(*digest, dir_.File("back.bin")).ok());
  EXPECT_EQ(Slurp(dir_.File("back.bin")), bytes);
}

TEST_F(ServiceTest, UploadWithWrongDigestIsRefusedAndLeavesNoBlob) {
  StartServer();
  const std::string bytes = WriteRandomFile(dir_.File("a.bin"), 100000, 9);
  WriteRandomFile(dir_.File("b.bin"), 100000, 10);
  auto claimed = server::DigestOfFile(dir_.File("b.bin"));  // the digest of other bytes
  ASSERT_TRUE(claimed.ok());
  const std::string resource =
      absl::StrCat("uploads/liar/blobs/", claimed->hash(), "/", claimed->size_bytes());
  auto ctx = client_->Context();
  v1::WriteResponse resp;
  auto writer = client_->blobs()->Write(ctx.get(), &resp);
  v1::WriteRequest req;
  req.set_resource_name(resource);
  req.set_data(bytes);
  req.set_finish_write(true);
  writer->Write(req);
  writer->WritesDone();
  grpc::Status st = writer->Finish();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(st.error_message(), HasSubstr(claimed->hash()));
  EXPECT_EQ(Missing(*client_, *claimed).size(), 1u);
  // Nothing of it is left in the store: not a blob, not a part file.
  for (const auto& e :
       std::filesystem::recursive_directory_iterator(options_.data_dir + "/blobs")) {
    EXPECT_FALSE(e.is_regular_file()) << e.path();
  }
}

TEST_F(ServiceTest, UploadLargerThanTheLimitIsResourceExhausted) {
  options_.limits.max_blob_bytes = 1000;
  StartServer();
  WriteRandomFile(dir_.File("a.bin"), 5000, 11);
  auto up = client_->Upload(dir_.File("a.bin"));
  ASSERT_FALSE(up.ok());
  EXPECT_EQ(up.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(up.status().message(), HasSubstr("max_blob_bytes"));
}

TEST_F(ServiceTest, MalformedResourceNameIsInvalidArgument) {
  StartServer();
  auto ctx = client_->Context();
  v1::WriteResponse resp;
  auto writer = client_->blobs()->Write(ctx.get(), &resp);
  v1::WriteRequest req;
  req.set_resource_name("uploads/x/../../etc/blobs/abc/3");
  req.set_data("abc");
  writer->Write(req);
  writer->WritesDone();
  grpc::Status st = writer->Finish();
  EXPECT_EQ(st.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_THAT(st.error_message(), HasSubstr("resource_name"));
}

}  // namespace
}  // namespace sheetmesh::testing
