#pragma once
// A farm.v1.Worker in the test's process that renders honestly (the worker's own TileRenderer)
// and then lies as it is told: a shifted rect, a missing, extra or short plane, a NaN, or pixels
// that look right but are not (a few bits flipped). It serves grpc.health.v1 so that a scheduler
// probes it up like a `farm worker`, on a free port of 127.0.0.1. It has no scheduler to fetch
// assets from: the scheduler sends the job's files inline after the first refusal.
#include <grpcpp/grpcpp.h>

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>

#include "proto/farm.grpc.pb.h"
#include "server/worker/tile_renderer.h"

namespace farm::test {

enum class Lie {
  None,           // honest
  ShiftedRect,    // the rect moved one pixel right, the planes as rendered
  MissingPlane,   // the normal plane left out
  ExtraPlane,     // a bvh_cost plane the job did not ask for
  ShortPlane,     // the depth plane one float short
  NaN,            // one red value NaN
  NegativeDepth,  // one depth -1
  FlippedBits,    // a few red and green values with a mantissa bit flipped: plausible, wrong
  FailsAtOnce,    // every RenderTile answered INTERNAL at once, with no message (a broken install)
};
const char* to_string(Lie lie);

// What `lie` does to an honest reply (the unit tests use it on engine output).
void tell_lie(Lie lie, v1::RenderTileResponse& reply);

class FakeWorker {
 public:
  explicit FakeWorker(const std::filesystem::path& cache_dir, Lie lie = Lie::None);
  ~FakeWorker();
  FakeWorker(const FakeWorker&) = delete;
  FakeWorker& operator=(const FakeWorker&) = delete;

  const std::string& address() const { return address_; }  // empty if it did not start
  void set_lie(Lie lie) { lie_ = lie; }
  // Once `n` replies have been sent, calls wait before rendering until release() (or until their
  // caller cancels them). Calls that arrive before the n-th reply is sent go ahead.
  void hold_after(int n);
  void release();
  int calls_answered() const { return answered_.load(); }  // replies sent with OK
  int lies_told() const { return lies_.load(); }
  // The next `n` calls that come without their job are answered NOT_FOUND, as a worker that no
  // longer holds the scene answers.
  void forget_scenes_for(int n) { forget_ = n; }
  int calls_received() const { return calls_.load(); }  // every RenderTile, answered or not
  int calls_arrived() const { return arrived_.load(); }  // likewise, and the ones held now
  int calls_with_job() const { return calls_with_job_.load(); }
  std::uint64_t job_text_bytes() const { return job_bytes_.load(); }  // job_json received, all calls

 private:
  class Service;

  std::atomic<Lie> lie_;
  std::atomic<int> answered_{0}, lies_{0}, calls_{0}, calls_with_job_{0}, arrived_{0};
  std::atomic<std::uint64_t> job_bytes_{0};
  std::atomic<int> forget_{0};
  std::mutex mutex_;  // guards hold_after_
  std::condition_variable released_;
  int hold_after_ = -1;  // -1: no call waits
  std::unique_ptr<TileRenderer> renderer_;
  std::unique_ptr<Service> service_;
  std::unique_ptr<grpc::Server> server_;
  std::string address_;
};

}  // namespace farm::test
