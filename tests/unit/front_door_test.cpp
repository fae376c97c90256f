// The scheduler's front door (server/scheduler/front_door.h) called directly, without gRPC or
// HTTP: the role and ownership checks live in it, so a caller's Principal alone decides what it
// may see and do. A real SchedulerCore with no workers: every job submitted stays QUEUED.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "server/common/read_whole_file.h"
#include "server/common/service_error.h"
#include "server/common/sha256.h"
#include "server/scheduler/front_door.h"
#include "server/scheduler/scheduler_core.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using namespace std::chrono_literals;

const Principal kAlice{"alice", Role::submit};
const Principal kBob{"bob", Role::submit};
const Principal kReader{"auditor", Role::read};
const Principal kAdmin{"boss", Role::admin};
const Principal kWorker{"render01", Role::worker};
const Principal kOtherWorker{"render02", Role::worker};
constexpr int kMaxPriority = 10;

// What `call` ends with, as the adapters would answer it: OK when it returns, else the status of
// what it throws (its message kept in `message` when given).
template <typename F>
grpc::StatusCode code_of(F&& call, std::string* message = nullptr) {
  try {
    call();
  } catch (const std::exception&) {
    const grpc::Status status = status_of_current_exception();
    if (message) *message = status.error_message();
    return status.error_code();
  }
  return grpc::StatusCode::OK;
}

class FrontDoorTest : public ::testing::Test {
 protected:
  FrontDoorTest() : core_(options()), door_(core_, access()) {}
  ~FrontDoorTest() override { core_.stop(); }

  // No tokens: the tests make their callers' Principals themselves, as an adapter does once it
  // has authenticated a request.
  static SchedulerAccess access() {
    SchedulerAccess a;
    a.max_priority = kMaxPriority;
    return a;
  }

  SchedulerOptions options() const {
    SchedulerOptions o;
    o.data_dir = dir_ / "farm";
    o.log_level = LogLevel::off;
    return o;
  }

  // Uploads `bytes` through the front door as `who`; returns their SHA-256.
  std::string upload(const Principal& who, const std::string& bytes) {
    AssetUpload upload = door_.upload_asset(who);
    v1::AssetHeader header;
    header.set_sha256(sha256_hex(bytes));
    header.set_size(bytes.size());
    if (upload.begin(header)) {
      upload.append(bytes);
      upload.commit();
    }
    return header.sha256();
  }

  // A small Cornell box job of `who`'s, its files uploaded as `who`: its id.
  std::string submit(const Principal& who, int priority = 0) {
    for (const auto& [path, file] : test::cornell_assets()) upload(who, read_whole_file(file, "asset"));
    return door_.submit(who, test::cornell_job_spec("raster", 16, 16, 1), priority).job_id();
  }

  test::TempDir dir_;  // first: the core's data dir lives in it
  SchedulerCore core_;
  SchedulerFrontDoor door_;
};

TEST_F(FrontDoorTest, ASubmitterCannotSeeOrActOnAnotherOwnersJob) {
  const std::string id = submit(kAlice);
  EXPECT_EQ(door_.get_job(kAlice, id).owner(), "alice");

  std::string message;
  EXPECT_EQ(code_of([&] { door_.get_job(kBob, id); }, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(message, "'bob' (roles: submit) may not see job " + id + ": it belongs to 'alice'");
  EXPECT_EQ(code_of([&] { door_.cancel_job(kBob, id); }, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(message, "'bob' (roles: submit) may not cancel job " + id + ": it belongs to 'alice'");
  EXPECT_EQ(code_of([&] { door_.pause_job(kBob, id, true); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.set_priority(kBob, id, 1); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.retry_job(kBob, id); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.delete_job(kBob, id); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.watch_job(kBob, id); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.live_preview(kBob, id, std::nullopt); }), grpc::StatusCode::PERMISSION_DENIED);
  v1::GetJobLogRequest log;
  log.set_job_id(id);
  EXPECT_EQ(code_of([&] { door_.job_log(kBob, log); }), grpc::StatusCode::PERMISSION_DENIED);
  v1::GetResultRequest result;
  result.set_job_id(id);
  EXPECT_EQ(code_of([&] { door_.result_file(kBob, result); }), grpc::StatusCode::PERMISSION_DENIED);

  // A submitter lists its own jobs only; an unknown job is not found, whoever asks.
  EXPECT_EQ(door_.list_jobs(kBob, {}).jobs_size(), 0);
  ASSERT_EQ(door_.list_jobs(kAlice, {}).jobs_size(), 1);
  EXPECT_EQ(door_.list_jobs(kAlice, {}).jobs(0).job_id(), id);
  EXPECT_EQ(code_of([&] { door_.get_job(kBob, "0123abcd"); }), grpc::StatusCode::NOT_FOUND);

  // Nothing bob tried changed the job; its owner and an admin may act on it.
  EXPECT_EQ(door_.get_job(kAdmin, id).state(), v1::JOB_STATE_QUEUED);
  EXPECT_EQ(door_.pause_job(kAlice, id, true).paused(), true);
  EXPECT_EQ(door_.cancel_job(kAdmin, id).state(), v1::JOB_STATE_CANCELLED);
}

TEST_F(FrontDoorTest, AReaderSeesEveryJobAndTheWorkersButActsOnNone) {
  const std::string id = submit(kAlice);
  const v1::ListJobsResponse listed = door_.list_jobs(kReader, {});
  ASSERT_EQ(listed.jobs_size(), 1);
  EXPECT_EQ(listed.jobs(0).owner(), "alice");
  EXPECT_EQ(door_.get_job(kReader, id).job_id(), id);
  v1::GetJobLogRequest log;
  log.set_job_id(id);
  EXPECT_GE(door_.job_log(kReader, log).entries_size(), 1);

  std::string message;
  EXPECT_EQ(code_of([&] { door_.cancel_job(kReader, id); }, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(message, "'auditor' (roles: read) may not call CancelJob (it needs a role of: submit,admin)");
  EXPECT_EQ(code_of([&] { door_.pause_job(kReader, id, true); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.delete_job(kReader, id); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { submit(kReader); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(door_.get_job(kAdmin, id).state(), v1::JOB_STATE_QUEUED);

  // The workers and /metrics' figures: read and admin, not a submitter.
  EXPECT_EQ(door_.list_workers(kReader).workers_size(), 0);
  const SchedulerMetrics metrics = door_.metrics(kReader);
  EXPECT_EQ(metrics.jobs.jobs.at(v1::JOB_STATE_QUEUED), 1);
  EXPECT_GT(metrics.jobs.queued_units, 0);
  EXPECT_EQ(code_of([&] { door_.list_workers(kAlice); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.metrics(kAlice); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.metrics(kAdmin); }), grpc::StatusCode::OK);
}

TEST_F(FrontDoorTest, APriorityAboveTheMaximumNeedsAdmin) {
  std::string message;
  EXPECT_EQ(code_of([&] { submit(kAlice, kMaxPriority + 1); }, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(message, "'alice' (roles: submit) may not submit with priority 11 (above 10 needs the admin role)");
  EXPECT_EQ(door_.list_jobs(kAdmin, {}).jobs_size(), 0);  // refused before it was queued

  const std::string id = submit(kAlice, kMaxPriority);
  EXPECT_EQ(door_.get_job(kAlice, id).priority(), kMaxPriority);
  EXPECT_EQ(code_of([&] { door_.set_priority(kAlice, id, kMaxPriority + 1); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(door_.set_priority(kAlice, id, 3).priority(), 3);
  EXPECT_EQ(door_.set_priority(kAdmin, id, 50).priority(), 50);
  EXPECT_EQ(door_.get_job(kAdmin, submit(kAdmin, 99)).priority(), 99);
}

TEST_F(FrontDoorTest, AWatchOfEveryJobHearsOnlyTheCallersOwnUnlessItMayReadThemAll) {
  const std::unique_ptr<JobWatch> bobs = door_.watch_every_job(kBob);
  const std::unique_ptr<JobWatch> readers = door_.watch_every_job(kReader);
  const std::string id = submit(kAlice);
  v1::JobEvent event;
  ASSERT_TRUE(readers->next(event, 10s));
  EXPECT_EQ(event.job().job_id(), id);
  EXPECT_FALSE(bobs->next(event, 200ms));  // alice's job: not bob's to hear

  const std::string mine = submit(kBob);
  ASSERT_TRUE(bobs->next(event, 10s));
  EXPECT_EQ(event.job().job_id(), mine);

  // A watch of one job: its owner's, with the job as it is now, then its events.
  const std::unique_ptr<JobWatch> alices = door_.watch_job(kAlice, id);
  EXPECT_EQ(alices->snapshot().job_id(), id);
  EXPECT_EQ(alices->snapshot().state(), v1::JOB_STATE_QUEUED);
  door_.cancel_job(kAlice, id);
  bool cancelled = false;
  while (!cancelled && alices->next(event, 10s)) {
    cancelled = event.has_state_changed() && event.job().state() == v1::JOB_STATE_CANCELLED;
  }
  EXPECT_TRUE(cancelled);
}

// A watch's snapshot and its events meet at one moment: the first event after the snapshot never
// shows the job older than the snapshot did. Each priority change is an event carrying the job, its
// priority one higher than the last; watches are begun while they come as fast as the store takes
// them. (A watch that subscribed, then read the job, could queue an event made before that read.)
TEST_F(FrontDoorTest, NoEventAWatchHearsShowsTheJobOlderThanItsSnapshot) {
  const std::string id = submit(kAlice);
  std::atomic<bool> done{false};
  std::thread changes([&] {
    for (int priority = 1; !done; ++priority) door_.set_priority(kAdmin, id, priority);
  });
  int older = 0;
  for (int i = 0; i < 200; ++i) {
    const std::unique_ptr<JobWatch> watch = door_.watch_job(kAlice, id);
    v1::JobEvent event;
    ASSERT_TRUE(watch->next(event, 10s));
    if (event.job().priority() < watch->snapshot().priority()) ++older;
  }
  done = true;
  changes.join();
  EXPECT_EQ(older, 0) << "of 200 watches, the first event showed the job older than the snapshot";
}

TEST_F(FrontDoorTest, WorkersAndAssetsAskForTheirRolesAndTheirOwnRegistrations) {
  // Assets: submitters upload and ask; only a worker given a call that reads an asset, or an
  // admin, fetches it.
  EXPECT_EQ(code_of([&] { door_.upload_asset(kReader); }), grpc::StatusCode::PERMISSION_DENIED);
  const std::string sha = upload(kAlice, "a small asset");
  v1::HasAssetsRequest has;
  has.add_sha256(sha);
  has.add_sha256(sha256_hex("not uploaded"));
  EXPECT_EQ(code_of([&] { door_.has_assets(kWorker, has); }), grpc::StatusCode::PERMISSION_DENIED);
  const v1::HasAssetsResponse missing = door_.has_assets(kAlice, has);
  ASSERT_EQ(missing.missing_size(), 1);
  EXPECT_EQ(missing.missing(0), sha256_hex("not uploaded"));
  std::string message;
  EXPECT_EQ(code_of([&] { door_.asset_file(kWorker, sha); }, &message), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_NE(message.find("no job given to it now reads it"), std::string::npos) << message;
  EXPECT_EQ(code_of([&] { door_.asset_file(kAlice, sha); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(read_whole_file(door_.asset_file(kAdmin, sha), "asset"), "a small asset");
  EXPECT_EQ(code_of([&] { door_.asset_file(kAdmin, sha256_hex("not uploaded")); }), grpc::StatusCode::NOT_FOUND);

  // Registration: a worker token keeps its own workers, no other's.
  v1::RegisterWorkerRequest registration;
  registration.set_address("127.0.0.1:9");
  EXPECT_EQ(code_of([&] { door_.register_worker(kAlice, registration); }), grpc::StatusCode::PERMISSION_DENIED);
  const std::string worker_id = door_.register_worker(kWorker, registration).worker_id();
  EXPECT_EQ(code_of([&] { door_.register_worker(kOtherWorker, registration); }, &message),
            grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(message, "'render02' (roles: worker) may not register at 127.0.0.1:9: 'render01' registered a worker there");
  v1::HeartbeatRequest beat;
  beat.set_worker_id(worker_id);
  EXPECT_EQ(code_of([&] { door_.heartbeat(kOtherWorker, beat); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.heartbeat(kAlice, beat); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_FALSE(door_.heartbeat(kWorker, beat).register_again());
  beat.set_worker_id("never-registered");
  EXPECT_TRUE(door_.heartbeat(kOtherWorker, beat).register_again());
}

TEST_F(FrontDoorTest, PlanningASubmissionTakesTheRolesOfSubmittingAndAnswersItsStatuses) {
  // The Cornell box: the model held, its material library not yet described.
  v1::PlanSubmissionRequest request;
  *request.mutable_job() = test::cornell_job_spec("raster", 16, 16, 1);
  request.mutable_job()->mutable_assets()->RemoveLast();  // the .mtl, named second
  ASSERT_EQ(request.job().assets(0).path(), "assets/cornell_box.obj");
  upload(kAlice, read_whole_file(test::cornell_assets()[0].second, "asset"));
  EXPECT_EQ(code_of([&] { door_.plan_submission(kReader, request); }), grpc::StatusCode::PERMISSION_DENIED);
  EXPECT_EQ(code_of([&] { door_.plan_submission(kWorker, request); }), grpc::StatusCode::PERMISSION_DENIED);
  const v1::PlanSubmissionResponse plan = door_.plan_submission(kAlice, request);
  ASSERT_EQ(plan.needed_size(), 1);
  EXPECT_EQ(plan.needed(0).path(), "assets/cornell_box.mtl");
  EXPECT_EQ(plan.needed(0).named_by(), "assets/cornell_box.obj");
  EXPECT_FALSE(plan.complete());
  EXPECT_TRUE(door_.plan_submission(kAdmin, request).needed_size() == 1);
  // A bad job is INVALID_ARGUMENT with SubmitJob's words; a spec over the limits RESOURCE_EXHAUSTED.
  v1::PlanSubmissionRequest bad = request;
  bad.mutable_job()->set_job_json("{\"version\": 2}");
  std::string message;
  EXPECT_EQ(code_of([&] { door_.plan_submission(kAlice, bad); }, &message), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(message.find("cornell.json: version: unsupported version 2"), std::string::npos) << message;
  bad = request;
  bad.mutable_job()->mutable_assets(0)->set_size(std::uint64_t{5} << 30);
  EXPECT_EQ(code_of([&] { door_.plan_submission(kAlice, bad); }), grpc::StatusCode::RESOURCE_EXHAUSTED);
}

}  // namespace
}  // namespace farm
