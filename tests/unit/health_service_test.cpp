// HealthService (grpc.health.v1.Health) in process, over an in-process channel: what the spec
// asks of Check and Watch for known and unknown services, before and after shutdown().
#include "server/common/health_service.h"

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include <chrono>
#include <memory>

namespace farm {
namespace {

using namespace std::chrono_literals;
using grpc::health::v1::Health;
using grpc::health::v1::HealthCheckRequest;
using grpc::health::v1::HealthCheckResponse;

class HealthServiceTest : public ::testing::Test {
 protected:
  HealthServiceTest() {
    grpc::ServerBuilder builder;
    builder.RegisterService(&health_);
    server_ = builder.BuildAndStart();
    stub_ = Health::NewStub(server_->InProcessChannel(grpc::ChannelArguments()));
  }
  ~HealthServiceTest() override {
    health_.shutdown();
    server_->Shutdown(std::chrono::system_clock::now() + 60s);
  }

  grpc::Status check(const std::string& service, HealthCheckResponse& response) {
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + 60s);
    HealthCheckRequest request;
    request.set_service(service);
    return stub_->Check(&context, request, &response);
  }

  HealthService health_{{"farm.v1.Worker"}};
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<Health::Stub> stub_;
};

TEST_F(HealthServiceTest, CheckAnswersServingForTheServerAndItsServiceAndNotFoundForOthers) {
  HealthCheckResponse response;
  ASSERT_TRUE(check("", response).ok());
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);
  ASSERT_TRUE(check("farm.v1.Worker", response).ok());
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);
  const grpc::Status unknown = check("farm.v1.Scheduler", response);
  EXPECT_EQ(unknown.error_code(), grpc::StatusCode::NOT_FOUND);
  EXPECT_NE(unknown.error_message().find("farm.v1.Scheduler"), std::string::npos)
      << unknown.error_message();
}

TEST_F(HealthServiceTest, WatchOfAnUnknownServiceSaysServiceUnknownAndStaysOpenUntilTheClientGoes) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 60s);
  HealthCheckRequest request;
  request.set_service("no.such.Service");
  auto reader = stub_->Watch(&context, request);
  HealthCheckResponse response;
  ASSERT_TRUE(reader->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVICE_UNKNOWN);
  context.TryCancel();
  EXPECT_FALSE(reader->Read(&response));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::CANCELLED);
  // The service stays usable after a watcher left.
  ASSERT_TRUE(check("", response).ok());
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);
}

TEST_F(HealthServiceTest, ShutdownTurnsOpenWatchesNotServingAndEndsThem) {
  grpc::ClientContext whole_context, service_context;
  whole_context.set_deadline(std::chrono::system_clock::now() + 60s);
  service_context.set_deadline(std::chrono::system_clock::now() + 60s);
  HealthCheckRequest service_request;
  service_request.set_service("farm.v1.Worker");
  auto whole = stub_->Watch(&whole_context, HealthCheckRequest());
  auto service = stub_->Watch(&service_context, service_request);
  HealthCheckResponse response;
  ASSERT_TRUE(whole->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);
  ASSERT_TRUE(service->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::SERVING);

  health_.shutdown();
  for (auto* reader : {whole.get(), service.get()}) {
    ASSERT_TRUE(reader->Read(&response));
    EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);
    EXPECT_FALSE(reader->Read(&response));
    EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
  }
}

TEST_F(HealthServiceTest, AfterShutdownCheckSaysNotServingAndAWatchEndsAtOnce) {
  health_.shutdown();
  HealthCheckResponse response;
  ASSERT_TRUE(check("", response).ok());
  EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);
  ASSERT_TRUE(check("farm.v1.Worker", response).ok());
  EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);

  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 60s);
  auto reader = stub_->Watch(&context, HealthCheckRequest());
  ASSERT_TRUE(reader->Read(&response));
  EXPECT_EQ(response.status(), HealthCheckResponse::NOT_SERVING);
  EXPECT_FALSE(reader->Read(&response));
  EXPECT_EQ(reader->Finish().error_code(), grpc::StatusCode::UNAVAILABLE);
}

}  // namespace
}  // namespace farm
