// The worker's RenderTile handler (server/worker/worker_service.cpp over TileRenderer): one real
// WorkerService with its cache dir in the scratch folder and one render thread, served in
// process and called through the generated stub as the scheduler calls it.
//
// An input is a serialized farm.v1.RenderTileRequest: the job's text, its assets by hash, files
// inline, the scene hash and the rectangle. So that one input costs milliseconds, not seconds of
// rendering, a job text that parses as JSON is held to a tiny frame before the call: at most
// 32x32 pixels, 4 samples and 3 bounces (then the request's scene_hash, computed over the old
// text, is dropped and the worker computes it). The rest of the job, its models and its files are
// the fuzzer's.
//
// Property: every call returns a status within its deadline; a crash, a hang or unbounded growth
// is a finding.
#include <google/protobuf/stubs/logging.h>
#include <grpcpp/grpcpp.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/common/log.h"
#include "server/worker/worker_service.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

namespace v1 = farm::v1;

// Clamps an integer member of `render` to at most `most` (leaving other types to the parser).
void clamp_member(nlohmann::json& render, const char* key, std::int64_t most) {
  const auto it = render.find(key);
  if (it != render.end() && it->is_number_integer() && it->get<std::int64_t>() > most) *it = most;
}

// The job text held to a tiny frame; unchanged when it is no JSON object with a render object.
bool bound_job(v1::JobSpec& spec) {
  nlohmann::json job = nlohmann::json::parse(spec.job_json(), nullptr, /*allow_exceptions=*/false);
  if (!job.is_object() || !job.contains("render") || !job["render"].is_object()) return false;
  nlohmann::json& render = job["render"];
  clamp_member(render, "width", 32);
  clamp_member(render, "height", 32);
  clamp_member(render, "spp", 4);
  clamp_member(render, "max_depth", 3);
  // -1 is the path tracer's unbounded depth (Russian roulette): bounded too.
  if (render.contains("max_depth") && render["max_depth"] == -1) render["max_depth"] = 3;
  if (!render.contains("width")) render["width"] = 32;
  if (!render.contains("height")) render["height"] = 32;
  spec.set_job_json(job.dump());
  return true;
}

class InProcessWorker {
 public:
  InProcessWorker() : service_(options()) {
    grpc::ServerBuilder builder;
    builder.RegisterService(&service_);
    server_ = builder.BuildAndStart();
    stub_ = v1::Worker::NewStub(server_->InProcessChannel(grpc::ChannelArguments()));
  }

  void render(v1::RenderTileRequest& request) {
    if (request.has_job() && bound_job(*request.mutable_job())) request.clear_scene_hash();
    grpc::ClientContext context;
    context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
    v1::RenderTileResponse response;
    (void)stub_->RenderTile(&context, request, &response);
  }

 private:
  static farm::WorkerOptions options() {
    farm::WorkerOptions o;
    o.cache_dir = farm::fuzz::scratch_dir() / "worker";
    o.threads = 1;
    o.max_scenes = 2;
    o.cache_memory_mb = 256;
    return o;
  }

  farm::WorkerService service_;
  std::unique_ptr<grpc::Server> server_;
  std::unique_ptr<v1::Worker::Stub> stub_;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // One worker for the run, as a real one serves call after call (its scene cache included).
  static auto* worker = [] {
    farm::set_log_level("off");
    // Protobuf logs every string field of invalid UTF-8 it refuses to parse: thousands of lines
    // a second of fuzzing, none of them a finding (the parse fails, and the input is skipped).
    google::protobuf::SetLogHandler(nullptr);
    return new InProcessWorker();
  }();
  v1::RenderTileRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return 0;
  worker->render(request);
  return 0;
}
