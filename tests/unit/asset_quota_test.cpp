// The asset store's total size (server/scheduler/assets/asset_quota.h): uploads reserve their size, the
// stored blobs count as they are on disk, and a reservation ends with its upload.
#include <gtest/gtest.h>

#include <string>

#include "server/common/asset_store.h"
#include "server/common/service_error.h"
#include "server/scheduler/assets/asset_quota.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

grpc::StatusCode code_of_reserving(AssetQuota& quota, std::uint64_t bytes, const std::string& owner = "other") {
  try {
    quota.reserve(bytes, owner);
  } catch (const ServiceError& e) {
    return e.code();
  }
  return grpc::StatusCode::OK;
}

TEST(AssetQuota, StoredBlobsAndUploadsInFlightCountAgainstTheLimit) {
  test::TempDir dir;
  AssetStore store(dir / "assets");
  AssetQuota quota(store.dir(), 1000);
  store.add(std::string(600, 'a'));
  dir.write("assets/.tmp-partial-upload", std::string(5000, 't'));  // counted by its reservation
  EXPECT_EQ(quota.stored_bytes(), 600u);

  EXPECT_EQ(code_of_reserving(quota, 401), grpc::StatusCode::RESOURCE_EXHAUSTED);
  {
    const AssetQuota::Reservation in_flight = quota.reserve(300, "alice");
    EXPECT_EQ(code_of_reserving(quota, 101), grpc::StatusCode::RESOURCE_EXHAUSTED);
    EXPECT_EQ(code_of_reserving(quota, 100), grpc::StatusCode::OK);
  }
  // The upload ended without a blob: its bytes are free again.
  EXPECT_EQ(code_of_reserving(quota, 400), grpc::StatusCode::OK);

  store.remove(store.add(std::string(600, 'a')));  // a blob removed counts no more
  EXPECT_EQ(quota.stored_bytes(), 0u);
  EXPECT_EQ(code_of_reserving(quota, 1000), grpc::StatusCode::OK);
  EXPECT_EQ(code_of_reserving(quota, 1001), grpc::StatusCode::RESOURCE_EXHAUSTED);
}

// One owner's uploads in flight hold at most a quarter of the limit (issue #32), the first of
// them whatever its size; another owner is not held back by them.
TEST(AssetQuota, OneOwnersUploadsInFlightHoldAQuarterOfTheLimitAtMost) {
  test::TempDir dir;
  AssetStore store(dir / "assets");
  AssetQuota quota(store.dir(), 1000);
  EXPECT_EQ(quota.owner_share(), 250u);
  const AssetQuota::Reservation big = quota.reserve(400, "alice");  // her first: allowed
  EXPECT_EQ(code_of_reserving(quota, 1, "alice"), grpc::StatusCode::RESOURCE_EXHAUSTED);
  EXPECT_EQ(code_of_reserving(quota, 250, "bob"), grpc::StatusCode::OK);
  {
    const AssetQuota::Reservation bobs = quota.reserve(200, "bob");
    EXPECT_EQ(code_of_reserving(quota, 50, "bob"), grpc::StatusCode::OK);
    EXPECT_EQ(code_of_reserving(quota, 51, "bob"), grpc::StatusCode::RESOURCE_EXHAUSTED);
  }
  EXPECT_EQ(code_of_reserving(quota, 250, "bob"), grpc::StatusCode::OK);  // his reservation ended
}

TEST(AssetQuota, TheMessageNamesTheSizesTheLimitAndTheFlag) {
  test::TempDir dir;
  AssetStore store(dir / "assets");
  store.add(std::string(700, 'a'));
  AssetQuota quota(store.dir(), 1000);
  try {
    quota.reserve(400);
    FAIL() << "400 bytes over 700 stored passed a limit of 1000";
  } catch (const ServiceError& e) {
    EXPECT_STREQ(e.what(), "asset of 400 bytes: the scheduler's asset store holds 700 bytes (0 more "
                           "being uploaded) of at most 1000 (--max-asset-store-bytes)");
  }
}

TEST(AssetQuota, ZeroMeansNoLimit) {
  test::TempDir dir;
  AssetQuota quota(dir.path(), 0);
  EXPECT_EQ(code_of_reserving(quota, std::uint64_t{1} << 62), grpc::StatusCode::OK);
}

}  // namespace
}  // namespace farm
