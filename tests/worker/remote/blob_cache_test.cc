// The remote worker's cache of uploaded volumes (blob_cache.h), over a blob held in memory:
// what is fetched, whole or in ranges, and what stays.
#include "worker/remote/blob_cache.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>

#include "common/file_util.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh::remote {
namespace {

using runtime::ByteRange;
using ::testing::HasSubstr;

class BlobCacheTest : public ::testing::Test {
 protected:
  BlobCacheTest()
      : cache_(
            tmp_.File("cache"),
            [this](const v1::Digest& d, const std::string& path) {
              ++downloads_;
              return WriteFileAtomically(path, Blob(d));
            },
            [this](const v1::Digest& d, int64_t offset, int64_t length,
                   const std::function<absl::Status(absl::string_view)>& sink) -> absl::Status {
              requests_.push_back({offset, length});
              const std::string blob = Blob(d);
              const int64_t end = std::min<int64_t>(offset + length, blob.size());
              if (fail_at_ >= 0 && offset <= fail_at_ && fail_at_ < end) {
                return absl::UnavailableError("the server went away");
              }
              // In two pieces, as a stream sends them.
              const int64_t mid = offset + (end - offset) / 2;
              if (absl::Status st = sink(absl::string_view(blob).substr(offset, mid - offset));
                  !st.ok()) {
                return st;
              }
              return sink(absl::string_view(blob).substr(mid, end - mid));
            }) {}

  // The blob of a digest: its hash's bytes over and over.
  static std::string Blob(const v1::Digest& d) {
    std::string s;
    for (int64_t i = 0; i < d.size_bytes(); ++i)
      s.push_back(static_cast<char>(d.hash()[i % 8] + i));
    return s;
  }
  static v1::Digest Digest(const std::string& hash, int64_t size) {
    v1::Digest d;
    d.set_hash(hash);
    d.set_size_bytes(size);
    return d;
  }
  // The bytes of `path` in `r` equal the blob's.
  static void ExpectHolds(const std::string& path, const v1::Digest& d, ByteRange r) {
    const std::string got = *ReadFileToString(path);
    ASSERT_EQ(static_cast<int64_t>(got.size()), d.size_bytes());
    EXPECT_EQ(got.substr(r.offset, r.length), Blob(d).substr(r.offset, r.length));
  }

  sheetmesh::testing::TempDir tmp_;
  BlobCache cache_;
  int downloads_ = 0;
  std::vector<ByteRange> requests_;
  int64_t fail_at_ = -1;
};

TEST_F(BlobCacheTest, ABricksRangesAreFetchedOnceAndOnlyWhatIsMissingAfter) {
  const v1::Digest d = Digest("aaaaaaaa", 1000);
  const std::vector<ByteRange> first = {{100, 50}, {10, 20}, {25, 10}};
  absl::StatusOr<std::string> path = cache_.Get("jobs/1", d, &first);
  ASSERT_TRUE(path.ok()) << path.status();
  EXPECT_EQ(requests_, (std::vector<ByteRange>{{10, 25}, {100, 50}})) << "sorted and joined";
  ExpectHolds(*path, d, {10, 25});
  ExpectHolds(*path, d, {100, 50});
  EXPECT_EQ(ReadFileToString(*path)->substr(500, 10), std::string(10, '\0')) << "not fetched";
  EXPECT_EQ(cache_.fetched_bytes(), 75);
  // The next brick of the volume: only what the file lacks, and nothing past its end.
  requests_.clear();
  const std::vector<ByteRange> second = {{20, 200}, {990, 100}};
  path = cache_.Get("jobs/2", d, &second);
  ASSERT_TRUE(path.ok()) << path.status();
  EXPECT_EQ(requests_, (std::vector<ByteRange>{{35, 65}, {150, 70}, {990, 10}}));
  ExpectHolds(*path, d, {10, 210});
  ExpectHolds(*path, d, {990, 10});
  EXPECT_EQ(cache_.fetched_bytes(), 75 + 145);
  requests_.clear();
  EXPECT_TRUE(cache_.Get("jobs/3", d, &first).ok());
  EXPECT_TRUE(requests_.empty()) << "all there";
  EXPECT_EQ(downloads_, 0);

  // A task that needs it all downloads it whole (checked by its digest); after that the
  // ranges are served from the whole file, and the part goes.
  path = cache_.Get("jobs/4", d, nullptr);
  ASSERT_TRUE(path.ok()) << path.status();
  EXPECT_EQ(downloads_, 1);
  EXPECT_EQ(*ReadFileToString(*path), Blob(d));
  EXPECT_FALSE(std::filesystem::exists(tmp_.File("cache/aaaaaaaa.part")));
  requests_.clear();
  EXPECT_EQ(*cache_.Get("jobs/5", d, &second), *path);
  EXPECT_TRUE(requests_.empty());
}

TEST_F(BlobCacheTest, AFetchThatBreaksOffKeepsWhatCameBeforeAndTheOldVolumeGoes) {
  const v1::Digest d = Digest("bbbbbbbb", 4096);
  const std::vector<ByteRange> want = {{0, 100}, {1000, 100}, {3000, 100}};
  fail_at_ = 1050;
  const absl::StatusOr<std::string> broken = cache_.Get("jobs/1", d, &want);
  EXPECT_EQ(broken.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(broken.status().message(), HasSubstr("went away"));
  cache_.Release("jobs/1");
  fail_at_ = -1;
  requests_.clear();
  const absl::StatusOr<std::string> path = cache_.Get("jobs/2", d, &want);
  ASSERT_TRUE(path.ok()) << path.status();
  EXPECT_EQ(requests_, (std::vector<ByteRange>{{1000, 100}, {3000, 100}}))
      << "the first range came before the break";
  for (const ByteRange& r : want) ExpectHolds(*path, d, r);
  cache_.Release("jobs/2");
  // Another volume's task ends too: the first volume, idle, stays until this one is idle.
  const v1::Digest e = Digest("cccccccc", 64);
  ASSERT_TRUE(cache_.Get("jobs/3", e, nullptr).ok());
  EXPECT_TRUE(std::filesystem::exists(tmp_.File("cache/bbbbbbbb.part")));
  cache_.Release("jobs/3");
  for (const char* f : {"bbbbbbbb.part", "bbbbbbbb.ranges", "bbbbbbbb"}) {
    EXPECT_FALSE(std::filesystem::exists(tmp_.File(std::string("cache/") + f))) << f;
  }
  EXPECT_TRUE(std::filesystem::exists(tmp_.File("cache/cccccccc")));
}

TEST(JoinRangesTest, SortsClipsAndJoins) {
  EXPECT_EQ(JoinRanges({{50, 10}, {-5, 10}, {5, 0}, {58, 5}, {95, 20}, {200, 1}}, 100),
            (std::vector<ByteRange>{{0, 5}, {50, 13}, {95, 5}}));
  EXPECT_TRUE(JoinRanges({{10, -3}}, 100).empty());
}

}  // namespace
}  // namespace sheetmesh::remote
