// The ETA of `farm status`, `farm watch` and the job page (issue #32): a job whose units took a
// known time each says how long the rest will take at that rate, and says nothing when it has
// nothing to go by (not running, paused, no unit done).
#include <gtest/gtest.h>
#include <google/protobuf/util/time_util.h>

#include "server/common/job_eta.h"

namespace farm {
namespace {

using google::protobuf::util::TimeUtil;
using std::chrono::seconds;

v1::Job running_job(int done, int total, seconds since_start, std::chrono::system_clock::time_point now) {
  v1::Job job;
  job.set_state(v1::JOB_STATE_RUNNING);
  job.set_tiles_done(static_cast<std::uint32_t>(done));
  job.set_tiles_total(static_cast<std::uint32_t>(total));
  *job.mutable_started_at() = TimeUtil::MillisecondsToTimestamp(
      std::chrono::duration_cast<std::chrono::milliseconds>((now - since_start).time_since_epoch()).count());
  return job;
}

TEST(JobEta, TheUnitsMeasuredRateTellsTheTimeLeft) {
  const auto now = std::chrono::system_clock::time_point(seconds(1'800'000'000));
  // 25 units in 10 s: 0.4 s a unit, 75 left: 30 s.
  EXPECT_EQ(job_eta(running_job(25, 100, seconds(10), now), now), seconds(30));
  // 1 unit in 90 s, 39 left: an hour.
  EXPECT_EQ(job_eta(running_job(1, 40, seconds(90), now), now), seconds(3510));
  EXPECT_EQ(short_duration(3510), "58m30s");
  EXPECT_EQ(short_duration(30), "30.0s");
  EXPECT_EQ(short_duration(7800), "2h10m");

  EXPECT_FALSE(job_eta(running_job(0, 100, seconds(10), now), now)) << "nothing measured yet";
  v1::Job paused = running_job(25, 100, seconds(10), now);
  paused.set_paused(true);
  EXPECT_FALSE(job_eta(paused, now));
  v1::Job queued = running_job(25, 100, seconds(10), now);
  queued.set_state(v1::JOB_STATE_QUEUED);
  EXPECT_FALSE(job_eta(queued, now));
  EXPECT_FALSE(job_eta(running_job(100, 100, seconds(10), now), now)) << "all done";
}

}  // namespace
}  // namespace farm
