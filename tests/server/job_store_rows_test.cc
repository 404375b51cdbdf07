#include "server/job_store_rows.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace sheetmesh::server {
namespace {

using ::testing::HasSubstr;

TEST(JobStoreRowsTest, IdsSortByCreationAndNamesStripTheirPrefix) {
  EXPECT_LT(NewJobId(9, 0xffffffff), NewJobId(10, 0));
  EXPECT_EQ(NewJobId(1, 0x1234567890abULL), "000000000001-567890ab");
  EXPECT_EQ(JobIdOf("jobs/000000000001-567890ab"), "000000000001-567890ab");
  EXPECT_EQ(JobIdOf("000000000001-567890ab"), "000000000001-567890ab");
}

TEST(JobStoreRowsTest, RequestIdsOfTwoTenantsNeverMeet) {
  EXPECT_EQ(ScopedRequestId("default", "r1"), "r1");
  EXPECT_EQ(ScopedRequestId("", "r1"), "r1");
  EXPECT_NE(ScopedRequestId("a", "r1"), ScopedRequestId("b", "r1"));
  EXPECT_NE(ScopedRequestId("a", "r1"), "r1");
}

TEST(JobStoreRowsTest, AJobNamesItsInputAndArtifactBlobs) {
  v1::Job j;
  j.mutable_input()->mutable_volume_digest()->set_hash("in");
  j.add_artifacts()->mutable_digest()->set_hash("out1");
  j.add_artifacts()->mutable_digest()->set_hash("out2");
  EXPECT_EQ(BlobsOf(j), (std::set<std::string>{"in", "out1", "out2"}));
}

TEST(JobStoreRowsTest, ACorruptRecordIsDataLossAndAnOldOneIsTheDefaultTenants) {
  EXPECT_EQ(ParseStoredJob("\xff\xff\xff").status().code(), absl::StatusCode::kDataLoss);
  v1::Job old;
  old.set_name("jobs/1");
  auto back = ParseStoredJob(old.SerializeAsString());
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back->tenant(), kDefaultTenant);
}

TEST(JobStoreRowsTest, AFinishedJobKeepsItsArtifactsUnlessCancelled) {
  const absl::Time t = absl::FromUnixSeconds(1767225600);
  std::vector<v1::Artifact> kept(1);
  kept[0].set_name("surface.ply");
  v1::JobError error;
  error.set_message("volume stage failed");
  for (v1::JobState state : {v1::SUCCEEDED, v1::FAILED, v1::CANCELLED}) {
    v1::Job j;
    j.set_state(v1::RUNNING);
    j.mutable_error()->set_message("stale");
    ApplyFinish(&j, state, error, kept, t);
    EXPECT_EQ(j.state(), state);
    EXPECT_EQ(j.end_time().seconds(), 1767225600);
    EXPECT_EQ(j.artifacts_size(), state == v1::CANCELLED ? 0 : 1) << v1::JobState_Name(state);
    EXPECT_EQ(j.has_error(), state != v1::SUCCEEDED);
  }
}

TEST(JobStoreRowsTest, ALostWorkerRequeuesCancelsOrFailsTheJob) {
  v1::Job j;
  j.set_state(v1::RUNNING);
  j.set_attempts(1);
  j.mutable_progress()->set_stage("surface");
  ApplyLostWorker(&j, false, 3);
  EXPECT_EQ(j.state(), v1::QUEUED);
  EXPECT_FALSE(j.has_progress());
  j.set_state(v1::RUNNING);
  ApplyLostWorker(&j, /*cancel_requested=*/true, 3);
  EXPECT_EQ(j.state(), v1::CANCELLED);
  EXPECT_EQ(j.error().code(), int(absl::StatusCode::kCancelled));
  // Runs lost to restarts of a server (isolated jobs) do not count against max_attempts.
  v1::Job k;
  k.set_state(v1::RUNNING);
  k.set_attempts(3);
  ApplyLostWorker(&k, false, 3, /*not_the_jobs_fault=*/true);
  EXPECT_EQ(k.state(), v1::QUEUED);
  EXPECT_EQ(k.lost_to_restarts(), 1);
  k.set_state(v1::RUNNING);
  k.set_attempts(4);
  ApplyLostWorker(&k, false, 3);
  EXPECT_EQ(k.state(), v1::FAILED);
  EXPECT_THAT(k.error().message(), HasSubstr("lost 4 times"));
}

}  // namespace
}  // namespace sheetmesh::server
