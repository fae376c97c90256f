// What the scheduler keeps in memory of a job (RunningJobs) goes when the job ends, and stays gone.
#include "server/scheduler/jobs/running_jobs.h"

#include <gtest/gtest.h>

#include "server/common/read_whole_file.h"
#include "server/common/scene_hash.h"
#include "tests/support/job_specs.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

struct StoredJob {
  test::TempDir dir;
  AssetStore assets{dir / "assets"};
  JobStore store{dir / "jobs.db"};
  RunningJobs jobs{store, assets, dir.path()};

  // The Cornell job in the store (as an earlier process would have left it), its assets uploaded.
  std::string add() {
    for (const auto& [path, file] : test::cornell_assets()) assets.add(read_whole_file(file, "asset"));
    NewJob job;
    job.id = "j1";
    job.name = "cornell";
    job.spec = test::cornell_job_spec("raster", 16, 16, 1);
    job.scene_hash = scene_hash(job.spec);
    job.engine = "raster";
    job.width = job.height = 16;
    job.tiles = {Rect{0, 0, 16, 16}};
    store.jobs().add_job(job, 1000);
    return job.id;
  }
};

TEST(RunningJobsTest, AnActiveJobReadFromTheStoreIsKeptUntilForgotten) {
  StoredJob s;
  const std::string id = s.add();
  EXPECT_EQ(s.jobs.get(id)->job->render.width, 16);
  EXPECT_EQ(s.jobs.count(), 1u);
  s.jobs.add_unit_cost(id, 2.0);
  EXPECT_EQ(s.jobs.forget(id), 0u);
  EXPECT_EQ(s.jobs.count(), 0u);
  EXPECT_FALSE(s.jobs.unit_cost(id));
}

TEST(RunningJobsTest, ALateCallAboutAFinalJobDoesNotBringItBackForGood) {
  StoredJob s;
  const std::string id = s.add();
  s.store.jobs().cancel_job(id, 2000);
  s.jobs.forget(id);
  // A worker's answer arriving after the cancel still needs the job's settings...
  EXPECT_EQ(s.jobs.get(id)->job->render.height, 16);
  // ...but nothing of the job stays: nobody would forget it again.
  EXPECT_EQ(s.jobs.count(), 0u);
}

}  // namespace
}  // namespace farm
