#pragma once
// How a process calls a farm service: plain text or TLS (verifying the server, presenting a client
// certificate for mTLS), and the bearer token every call carries. Used by `farm submit` and the
// other client commands, by workers calling their scheduler, and by schedulers calling workers.
#include <grpcpp/channel.h>
#include <grpcpp/support/channel_arguments.h>

#include <memory>
#include <string>

#include "server/common/tls_files.h"

namespace farm {

struct ClientIdentity {
  std::string token;  // sent as `authorization: Bearer <token>`; empty: none
  bool tls = false;   // TLS, verifying the server against tls.ca (else the system's roots)
  TlsFiles tls_files; // cert + key: the client certificate presented (mTLS)
};

// A channel to `address` for `identity`. InputError when its TLS files are unusable.
std::shared_ptr<grpc::Channel> open_channel(const std::string& address, const ClientIdentity& identity,
                                            const grpc::ChannelArguments& args = {});

}  // namespace farm
