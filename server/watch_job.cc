#include "server/watch_job.h"

#include <grpcpp/server_context.h>

#include <atomic>
#include <climits>
#include <deque>
#include <vector>

#include "absl/time/clock.h"
#include "server/job_view.h"
#include "server/status_util.h"

namespace sheetmesh::server {

// One watch. At any moment exactly one party holds it: the code that created it, gRPC (a
// write in flight), the hub (waiting), or the hub's thread (polling). Only the holder
// writes, finishes or hands it on, so nothing races; OnCancel only marks it, unless it
// takes it back from the hub.
class WatchHub::Reactor final : public grpc::ServerWriteReactor<v1::WatchJobResponse> {
 public:
  Reactor(WatchHub* hub, grpc::CallbackServerContext* context, v1::WatchJobRequest request)
      : hub_(hub), ctx_(*hub->ctx_), context_(context), request_(std::move(request)) {}

  void Begin() {
    if (grpc::Status a = ctx_.tenants->Authenticate(*context_, &tenant_); !a.ok()) {
      Finish(a);
      return;
    }
    absl::StatusOr<StreamLimits::Slot> slot =
        ctx_.watch_streams->Acquire(ClientOf(*context_, ctx_.tenants->open() ? "" : tenant_));
    if (!slot.ok()) {
      Finish(ToGrpcStatus(slot.status()));
      return;
    }
    slot_ = std::move(*slot);
    seen_ = ctx_.events->Version(request_.name());
    absl::StatusOr<v1::Job> job = FreshJob(ctx_, tenant_, request_.name());
    if (!job.ok()) {
      Finish(ToGrpcStatus(job.status()));
      return;
    }
    v1::WatchJobResponse msg;
    *msg.mutable_job() = *job;
    queue_.push_back(std::move(msg));
    last_ = job->SerializeAsString();
    stage_sent_ = job->state() == v1::RUNNING ? job->progress().stage_index() : 0;
    terminal_ = v1::IsTerminal(job->state());
    Send();
  }

  // The hub's thread holds this watch: its job changed, its heartbeat is due, or the server
  // is stopping.
  void Poll(bool stopping) {
    if (cancelled_) return Finish(grpc::Status::OK);  // the watcher left; the job goes on
    if (stopping) {
      return Finish(ToGrpcStatus(
          absl::UnavailableError("the server is shutting down; watch again after it restarts")));
    }
    const uint64_t now = ctx_.events->Version(request_.name());
    const bool changed = now != seen_;
    // The job first, then the stage log: every stage before the job's current one is in the
    // log by then (LocalJobHost records a stage before it shows it).
    absl::StatusOr<v1::Job> job = FreshJob(ctx_, tenant_, request_.name());
    if (!job.ok()) return Finish(ToGrpcStatus(job.status()));
    // The first time, the whole log: a stage may have begun before the job's state said
    // RUNNING in the first message.
    const std::vector<v1::JobProgress> stages =
        ctx_.events->StagesSince(request_.name(), first_ ? 0 : seen_);
    first_ = false;
    seen_ = now;
    // Stages that started and ended between two looks are still told, in order.
    const int current = job->state() == v1::RUNNING ? job->progress().stage_index() : INT32_MAX;
    for (const v1::JobProgress& stage : stages) {
      if (stage.stage_index() <= stage_sent_ || stage.stage_index() >= current) continue;
      v1::WatchJobResponse msg;
      *msg.mutable_job() = *job;
      msg.mutable_job()->set_state(v1::RUNNING);
      msg.mutable_job()->clear_error();
      msg.mutable_job()->clear_artifacts();
      msg.mutable_job()->clear_end_time();
      *msg.mutable_job()->mutable_progress() = stage;
      stage_sent_ = stage.stage_index();
      queue_.push_back(std::move(msg));
    }
    if (job->state() == v1::RUNNING)
      stage_sent_ = std::max(stage_sent_, job->progress().stage_index());
    const std::string cur = job->SerializeAsString();
    v1::WatchJobResponse msg;
    *msg.mutable_job() = *job;
    msg.set_heartbeat(!changed || cur == last_);
    last_ = cur;
    queue_.push_back(std::move(msg));
    terminal_ = v1::IsTerminal(job->state());
    Send();
  }

  void FinishStopping() {
    Finish(ToGrpcStatus(
        absl::UnavailableError("the server is shutting down; watch again after it restarts")));
  }

  void OnWriteDone(bool ok) override {
    if (!ok || cancelled_) return Finish(grpc::Status::OK);
    Send();
  }

  void OnCancel() override {
    cancelled_ = true;
    if (hub_->Take(this)) Finish(grpc::Status::OK);
  }

  void OnDone() override {
    hub_->Take(this);
    delete this;
  }

  const std::string& job() const { return request_.name(); }
  uint64_t seen() const { return seen_; }
  absl::Time deadline() const { return deadline_; }

 private:
  // The next message; with none left, the end (a finished job) or a wait in the hub.
  void Send() {
    if (!queue_.empty()) {
      current_ = std::move(queue_.front());
      queue_.pop_front();
      StartWrite(&current_);
      return;
    }
    if (terminal_) return Finish(grpc::Status::OK);
    deadline_ = absl::Now() + ctx_.heartbeat;
    hub_->Wait(this);
  }

  WatchHub* hub_;
  const ServiceContext& ctx_;
  grpc::CallbackServerContext* context_;
  const v1::WatchJobRequest request_;
  std::string tenant_;
  StreamLimits::Slot slot_;
  std::atomic<bool> cancelled_{false};
  std::deque<v1::WatchJobResponse> queue_;
  v1::WatchJobResponse current_;  // the message being written
  uint64_t seen_ = 0;
  std::string last_;
  int stage_sent_ = 0;
  bool first_ = true;
  bool terminal_ = false;
  absl::Time deadline_;
};

WatchHub::WatchHub(const ServiceContext* ctx) : ctx_(ctx) {
  ctx_->events->SetListener([this] {
    {
      std::lock_guard<std::mutex> lock(mu_);
      dirty_ = true;
    }
    cv_.notify_all();
  });
  thread_ = std::thread([this] { Run(); });
}

WatchHub::~WatchHub() {
  Stop();
  ctx_->events->SetListener(nullptr);
}

grpc::ServerWriteReactor<v1::WatchJobResponse>* WatchHub::Watch(
    grpc::CallbackServerContext* context, const v1::WatchJobRequest& request) {
  auto* r = new Reactor(this, context, request);
  r->Begin();
  return r;
}

void WatchHub::Stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

int WatchHub::waiting() const {
  std::lock_guard<std::mutex> lock(mu_);
  return static_cast<int>(waiting_.size());
}

void WatchHub::Wait(Reactor* r) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!stopping_) {
      waiting_.insert(r);
      cv_.notify_all();  // its deadline may come before the others'
      return;
    }
  }
  r->FinishStopping();
}

bool WatchHub::Take(Reactor* r) {
  std::lock_guard<std::mutex> lock(mu_);
  return waiting_.erase(r) > 0;
}

void WatchHub::Run() {
  std::unique_lock<std::mutex> lock(mu_);
  for (;;) {
    absl::Time next = absl::Now() + absl::Seconds(1);
    for (Reactor* r : waiting_) next = std::min(next, r->deadline());
    cv_.wait_until(lock, absl::ToChronoTime(next), [&] { return dirty_ || stopping_; });
    dirty_ = false;
    const bool stopping = stopping_;
    const absl::Time now = absl::Now();
    std::vector<Reactor*> ready;
    for (auto it = waiting_.begin(); it != waiting_.end();) {
      Reactor* r = *it;
      if (stopping || now >= r->deadline() || ctx_->events->Version(r->job()) != r->seen()) {
        ready.push_back(r);
        it = waiting_.erase(it);
      } else {
        ++it;
      }
    }
    lock.unlock();
    for (Reactor* r : ready) r->Poll(stopping);
    lock.lock();
    if (stopping && waiting_.empty()) break;
  }
}

}  // namespace sheetmesh::server
