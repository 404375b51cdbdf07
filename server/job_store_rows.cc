#include "server/job_store_rows.h"

#include <algorithm>
#include <cstdio>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "google/protobuf/util/time_util.h"

namespace sheetmesh::server {

google::protobuf::Timestamp TimestampOf(absl::Time t) {
  return google::protobuf::util::TimeUtil::MillisecondsToTimestamp(absl::ToUnixMillis(t));
}

google::protobuf::Timestamp NowTimestamp() { return TimestampOf(absl::Now()); }

std::string JobIdOf(const std::string& name) {
  return name.rfind("jobs/", 0) == 0 ? name.substr(5) : name;
}

std::string NewJobId(int64_t seq, uint64_t random) {
  char id[40];
  std::snprintf(id, sizeof(id), "%012lld-%08llx", static_cast<long long>(seq),
                static_cast<unsigned long long>(random & 0xffffffffULL));
  return id;
}

std::string NameNewJob(v1::Job* job, int64_t seq, uint64_t random, absl::Time now) {
  const std::string id = NewJobId(seq, random);
  job->set_name(absl::StrCat("jobs/", id));
  *job->mutable_create_time() = TimestampOf(now);
  if (job->state() == v1::JOB_STATE_UNSPECIFIED) job->set_state(v1::QUEUED);
  return id;
}

std::string ScopedRequestId(const std::string& tenant, const std::string& request_id) {
  if (tenant.empty() || tenant == kDefaultTenant) return request_id;
  return absl::StrCat("\x1f", tenant, "\x1f", request_id);
}

std::set<std::string> BlobsOf(const v1::Job& job) {
  std::set<std::string> out;
  if (job.input().has_volume_digest()) out.insert(job.input().volume_digest().hash());
  for (const v1::VolumeFiles::File& f : job.input().volume_files().files()) {
    out.insert(f.digest().hash());
  }
  for (const v1::Artifact& a : job.artifacts()) out.insert(a.digest().hash());
  if (job.bricks().has_plan()) out.insert(job.bricks().plan().digest().hash());
  return out;
}

absl::StatusOr<v1::Job> ParseStoredJob(const std::string& bytes) {
  v1::Job j;
  if (!j.ParseFromString(bytes)) return absl::DataLossError("a stored job record is corrupt");
  if (j.tenant().empty()) j.set_tenant(kDefaultTenant);
  return j;
}

void ApplyFinish(v1::Job* job, v1::JobState state, const v1::JobError& error,
                 const std::vector<v1::Artifact>& artifacts, absl::Time now) {
  job->set_state(state);
  *job->mutable_end_time() = TimestampOf(now);
  // A failed job keeps what its run kept (the surface when the volume stage failed); a
  // cancelled one keeps nothing.
  if (state != v1::CANCELLED) {
    for (const v1::Artifact& a : artifacts) *job->add_artifacts() = a;
  }
  if (state == v1::SUCCEEDED) {
    job->clear_error();
  } else {
    *job->mutable_error() = error;
  }
}

void ApplyCancelBeforeStart(v1::Job* job, absl::Time now) {
  job->set_state(v1::CANCELLED);
  *job->mutable_end_time() = TimestampOf(now);
  job->mutable_error()->set_code(static_cast<int>(absl::StatusCode::kCancelled));
  job->mutable_error()->set_message(job->bricks().count() > 0 ? "cancelled while its bricks ran"
                                                              : "cancelled before it started");
}

void ApplyLostWorker(v1::Job* job, bool cancel_requested, int max_attempts, bool not_the_jobs_fault,
                     absl::Time now) {
  job->clear_progress();
  if (not_the_jobs_fault) job->set_lost_to_restarts(job->lost_to_restarts() + 1);
  if (cancel_requested) {
    job->set_state(v1::CANCELLED);
    job->mutable_error()->set_code(static_cast<int>(absl::StatusCode::kCancelled));
    job->mutable_error()->set_message("cancelled while its worker was lost");
    *job->mutable_end_time() = TimestampOf(now);
  } else if (job->attempts() - job->lost_to_restarts() >= max_attempts) {
    job->set_state(v1::FAILED);
    job->mutable_error()->set_code(static_cast<int>(absl::StatusCode::kAborted));
    job->mutable_error()->set_message(
        absl::StrCat("its worker was lost ", job->attempts(),
                     " times (lease expired or server restarted); giving up after max_attempts = ",
                     max_attempts));
    *job->mutable_end_time() = TimestampOf(now);
  } else {
    job->set_state(v1::QUEUED);
  }
}

std::vector<v1::Job> BrickTasks(const v1::Job& parent, const v1::Artifact& plan, int count) {
  std::vector<v1::Job> tasks;
  tasks.reserve(static_cast<size_t>(count));
  for (int i = 0; i < count; ++i) {
    v1::Job t;
    t.set_request_id(absl::StrCat(parent.request_id(), "/brick/", i));
    *t.mutable_input() = parent.input();
    *t.mutable_parameters() = parent.parameters();
    t.set_resolved_parameters(parent.resolved_parameters());
    t.set_pipeline_version(parent.pipeline_version());
    t.set_tenant(parent.tenant());
    t.set_state(v1::QUEUED);
    v1::JobBricks& b = *t.mutable_bricks();
    b.set_size(parent.bricks().size());
    *b.mutable_plan() = plan;
    b.set_count(count);
    b.set_parent(parent.name());
    b.set_index(i);
    tasks.push_back(std::move(t));
  }
  return tasks;
}

void ApplySplit(v1::Job* parent, const v1::Artifact& plan, const std::vector<std::string>& names) {
  parent->set_state(v1::QUEUED);
  parent->set_attempts(std::max(0, parent->attempts() - 1));
  v1::JobBricks& b = *parent->mutable_bricks();
  *b.mutable_plan() = plan;
  b.set_count(static_cast<int>(names.size()));
  b.clear_tasks();
  for (const std::string& n : names) b.add_tasks(n);
  v1::JobProgress& p = *parent->mutable_progress();
  p.set_stage("bricks");
  p.set_fraction(0);
  p.set_message(absl::StrCat("0 of ", names.size(), " bricks done"));
}

void ApplyMerged(v1::Job* task) { task->clear_artifacts(); }

absl::Status CheckSplittable(const v1::Job& job, int count) {
  if (count < 1 || count > kMaxBricks) {
    return absl::InvalidArgumentError(
        absl::StrCat("count ", count, " is not a number of bricks (1 to ", kMaxBricks, ")"));
  }
  if (job.bricks().size().empty() || !job.bricks().parent().empty()) {
    return absl::FailedPreconditionError(
        absl::StrCat(job.name(), " is not a job run as bricks: it cannot be split"));
  }
  if (job.bricks().count() > 0) {
    return absl::FailedPreconditionError(
        absl::StrCat(job.name(), " is split already, into ", job.bricks().count(), " bricks"));
  }
  return absl::OkStatus();
}

}  // namespace sheetmesh::server
