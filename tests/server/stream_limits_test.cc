#include "server/stream_limits.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sheetmesh::server {
namespace {

using ::testing::HasSubstr;

TEST(StreamLimitsTest, EachClientAndTheServerHaveTheirLimitAndClosingFreesAPlace) {
  StreamLimits limits("watch", "max_watch_streams", /*per_client=*/2, /*total=*/3);
  auto a1 = limits.Acquire("tenant:a");
  auto a2 = limits.Acquire("tenant:a");
  ASSERT_TRUE(a1.ok() && a2.ok());
  auto a3 = limits.Acquire("tenant:a");
  ASSERT_FALSE(a3.ok());
  EXPECT_EQ(a3.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(
      a3.status().message(),
      HasSubstr("tenant:a has 2 open, the limit per client (--max_watch_streams_per_client)"));
  auto b1 = limits.Acquire("tenant:b");
  ASSERT_TRUE(b1.ok());
  auto b2 = limits.Acquire("tenant:b");
  ASSERT_FALSE(b2.ok());
  EXPECT_THAT(b2.status().message(),
              HasSubstr("the server has 3 open, its limit (--max_watch_streams)"));
  EXPECT_EQ(limits.open(), 3);
  // A refused client holds no place; a released slot frees one, once.
  EXPECT_EQ(limits.open_of("tenant:c"), 0);
  a1->Release();
  a1->Release();
  EXPECT_EQ(limits.open(), 2);
  EXPECT_EQ(limits.open_of("tenant:a"), 1);
  ASSERT_TRUE(limits.Acquire("tenant:b").ok());  // and freed again as the slot goes
  EXPECT_EQ(limits.open(), 2);
}

TEST(StreamLimitsTest, AMovedSlotFreesItsPlaceOnce) {
  StreamLimits limits("upload", "max_upload_streams", 1, 1);
  {
    auto s = limits.Acquire("peer:1.2.3.4");
    ASSERT_TRUE(s.ok());
    StreamLimits::Slot moved = std::move(*s);
    EXPECT_EQ(limits.open(), 1);
  }
  EXPECT_EQ(limits.open(), 0);
  EXPECT_TRUE(limits.Acquire("peer:1.2.3.4").ok());
}

}  // namespace
}  // namespace sheetmesh::server
