// The server's stores on their own: the content-addressed blob store, the SQLite job
// store, references under allowed roots, and the job events watchers wait on.
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

// ---------------------------------------------------------------------------------------
// SQLite job store

v1::Job NewJob(const std::string& request_id) {
  v1::Job j;
  j.set_request_id(request_id);
  j.mutable_input()->set_volume_path("/data/" + request_id);
  j.set_pipeline_version("test");
  return j;
}

TEST(JobStoreTest, CreateIsIdempotentByRequestId) {
  TempDir dir;
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok()) << store.status();
  bool created = false;
  auto a = (*store)->Create(NewJob("r1"), "k1", &created);
  ASSERT_TRUE(a.ok());
  EXPECT_TRUE(created);
  EXPECT_EQ(a->state(), v1::QUEUED);
  EXPECT_THAT(a->name(), ::testing::StartsWith("jobs/"));
  auto b = (*store)->Create(NewJob("r1"), "k1", &created);
  ASSERT_TRUE(b.ok());
  EXPECT_FALSE(created);
  EXPECT_EQ(a->name(), b->name());
  auto found = (*store)->FindByRequestId("default", "r1");
  ASSERT_TRUE(found.ok() && found->has_value());
  EXPECT_EQ((*found)->name(), a->name());
  EXPECT_EQ((*store)->Get("jobs/none").status().code(), absl::StatusCode::kNotFound);
}

TEST(JobStoreTest, TenantsHaveTheirOwnRequestIdsListsAndBlobs) {
  TempDir dir;
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok());
  bool created = false;
  v1::Job a = NewJob("same");
  a.set_tenant("alice");
  a.mutable_input()->mutable_volume_digest()->set_hash(std::string(64, 'a'));
  v1::Job b = NewJob("same");
  b.set_tenant("bob");
  auto ja = (*store)->Create(a, "k", &created);
  ASSERT_TRUE(ja.ok() && created);
  auto jb = (*store)->Create(b, "k", &created);
  ASSERT_TRUE(jb.ok() && created) << "the same request id in another tenant is another job";
  EXPECT_NE(ja->name(), jb->name());
  std::string next;
  auto alices = (*store)->List("alice", v1::JOB_STATE_UNSPECIFIED, 10, "", &next);
  ASSERT_TRUE(alices.ok());
  ASSERT_EQ(alices->size(), 1u);
  EXPECT_EQ((*alices)[0].name(), ja->name());
  EXPECT_TRUE(*(*store)->OwnsBlob("alice", std::string(64, 'a'))) << "her job's input";
  EXPECT_FALSE(*(*store)->OwnsBlob("bob", std::string(64, 'a')));
  ASSERT_TRUE((*store)->AddUploadedBlob("bob", std::string(64, 'b')).ok());
  EXPECT_TRUE(*(*store)->OwnsBlob("bob", std::string(64, 'b')));
  EXPECT_FALSE(*(*store)->OwnsBlob("alice", std::string(64, 'b')));
  EXPECT_EQ(*(*store)->ReferencedBlobs(), std::set<std::string>{std::string(64, 'a')});
  ASSERT_TRUE((*store)->ForgetBlob(std::string(64, 'b')).ok());
  EXPECT_FALSE(*(*store)->OwnsBlob("bob", std::string(64, 'b')));
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

TEST(JobStoreTest, LeaseRenewFinishAndCache) {
  TempDir dir;
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok());
  bool created;
  auto first = (*store)->Create(NewJob("r1"), "k1", &created);
  auto second = (*store)->Create(NewJob("r2"), "k2", &created);
  ASSERT_TRUE(first.ok() && second.ok());
  auto l1 = (*store)->LeaseNext("w1", absl::Seconds(30));
  ASSERT_TRUE(l1.ok() && l1->has_value());
  EXPECT_EQ((*l1)->name(), first->name());  // oldest first
  EXPECT_EQ((*l1)->state(), v1::RUNNING);
  EXPECT_EQ((*l1)->attempts(), 1);
  EXPECT_TRUE((*store)->Renew(first->name(), "w1", absl::Seconds(30)).ok());
  EXPECT_EQ((*store)->Renew(first->name(), "w2", absl::Seconds(30)).code(),
            absl::StatusCode::kFailedPrecondition);
  v1::JobProgress p;
  p.set_stage("surface");
  p.set_stage_index(3);
  ASSERT_TRUE((*store)->SetProgress(first->name(), "w1", p).ok());
  EXPECT_EQ((*store)->Get(first->name())->progress().stage(), "surface");
  v1::Artifact art;
  art.set_name("report.json");
  art.mutable_digest()->set_hash(std::string(64, 'b'));
  auto done = (*store)->Finish(first->name(), "w1", v1::SUCCEEDED, v1::JobError(), {art});
  ASSERT_TRUE(done.ok());
  EXPECT_EQ(done->state(), v1::SUCCEEDED);
  EXPECT_EQ(done->artifacts_size(), 1);
  auto cached = (*store)->FindCached("k1");
  ASSERT_TRUE(cached.ok() && cached->has_value());
  EXPECT_EQ((*cached)->name(), first->name());
  EXPECT_FALSE((*store)->FindCached("k2")->has_value());
  EXPECT_EQ(*(*store)->CountInState(v1::QUEUED), 1);
}

TEST(JobStoreTest, ExpiredLeasesRequeueThenFailAfterMaxAttempts) {
  TempDir dir;
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok());
  bool created;
  auto job = (*store)->Create(NewJob("r1"), "k1", &created);
  ASSERT_TRUE(job.ok());
  for (int attempt = 1; attempt <= 2; ++attempt) {
    auto l = (*store)->LeaseNext("w", absl::Milliseconds(1));
    ASSERT_TRUE(l.ok() && l->has_value());
    EXPECT_EQ((*l)->attempts(), attempt);
    absl::SleepFor(absl::Milliseconds(20));
    EXPECT_EQ(*(*store)->RequeueExpired(2, false), 1);
  }
  auto end = (*store)->Get(job->name());
  ASSERT_TRUE(end.ok());
  EXPECT_EQ(end->state(), v1::FAILED);
  EXPECT_THAT(end->error().message(), HasSubstr("2"));
}

TEST(JobStoreTest, RestartRequeuesRunningJobsAndKeepsEverything) {
  TempDir dir;
  std::string name;
  {
    auto store = OpenSqliteJobStore(dir.File("jobs.db"));
    ASSERT_TRUE(store.ok());
    bool created;
    name = (*store)->Create(NewJob("r1"), "k1", &created)->name();
    ASSERT_TRUE((*store)->LeaseNext("w", absl::Hours(1))->has_value());
  }
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok());
  EXPECT_EQ(*(*store)->RequeueExpired(3, /*all=*/true), 1);
  auto job = (*store)->Get(name);
  ASSERT_TRUE(job.ok());
  EXPECT_EQ(job->state(), v1::QUEUED);
  EXPECT_EQ(job->attempts(), 1);
  auto again = (*store)->LeaseNext("w2", absl::Seconds(30));
  ASSERT_TRUE(again.ok() && again->has_value());
  EXPECT_EQ((*again)->attempts(), 2);
}

TEST(JobStoreTest, CancelAndDelete) {
  TempDir dir;
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok());
  bool created;
  auto queued = (*store)->Create(NewJob("q"), "kq", &created);
  auto running = (*store)->Create(NewJob("r"), "kr", &created);
  ASSERT_TRUE(queued.ok() && running.ok());
  ASSERT_TRUE((*store)->LeaseNext("w", absl::Seconds(30))->has_value());  // "q" runs
  // Now "q" is running and "r" queued.
  auto c1 = (*store)->RequestCancel(running->name());
  ASSERT_TRUE(c1.ok());
  EXPECT_EQ(c1->state(), v1::CANCELLED);
  auto c2 = (*store)->RequestCancel(queued->name());
  ASSERT_TRUE(c2.ok());
  EXPECT_EQ(c2->state(), v1::RUNNING);
  EXPECT_TRUE(*(*store)->CancelRequested(queued->name()));
  EXPECT_EQ((*store)->Delete(queued->name()).code(), absl::StatusCode::kFailedPrecondition);
  v1::JobError e;
  e.set_code(1);
  ASSERT_TRUE((*store)->Finish(queued->name(), "w", v1::CANCELLED, e, {}).ok());
  EXPECT_TRUE((*store)->Delete(queued->name()).ok());
  EXPECT_EQ((*store)->Get(queued->name()).status().code(), absl::StatusCode::kNotFound);
}

TEST(JobStoreTest, ListPagesNewestFirstByState) {
  TempDir dir;
  auto store = OpenSqliteJobStore(dir.File("jobs.db"));
  ASSERT_TRUE(store.ok());
  bool created;
  std::vector<std::string> names;
  for (int i = 0; i < 7; ++i)
    names.push_back((*store)->Create(NewJob(absl::StrCat("r", i)), "", &created)->name());
  std::vector<std::string> seen;
  std::string token, next;
  do {
    auto page = (*store)->List("default", v1::JOB_STATE_UNSPECIFIED, 3, token, &next);
    ASSERT_TRUE(page.ok());
    for (const auto& j : *page) seen.push_back(j.name());
    token = next;
  } while (!token.empty());
  EXPECT_EQ(seen, std::vector<std::string>(names.rbegin(), names.rend()));
  auto running = (*store)->List("default", v1::RUNNING, 10, "", &next);
  ASSERT_TRUE(running.ok());
  EXPECT_TRUE(running->empty());
  EXPECT_EQ((*store)->List("default", v1::QUEUED, 10, "garbage", &next).status().code(),
            absl::StatusCode::kInvalidArgument);
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
