#include "tests/support/fake_worker.h"

#include <grpcpp/health_check_service_interface.h>

#include <chrono>
#include <cstdint>
#include <cstring>
#include <limits>

namespace farm::test {

namespace {

void set_float(std::string& plane, std::size_t index, float value) {
  if ((index + 1) * sizeof(float) <= plane.size()) std::memcpy(plane.data() + index * sizeof(float), &value, sizeof value);
}

void flip_bit(std::string& plane, std::size_t index, int bit) {
  if ((index + 1) * sizeof(float) > plane.size()) return;
  std::uint32_t bits;
  std::memcpy(&bits, plane.data() + index * sizeof bits, sizeof bits);
  bits ^= std::uint32_t{1} << bit;
  std::memcpy(plane.data() + index * sizeof bits, &bits, sizeof bits);
}

}  // namespace

const char* to_string(Lie lie) {
  switch (lie) {
    case Lie::None: return "none";
    case Lie::ShiftedRect: return "shifted-rect";
    case Lie::MissingPlane: return "missing-plane";
    case Lie::ExtraPlane: return "extra-plane";
    case Lie::ShortPlane: return "short-plane";
    case Lie::NaN: return "nan";
    case Lie::NegativeDepth: return "negative-depth";
    case Lie::FlippedBits: return "flipped-bits";
    case Lie::FailsAtOnce: return "fails-at-once";
  }
  return "?";
}

void tell_lie(Lie lie, v1::RenderTileResponse& reply) {
  v1::TileData& t = *reply.mutable_tile();
  switch (lie) {
    case Lie::None:
    case Lie::FailsAtOnce:  // answered before any rendering
      return;
    case Lie::ShiftedRect:
      t.mutable_rect()->set_x0(t.rect().x0() + 1);
      t.mutable_rect()->set_x1(t.rect().x1() + 1);
      return;
    case Lie::MissingPlane:
      t.clear_normal();
      return;
    case Lie::ExtraPlane:
      t.set_bvh_cost(std::string(static_cast<std::size_t>(t.width()) * static_cast<std::size_t>(t.height()) * sizeof(float), '\0'));
      return;
    case Lie::ShortPlane:
      if (t.depth().size() >= sizeof(float)) t.mutable_depth()->resize(t.depth().size() - sizeof(float));
      return;
    case Lie::NaN:
      set_float(*t.mutable_rgba(), 0, std::numeric_limits<float>::quiet_NaN());
      return;
    case Lie::NegativeDepth:
      set_float(*t.mutable_depth(), 0, -1.0f);
      return;
    case Lie::FlippedBits: {
      // Bit 20 of a float is its mantissa's third bit: the value changes by an eighth or so,
      // stays finite and keeps its sign. Red and green of every seventh pixel.
      const std::size_t pixels = t.rgba().size() / (4 * sizeof(float));
      for (std::size_t p = 0; p < pixels; p += 7) {
        flip_bit(*t.mutable_rgba(), 4 * p, 20);
        flip_bit(*t.mutable_rgba(), 4 * p + 1, 20);
      }
      return;
    }
  }
}

class FakeWorker::Service final : public v1::Worker::Service {
 public:
  explicit Service(FakeWorker& owner) : owner_(owner) {}

  grpc::Status RenderTile(grpc::ServerContext* context, const v1::RenderTileRequest* request,
                          v1::RenderTileResponse* response) override {
    ++owner_.arrived_;
    {
      std::unique_lock lock(owner_.mutex_);
      while (owner_.hold_after_ >= 0 && owner_.answered_.load() >= owner_.hold_after_) {
        // Polled: a held call must still notice that its caller gave up.
        if (context->IsCancelled()) return {grpc::StatusCode::CANCELLED, "cancelled while held"};
        owner_.released_.wait_for(lock, std::chrono::milliseconds(10));
      }
    }
    ++owner_.calls_;
    if (owner_.lie_.load() == Lie::FailsAtOnce) {
      ++owner_.lies_;
      return {grpc::StatusCode::INTERNAL, ""};
    }
    if (request->has_job()) {
      ++owner_.calls_with_job_;
      owner_.job_bytes_ += request->job().job_json().size();
    } else if (owner_.forget_.fetch_sub(1) > 0) {
      return {grpc::StatusCode::NOT_FOUND, "scene not prepared on this worker: send its job"};
    } else {
      owner_.forget_ = 0;
    }
    RenderControl control;
    control.cancelled = [context] { return context->IsCancelled(); };
    control.deadline = context->deadline();
    grpc::Status status = owner_.renderer_->render(*request, *response, control);
    if (!status.ok()) return status;
    const Lie lie = owner_.lie_.load();
    tell_lie(lie, *response);
    if (lie != Lie::None) ++owner_.lies_;
    ++owner_.answered_;
    return grpc::Status::OK;
  }

 private:
  FakeWorker& owner_;
};

FakeWorker::FakeWorker(const std::filesystem::path& cache_dir, Lie lie) : lie_(lie) {
  TileRendererOptions options;
  options.blobs_dir = cache_dir / "blobs";
  options.cache_dir = cache_dir;
  options.threads = 1;
  options.log_level = LogLevel::warn;
  renderer_ = std::make_unique<TileRenderer>(options);
  service_ = std::make_unique<Service>(*this);
  grpc::EnableDefaultHealthCheckService(true);
  grpc::ServerBuilder builder;
  int port = 0;
  builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port);
  builder.SetMaxReceiveMessageSize(64 << 20);
  builder.RegisterService(service_.get());
  server_ = builder.BuildAndStart();
  if (server_ && port != 0) address_ = "127.0.0.1:" + std::to_string(port);
}

FakeWorker::~FakeWorker() {
  release();
  if (server_) server_->Shutdown(std::chrono::system_clock::now() + std::chrono::seconds(1));
}

void FakeWorker::hold_after(int n) {
  {
    std::lock_guard lock(mutex_);
    hold_after_ = n;
  }
  released_.notify_all();
}

void FakeWorker::release() {
  {
    std::lock_guard lock(mutex_);
    hold_after_ = -1;
  }
  released_.notify_all();
}

}  // namespace farm::test
