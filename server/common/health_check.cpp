#include "server/common/health_check.h"

#include <grpcpp/generic/generic_stub.h>

#include <vector>

namespace farm {

HealthCheck check_health(const std::shared_ptr<grpc::Channel>& channel,
                         std::chrono::system_clock::time_point deadline) {
  grpc::GenericStub stub(channel);
  grpc::ClientContext context;
  context.set_deadline(deadline);
  // HealthCheckRequest{service: ""} encodes as no bytes.
  grpc::Slice empty;
  const grpc::ByteBuffer request(&empty, 1);
  grpc::CompletionQueue queue;
  auto call = stub.PrepareUnaryCall(&context, "/grpc.health.v1.Health/Check", request, &queue);
  call->StartCall();
  grpc::ByteBuffer reply;
  HealthCheck result;
  call->Finish(&reply, &result.status, reinterpret_cast<void*>(1));
  void* tag = nullptr;
  bool ok = false;
  queue.Next(&tag, &ok);  // the one event: Finish
  queue.Shutdown();
  while (queue.Next(&tag, &ok)) {
  }
  if (!result.status.ok()) return result;
  // HealthCheckResponse{status = 1: enum} is the varint field tag 0x08, then the value.
  std::vector<grpc::Slice> slices;
  if (!reply.Dump(&slices).ok()) return result;
  std::string bytes;
  for (const grpc::Slice& s : slices) bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
  if (bytes.size() == 2 && bytes[0] == '\x08') result.serving_status = static_cast<unsigned char>(bytes[1]);
  return result;
}

}  // namespace farm
