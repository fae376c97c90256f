#include "server/common/farm_server.h"

#include <grpcpp/ext/proto_server_reflection_plugin.h>

#include <vector>

namespace farm {

namespace {

// Server reflection on this builder. InitProtoReflectionServerBuilderPlugin() adds it to builders
// made after the call (so the call must come before the builder), and the reflection library
// makes that call itself from a static initializer once it is linked, as it is here; an option
// adds the plugin to a builder that already exists, unless the builder has it already (twice
// would register the reflection service twice).
class ReflectionOption final : public grpc::ServerBuilderOption {
 public:
  void UpdateArguments(grpc::ChannelArguments* /*args*/) override {}
  void UpdatePlugins(std::vector<std::unique_ptr<grpc::ServerBuilderPlugin>>* plugins) override {
    auto reflection = std::make_unique<grpc::reflection::ProtoServerReflectionPlugin>();
    for (const auto& plugin : *plugins) {
      if (plugin->name() == reflection->name()) return;
    }
    plugins->push_back(std::move(reflection));
  }
};

}  // namespace

FarmServer::FarmServer(const std::string& service) : health_({service}) {}

FarmServer::~FarmServer() { health_.shutdown(); }

std::unique_ptr<FarmServer> FarmServer::start(grpc::ServerBuilder& builder,
                                              const std::string& service) {
  auto server = std::make_unique<FarmServer>(service);
  builder.RegisterService(&server->health_);
  builder.SetOption(std::make_unique<ReflectionOption>());
  server->server_ = builder.BuildAndStart();
  if (!server->server_) return nullptr;
  return server;
}

void FarmServer::Shutdown(std::chrono::system_clock::time_point deadline) {
  health_.shutdown();
  server_->Shutdown(deadline);
}

}  // namespace farm
