// TLS and mTLS on the farm's services (issue #15), with certificates the test makes with openssl:
// clients verify the server, a server with --tls-ca requires client certificates, and a farm
// whose scheduler and worker both run mTLS renders a job.
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/job_state.h"
#include "tests/support/background_process.h"
#include "tests/support/job_specs.h"
#include "tests/support/run_command.h"
#include "tests/support/scheduler_client.h"
#include "tests/support/temp_dir.h"
#include "tests/support/test_certificates.h"

namespace farm {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::vector<std::string> server_tls_args(const TlsFiles& files, bool require_client_certificates) {
  std::vector<std::string> args{"--tls-cert", files.cert.string(), "--tls-key", files.key.string()};
  if (require_client_certificates) {
    args.push_back("--tls-ca");
    args.push_back(files.ca.string());
  }
  return args;
}

// ListJobs as `identity`; the status code.
grpc::StatusCode list_jobs(const std::string& address, const ClientIdentity& identity) {
  auto stub = test::scheduler_stub(address, identity);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + 20s);
  v1::ListJobsResponse out;
  return stub->ListJobs(&context, v1::ListJobsRequest(), &out).error_code();
}

ClientIdentity tls_client(const fs::path& ca, const TlsFiles* certificate = nullptr) {
  ClientIdentity id;
  id.tls = true;
  id.tls_files.ca = ca;
  if (certificate) {
    id.tls_files.cert = certificate->cert;
    id.tls_files.key = certificate->key;
  }
  return id;
}

class FarmTlsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    certs = test::make_test_certificates(dir / "pki");
    ASSERT_TRUE(certs.problem.empty()) << certs.problem;
  }
  test::TempDir dir;
  test::TestCertificates certs;
};

TEST_F(FarmTlsTest, ClientsVerifyTheServerAndAWrongCaIsRefused) {
  std::vector<std::string> args = server_tls_args(certs.node, false);
  test::SchedulerProcess scheduler(dir / "data", args);
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  EXPECT_NE(scheduler.process().output().find("TLS"), std::string::npos);

  EXPECT_EQ(list_jobs(scheduler.address(), tls_client(certs.ca)), grpc::StatusCode::OK);
  EXPECT_EQ(list_jobs(scheduler.address(), tls_client(certs.other_ca)), grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(list_jobs(scheduler.address(), ClientIdentity{}), grpc::StatusCode::UNAVAILABLE);  // plain text

  // The CLI: --tls-ca, and the same refused with the wrong CA.
  const std::string at = " --scheduler " + scheduler.address();
  const auto ok = test::run_command(test::farm_command("status" + at + " --tls-ca " + certs.ca.string()) + " 2>&1");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  const auto wrong = test::run_command(test::farm_command("status" + at + " --tls-ca " + certs.other_ca.string()) + " 2>&1");
  EXPECT_NE(wrong.exit_code, 0) << wrong.output;
}

TEST_F(FarmTlsTest, MutualTlsRequiresAClientCertificateTheCaSigned) {
  test::SchedulerProcess scheduler(dir / "data", server_tls_args(certs.node, true));
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  EXPECT_NE(scheduler.process().output().find("mTLS"), std::string::npos);

  EXPECT_EQ(list_jobs(scheduler.address(), tls_client(certs.ca, &certs.client)), grpc::StatusCode::OK);
  EXPECT_EQ(list_jobs(scheduler.address(), tls_client(certs.ca)), grpc::StatusCode::UNAVAILABLE);
  EXPECT_EQ(list_jobs(scheduler.address(), tls_client(certs.ca, &certs.stranger)), grpc::StatusCode::UNAVAILABLE);

  // mTLS is authentication: the client certificate's name is the job's owner.
  auto stub = test::scheduler_stub(scheduler.address(), tls_client(certs.ca, &certs.client));
  ASSERT_TRUE(test::upload_assets(*stub, test::cornell_assets()).ok());
  v1::Job job;
  ASSERT_TRUE(test::submit(*stub, test::cornell_job_spec("raster", 16, 16, 1), job).ok());
  EXPECT_EQ(job.owner(), "alice");
}

// Scheduler and worker both mTLS: the worker registers and fetches assets over TLS with its
// certificate, the scheduler calls the worker over TLS with its own.
TEST_F(FarmTlsTest, AFarmRunningMutualTlsEndToEndRendersAJob) {
  test::SchedulerProcess scheduler(dir / "data", server_tls_args(certs.node, true));
  ASSERT_FALSE(scheduler.address().empty()) << scheduler.process().output();
  std::vector<std::string> worker_args = server_tls_args(certs.node, true);
  for (const std::string& a : {std::string("--threads"), std::string("1"), std::string("--cache-dir"),
                               (dir / "w").string(), std::string("--scheduler"), scheduler.address()}) {
    worker_args.push_back(a);
  }
  test::WorkerProcess worker(worker_args);
  ASSERT_FALSE(worker.address().empty()) << worker.process().output();
  ASSERT_TRUE(worker.process().wait_for_line("registered with the scheduler", 20s)) << worker.process().output();

  // `farm submit --wait` over mTLS, to the end and the download.
  const fs::path job_file = dir.write("job.json", test::cornell_job_json("raster", 24, 16, 1));
  for (const auto& [path, file] : test::cornell_assets()) {
    fs::create_directories((dir / path).parent_path());
    fs::copy_file(file, dir / path);
  }
  const std::string args = "submit " + test::shell_quote(job_file.string()) + " --wait --scheduler " +
                           scheduler.address() + " --tls-ca " + certs.ca.string() + " --tls-cert " +
                           certs.client.cert.string() + " --tls-key " + certs.client.key.string();
  const auto r = test::run_command("cd " + test::shell_quote(dir.path().string()) + " && " + test::farm_command(args) + " 2>&1");
  EXPECT_EQ(r.exit_code, 0) << r.output << "\nscheduler:\n" << scheduler.process().output() << "\nworker:\n"
                            << worker.process().output();
}

TEST_F(FarmTlsTest, UnusableCertificateFilesAreBadInputNamingTheFile) {
  const std::string data = " --data-dir " + test::shell_quote((dir / "d").string());
  // A key that is not the certificate's.
  const auto mismatch = test::run_command(test::farm_command(
      "scheduler --listen 127.0.0.1:0" + data + " --tls-cert " + certs.node.cert.string() + " --tls-key " +
      certs.client.key.string()) + " 2>&1");
  EXPECT_EQ(mismatch.exit_code, 2) << mismatch.output;
  EXPECT_NE(mismatch.output.find(certs.client.key.string() + ": this key does not belong"), std::string::npos)
      << mismatch.output;
  // A certificate that is no certificate.
  const fs::path junk = dir.write("junk.pem", "not a certificate\n");
  const auto bad = test::run_command(test::farm_command(
      "worker --tls-cert " + junk.string() + " --tls-key " + certs.node.key.string()) + " 2>&1");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find(junk.string() + ": no PEM certificate"), std::string::npos) << bad.output;
  // A CA without a certificate of its own.
  const auto ca_only = test::run_command(test::farm_command("worker --tls-ca " + certs.ca.string()) + " 2>&1");
  EXPECT_EQ(ca_only.exit_code, 2) << ca_only.output;
}

}  // namespace
}  // namespace farm
