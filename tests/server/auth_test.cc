#include "server/auth.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "common/file_util.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh::server {
namespace {

using sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

absl::StatusOr<Tenants> FromText(TempDir& dir, const std::string& text) {
  const std::string path = dir.File("tokens");
  EXPECT_TRUE(WriteFileAtomically(path, text).ok());
  return Tenants::FromFile(path);
}

TEST(TenantsTest, ATokenFileNamesTenantsAndSkipsCommentsAndBlankLines) {
  TempDir dir;
  auto t = FromText(dir, "# lab tokens\n\nsecret-a  geo_lab\nsecret-b # the default tenant\n");
  ASSERT_TRUE(t.ok()) << t.status();
  EXPECT_FALSE(t->open());
  EXPECT_FALSE(t->has_worker_tokens());
}

TEST(TenantsTest, AMalformedFileIsRefusedNamingTheLine) {
  TempDir dir;
  struct Case {
    std::string text, error;
  } cases[] = {
      {"a b c\n", "tokens line 1: expected 'TOKEN [TENANT]', found 3 words"},
      {"x one\n\ny one\nx two\n", "tokens line 4: this token is given twice"},
      {"t bad/name\n", "tokens line 1: tenant 'bad/name' must be"},
      {"t .hidden\n", "tenant '.hidden' must be"},
      {"# nothing\n\n", "holds no token"},
  };
  for (const Case& c : cases) {
    auto t = FromText(dir, c.text);
    ASSERT_FALSE(t.ok()) << c.text;
    EXPECT_EQ(t.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_THAT(t.status().message(), HasSubstr(c.error)) << c.text;
  }
  EXPECT_EQ(Tenants::FromFile(dir.File("missing")).status().code(), absl::StatusCode::kNotFound);
}

TEST(TenantsTest, WorkersHaveATokenOfTheirOwn) {
  auto t = Tenants::FromToken("tenant-secret");
  ASSERT_TRUE(t.ok());
  EXPECT_FALSE(t->open());
  EXPECT_THAT(t->AddWorkerToken("", "--worker_token_file").message(), HasSubstr("is empty"));
  EXPECT_THAT(t->AddWorkerToken("tenant-secret", "workers.txt").message(),
              HasSubstr("workers.txt: the worker token is also a tenant's token"));
  EXPECT_TRUE(t->AddWorkerToken("worker-secret", "workers.txt").ok());
  EXPECT_TRUE(t->has_worker_tokens());
  // No token: an open server.
  EXPECT_TRUE(Tenants::FromToken("")->open());
}

}  // namespace
}  // namespace sheetmesh::server
