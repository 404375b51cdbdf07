// The server's stores on their own: the content-addressed blob store, the SQLite job
// store's migration (the rest of the job stores' contract is job_store_conformance_test),
// references under allowed roots, and the job events watchers wait on.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "absl/strings/str_cat.h"
#include "common/file_util.h"
#include "common/sha256.h"
#include "server/blob_store.h"
#include "server/job_events.h"
#include "server/job_store.h"
#include "server/references.h"
#include "tests/testing/temp_dir.h"

namespace sheetmesh::server {
namespace {

using sheetmesh::testing::TempDir;
using ::testing::HasSubstr;

v1::Digest DigestOf(const std::string& bytes) {
  v1::Digest d;
  d.set_hash(Sha256Hex(bytes));
  d.set_size_bytes(bytes.size());
  return d;
}

std::string Resource(const std::string& id, const v1::Digest& d) {
  return absl::StrCat("uploads/", id, "/blobs/", d.hash(), "/", d.size_bytes());
}

// One tenant's uploads, the blob counted as its own when stored.
absl::StatusOr<BlobStore::UploadState> Append(BlobStore& s, const std::string& r, int64_t offset,
                                              absl::string_view data, bool finish,
                                              int64_t max_bytes) {
  return s.Append("t", r, offset, data, finish, max_bytes, true);
}
absl::StatusOr<BlobStore::UploadState> Status(BlobStore& s, const std::string& r) {
  return s.Status("t", r, true);
}

// ---------------------------------------------------------------------------------------
// BlobStore

TEST(BlobStoreTest, AppendInPiecesThenFinish) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  const std::string bytes = "the quick brown fox jumps over the lazy dog";
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("a1", d);
  EXPECT_FALSE((*store)->Contains(d));
  auto s1 = Append(**store, r, 0, bytes.substr(0, 10), false, 1 << 20);
  ASSERT_TRUE(s1.ok()) << s1.status();
  EXPECT_FALSE((*store)->Contains(d));  // nothing visible before the end
  auto s2 = Append(**store, r, 10, bytes.substr(10), true, 1 << 20);
  ASSERT_TRUE(s2.ok()) << s2.status();
  EXPECT_TRUE(s2->complete);
  EXPECT_TRUE((*store)->Contains(d));
  auto path = (*store)->PathOf(d);
  ASSERT_TRUE(path.ok());
  EXPECT_EQ(*ReadFileToString(*path), bytes);
  // The sha256 helper agrees with a known vector.
  EXPECT_EQ(d.hash(), "05c6e08f1d9fdafa03147fcb8f82f124c76d2f70e3d989dc8aadb5e7d7450bec");
}

TEST(BlobStoreTest, OverlappingPiecesAreSkippedAndGapsRefused) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  const std::string bytes(1000, 'x');
  const v1::Digest d = DigestOf(bytes + "yz");
  const std::string r = Resource("a2", d);
  ASSERT_TRUE(Append(**store, r, 0, bytes.substr(0, 600), false, 1 << 20).ok());
  // A resumed writer starting earlier: the overlap is dropped.
  ASSERT_TRUE(Append(**store, r, 500, bytes.substr(500), false, 1 << 20).ok());
  // A gap is refused, naming the offset.
  auto gap = Append(**store, r, 1500, "zz", false, 1 << 20);
  EXPECT_EQ(gap.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(gap.status().message(), HasSubstr("write_offset 1500"));
  auto done = Append(**store, r, 1000, "yz", true, 1 << 20);
  ASSERT_TRUE(done.ok()) << done.status();
  EXPECT_TRUE((*store)->Contains(d));
}

TEST(BlobStoreTest, DigestMismatchDiscardsTheUpload) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  const v1::Digest claimed = DigestOf("something else");
  const std::string r = Resource("a3", claimed);
  auto st = Append(**store, r, 0, "something ELSE", true, 1 << 20);
  EXPECT_EQ(st.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(st.status().message(), HasSubstr(claimed.hash()));
  EXPECT_FALSE((*store)->Contains(claimed));
  auto status = Status(**store, r);
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status->committed, 0);
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.File("blobs"))) {
    EXPECT_FALSE(e.is_regular_file()) << e.path();
  }
}

TEST(BlobStoreTest, UploadResumesAfterReopening) {
  TempDir dir;
  const std::string bytes = std::string(3000, 'a') + std::string(3000, 'b');
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("a4", d);
  {
    auto store = BlobStore::Open(dir.File("blobs"));
    ASSERT_TRUE(store.ok());
    ASSERT_TRUE(Append(**store, r, 0, bytes.substr(0, 2500), false, 1 << 20).ok());
    ASSERT_TRUE((*store)->EndStream("t", r).ok());
  }
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  auto status = Status(**store, r);
  ASSERT_TRUE(status.ok());
  EXPECT_EQ(status->committed, 2500);
  ASSERT_TRUE(Append(**store, r, 2500, bytes.substr(2500), true, 1 << 20).ok());
  EXPECT_EQ(*ReadFileToString(*(*store)->PathOf(d)), bytes);
}

TEST(BlobStoreTest, AnEndedStreamClosesItsFilesAndExpiryRemovesTheUpload) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  const std::string bytes(10000, 'e');
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("exp", d);
  ASSERT_TRUE(Append(**store, r, 0, bytes.substr(0, 4000), false, 1 << 20).ok());
  EXPECT_EQ((*store)->open_uploads(), 1);
  ASSERT_TRUE((*store)->EndStream("t", r).ok());
  EXPECT_EQ((*store)->open_uploads(), 0);
  // Resumed: the files reopen, the hash goes on.
  ASSERT_TRUE(Append(**store, r, 4000, bytes.substr(4000, 2000), false, 1 << 20).ok());
  ASSERT_TRUE((*store)->EndStream("t", r).ok());
  EXPECT_EQ((*store)->ExpireUploads(absl::Hours(1)), 0) << "written just now";
  EXPECT_EQ((*store)->ExpireUploads(absl::ZeroDuration()), 1);
  EXPECT_EQ(Status(**store, r)->committed, 0);
  for (const auto& e : std::filesystem::recursive_directory_iterator(dir.File("blobs"))) {
    EXPECT_FALSE(e.is_regular_file()) << e.path();
  }
}

TEST(BlobStoreTest, ABlobStoredAlreadyCountsOnlyForItsOwner) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  const std::string bytes = "owned content";
  const v1::Digest d = DigestOf(bytes);
  ASSERT_TRUE(Append(**store, Resource("o1", d), 0, bytes, true, 1 << 20).ok());
  // A tenant that does not own it must send the bytes: naming the digest is not enough.
  auto claim = (*store)->Append("other", Resource("o2", d), 0, "", true, 1 << 20, false);
  EXPECT_EQ(claim.status().code(), absl::StatusCode::kInvalidArgument);
  auto sent = (*store)->Append("other", Resource("o3", d), 0, bytes, true, 1 << 20, false);
  ASSERT_TRUE(sent.ok()) << sent.status();
  EXPECT_TRUE(sent->complete);
  EXPECT_EQ(*ReadFileToString(*(*store)->PathOf(d)), bytes);
}

TEST(BlobStoreTest, LimitsAndMalformedNames) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  const v1::Digest d = DigestOf(std::string(100, 'q'));
  auto big = Append(**store, Resource("a5", d), 0, "q", false, 50);
  EXPECT_EQ(big.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_THAT(big.status().message(), HasSubstr("max_blob_bytes"));
  for (const std::string& bad : {std::string("uploads/a/blobs/xyz/3"), std::string("blobs/abc"),
                                 absl::StrCat("uploads/a b/blobs/", d.hash(), "/100"),
                                 absl::StrCat("uploads/a/blobs/", d.hash(), "/-1")}) {
    EXPECT_EQ(Append(**store, bad, 0, "q", false, 1 << 20).status().code(),
              absl::StatusCode::kInvalidArgument)
        << bad;
  }
}

TEST(BlobStoreTest, PutFileAndConcurrentWritersOfTheSameContent) {
  TempDir dir;
  auto store = BlobStore::Open(dir.File("blobs"));
  ASSERT_TRUE(store.ok());
  std::ofstream(dir.File("f")) << "file contents";
  auto put = (*store)->PutFile(dir.File("f"));
  ASSERT_TRUE(put.ok());
  EXPECT_EQ(put->hash(), DigestOf("file contents").hash());
  // Four writers of one upload, piece by piece: the store ends with the right blob.
  std::string bytes;
  for (int i = 0; i < 4000; ++i) bytes += static_cast<char>('a' + i % 26);
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("shared", d);
  std::vector<std::thread> writers;
  for (int w = 0; w < 4; ++w) {
    writers.emplace_back([&] {
      for (int64_t off = 0; off < 4000; off += 100) {
        auto st = Append(**store, r, off, absl::string_view(bytes).substr(off, 100),
                         off + 100 == 4000, 1 << 20);
        if (!st.ok() || st->complete) return;
      }
    });
  }
  for (auto& t : writers) t.join();
  ASSERT_TRUE((*store)->Contains(d));
  EXPECT_EQ(*ReadFileToString(*(*store)->PathOf(d)), bytes);
}

// Replicas over one database share one blob folder: two stores on the same root.
int PartFiles(const std::string& root) {
  int n = 0;
  for (const auto& e : std::filesystem::recursive_directory_iterator(root)) {
    n += e.is_regular_file() && e.path().extension() == ".part";
  }
  return n;
}

class SharedBlobFolderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto sa = BlobStore::Open(dir.File("blobs"));
    auto sb = BlobStore::Open(dir.File("blobs"));
    ASSERT_TRUE(sa.ok() && sb.ok());
    a = std::move(*sa);
    b = std::move(*sb);
  }
  TempDir dir;
  std::unique_ptr<BlobStore> a, b;
};

TEST_F(SharedBlobFolderTest, ReplicasWritingOneUploadAtOnceBothStoreIt) {
  std::string bytes;
  for (int i = 0; i < 30000; ++i) bytes += static_cast<char>('A' + i % 23);
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("same", d);  // two writers of one content name it alike
  ASSERT_TRUE(Append(*a, r, 0, bytes.substr(0, 10000), false, 1 << 20).ok());
  // A's stream holds the file: B writes a copy of its own, from where its writer is.
  auto b1 = Append(*b, r, 0, bytes.substr(0, 5000), false, 1 << 20);
  ASSERT_TRUE(b1.ok()) << b1.status();
  EXPECT_EQ(PartFiles(dir.File("blobs")), 2);
  // A writer that learnt A's state and resumes at B is told to ask again, not refused.
  auto ahead = Append(*b, r, 20000, bytes.substr(20000), true, 1 << 20);
  EXPECT_EQ(ahead.status().code(), absl::StatusCode::kUnavailable) << ahead.status();
  EXPECT_THAT(ahead.status().message(), HasSubstr("query the status"));
  // Expiry at B leaves the file A is writing.
  EXPECT_EQ(b->ExpireUploads(absl::ZeroDuration()), 0);
  auto a2 = Append(*a, r, 10000, bytes.substr(10000), true, 1 << 20);
  ASSERT_TRUE(a2.ok()) << a2.status();
  EXPECT_TRUE(a2->complete);
  auto b2 = Append(*b, r, 5000, bytes.substr(5000), true, 1 << 20);
  ASSERT_TRUE(b2.ok()) << b2.status();
  EXPECT_TRUE(b2->complete);
  EXPECT_EQ(*ReadFileToString(*a->PathOf(d)), bytes);
  EXPECT_EQ(PartFiles(dir.File("blobs")), 0);
}

TEST_F(SharedBlobFolderTest, AReplicaSeesWhatAnotherWroteOrStored) {
  const std::string bytes = std::string(7000, 'x') + std::string(7000, 'y');
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("moved", d);
  // B knew the upload at 1000 bytes; A's stream took it to 6000 since.
  ASSERT_TRUE(Append(*b, r, 0, bytes.substr(0, 1000), false, 1 << 20).ok());
  ASSERT_TRUE(b->EndStream("t", r).ok());
  ASSERT_TRUE(Append(*a, r, 1000, bytes.substr(1000, 5000), false, 1 << 20).ok());
  ASSERT_TRUE(a->EndStream("t", r).ok());
  EXPECT_EQ(Status(*b, r)->committed, 6000);
  // B resumes the same file (A's stream ended, so its lock is free) and stores the blob.
  auto b2 = Append(*b, r, 6000, bytes.substr(6000), true, 1 << 20);
  ASSERT_TRUE(b2.ok()) << b2.status();
  EXPECT_TRUE(b2->complete);
  EXPECT_EQ(PartFiles(dir.File("blobs")), 0) << "one file, no copy";
  // A's upload entry is stale: its status and a write both find the stored blob.
  auto as = Status(*a, r);
  ASSERT_TRUE(as.ok());
  EXPECT_TRUE(as->complete);
  auto a3 = Append(*a, r, 6000, bytes.substr(6000), true, 1 << 20);
  ASSERT_TRUE(a3.ok()) << a3.status();
  EXPECT_TRUE(a3->complete);
  EXPECT_EQ(*ReadFileToString(*a->PathOf(d)), bytes);

  // A stale entry whose file a replica removed (expired) starts again from nothing.
  const std::string other = std::string(5000, 'z');
  const std::string r2 = Resource("gone", DigestOf(other));
  ASSERT_TRUE(Append(*a, r2, 0, other.substr(0, 3000), false, 1 << 20).ok());
  ASSERT_TRUE(a->EndStream("t", r2).ok());
  EXPECT_EQ(Status(*b, r2)->committed, 3000);
  EXPECT_EQ(a->ExpireUploads(absl::ZeroDuration()), 1);
  EXPECT_EQ(Status(*b, r2)->committed, 0);
  auto resumed = Append(*b, r2, 3000, other.substr(3000), true, 1 << 20);
  EXPECT_EQ(resumed.status().code(), absl::StatusCode::kInvalidArgument) << resumed.status();
  auto again = Append(*b, r2, 0, other, true, 1 << 20);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_TRUE(again->complete);
}

TEST_F(SharedBlobFolderTest, ConcurrentWritersAtTwoReplicasAllSucceed) {
  std::string bytes;
  for (int i = 0; i < 200000; ++i) bytes += static_cast<char>(i * 7919 % 251);
  const v1::Digest d = DigestOf(bytes);
  const std::string r = Resource("race", d);
  // Each writer sends the whole blob in pieces as a client does: on kUnavailable it asks
  // for the status and resumes from there. Any other error fails the test.
  std::vector<absl::Status> errors(4);
  std::vector<std::thread> writers;
  for (int w = 0; w < 4; ++w) {
    writers.emplace_back([&, w] {
      BlobStore& s = w % 2 ? *b : *a;
      int64_t off = 0;
      for (int step = 0; step < 10000; ++step) {
        const int64_t n = std::min<int64_t>(7000, bytes.size() - off);
        auto st = Append(s, r, off, absl::string_view(bytes).substr(off, n),
                         off + n == static_cast<int64_t>(bytes.size()), 1 << 20);
        if (st.ok() && st->complete) return;
        if (st.ok()) {
          off += n;
          if (step % 5 == 4) {  // the stream breaks now and then
            errors[w].Update(s.EndStream("t", r));
            off = Status(s, r)->committed;
          }
          continue;
        }
        if (st.status().code() != absl::StatusCode::kUnavailable) {
          errors[w] = st.status();
          return;
        }
        errors[w].Update(s.EndStream("t", r));
        auto now = Status(s, r);
        if (!now.ok()) {
          errors[w] = now.status();
          return;
        }
        if (now->complete) return;
        off = now->committed;
      }
      errors[w] = absl::DeadlineExceededError("no end");
    });
  }
  for (auto& t : writers) t.join();
  for (const absl::Status& e : errors) EXPECT_TRUE(e.ok()) << e;
  ASSERT_TRUE(a->Contains(d));
  EXPECT_EQ(*ReadFileToString(*b->PathOf(d)), bytes);
  EXPECT_EQ(PartFiles(dir.File("blobs")), 0);
}

// ---------------------------------------------------------------------------------------
// SQLite job store

v1::Job NewJob(const std::string& request_id) {
  v1::Job j;
  j.set_request_id(request_id);
  j.mutable_input()->set_volume_path("/data/" + request_id);
  j.set_pipeline_version("test");
  return j;
}

TEST(JobStoreTest, AStoreFromBeforeTenantsIsTheDefaultTenants) {
  TempDir dir;
  {
    // The 0.8 schema, with one job naming an input blob.
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(dir.File("jobs.db").c_str(), &db), SQLITE_OK);
    v1::Job old = NewJob("old-request");
    old.set_name("jobs/000000000001-0000abcd");
    old.set_state(v1::SUCCEEDED);
    old.mutable_input()->mutable_volume_digest()->set_hash(std::string(64, 'c'));
    const std::string blob = old.SerializeAsString();
    ASSERT_EQ(sqlite3_exec(db,
                           "CREATE TABLE jobs (id TEXT PRIMARY KEY, seq INTEGER NOT NULL, "
                           "request_id TEXT UNIQUE NOT NULL, state INTEGER NOT NULL, lease_owner "
                           "TEXT, lease_expires INTEGER, cancel_requested INTEGER NOT NULL DEFAULT "
                           "0, cache_key TEXT, job BLOB NOT NULL)",
                           nullptr, nullptr, nullptr),
              SQLITE_OK);
    sqlite3_stmt* st = nullptr;
    sqlite3_prepare_v2(db,
                       "INSERT INTO jobs (id, seq, request_id, state, job) VALUES "
                       "('000000000001-0000abcd', 1, 'old-request', 3, ?)",
                       -1, &st, nullptr);
    sqlite3_bind_blob(st, 1, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT);
    ASSERT_EQ(sqlite3_step(st), SQLITE_DONE);
    sqlite3_finalize(st);
    sqlite3_close(db);
  }
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok()) << store.status();
  auto found = (*store)->FindByRequestId("default", "old-request");
  ASSERT_TRUE(found.ok() && found->has_value());
  EXPECT_EQ((*found)->tenant(), "default");
  std::string next;
  EXPECT_EQ((*store)->List("default", v1::JOB_STATE_UNSPECIFIED, 10, "", &next)->size(), 1u);
  EXPECT_TRUE(*(*store)->OwnsBlob("default", std::string(64, 'c')));
}

// ---------------------------------------------------------------------------------------
// References

TEST(ReferencesTest, OnlyUnderTheRootsAfterFollowingLinks) {
  TempDir dir;
  std::filesystem::create_directories(dir.File("root/sub"));
  std::filesystem::create_directories(dir.File("rootish"));
  std::ofstream(dir.File("root/sub/v.raw")) << "x";
  std::ofstream(dir.File("rootish/v.raw")) << "x";
  std::ofstream(dir.File("secret.raw")) << "x";
  std::filesystem::create_symlink(dir.File("secret.raw"), dir.File("root/link.raw"));
  std::filesystem::create_symlink(dir.File("root/sub/v.raw"), dir.File("root/inner.raw"));
  const std::vector<std::string> roots = {dir.File("root")};
  auto ok = ResolveReference(dir.File("root/sub/v.raw"), roots);
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_EQ(*ok, std::filesystem::canonical(dir.File("root/sub/v.raw")).string());
  EXPECT_TRUE(ResolveReference(dir.File("root/inner.raw"), roots).ok());
  for (const std::string& bad :
       {dir.File("secret.raw"), dir.File("root/link.raw"), dir.File("root/sub/../../secret.raw"),
        dir.File("rootish/v.raw")}) {
    auto r = ResolveReference(bad, roots);
    EXPECT_EQ(r.status().code(), absl::StatusCode::kPermissionDenied) << bad << ": " << r.status();
  }
  EXPECT_EQ(ResolveReference("relative.raw", roots).status().code(),
            absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(ResolveReference(dir.File("root/none.raw"), roots).status().code(),
            absl::StatusCode::kNotFound);
  EXPECT_EQ(ResolveReference(dir.File("root/sub/v.raw"), {}).status().code(),
            absl::StatusCode::kPermissionDenied);
}

// ---------------------------------------------------------------------------------------
// JobEvents

TEST(JobEventsTest, WaitersWakeAndStagesAreKeptInOrder) {
  JobEvents events;
  const uint64_t v0 = events.Version("jobs/1");
  std::thread later([&] {
    absl::SleepFor(absl::Milliseconds(50));
    for (int i = 1; i <= 3; ++i) {
      v1::JobProgress p;
      p.set_stage_index(i);
      events.NotifyStage("jobs/1", p);
    }
  });
  const uint64_t v1 = events.Wait("jobs/1", v0, absl::Seconds(10));
  EXPECT_GT(v1, v0);
  later.join();
  const auto stages = events.StagesSince("jobs/1", v0);
  ASSERT_EQ(stages.size(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(stages[i].stage_index(), i + 1);
  EXPECT_EQ(events.StagesSince("jobs/1", events.Version("jobs/1")).size(), 0u);
  // A wait with nothing new times out; Close wakes for good.
  const uint64_t now = events.Version("jobs/1");
  EXPECT_EQ(events.Wait("jobs/1", now, absl::Milliseconds(10)), now);
  events.Close();
  EXPECT_TRUE(events.closed());
  EXPECT_EQ(events.Wait("jobs/1", now, absl::Hours(1)), now);
}

TEST(JobEventsTest, FinishedJobsAreForgottenAfterALimit) {
  JobEvents events;
  for (size_t i = 0; i < JobEvents::kFinishedKept + 10; ++i) {
    const std::string name = absl::StrCat("jobs/", i);
    v1::JobProgress p;
    events.NotifyStage(name, p);
    events.NotifyFinished(name);
  }
  EXPECT_EQ(events.Version("jobs/0"), 0u);  // forgotten
  EXPECT_GT(events.Version(absl::StrCat("jobs/", JobEvents::kFinishedKept + 5)), 0u);
}

}  // namespace
}  // namespace sheetmesh::server
