#include "server/client/scheduler_connection.h"

#include <cstdlib>

#include "server/common/token_table.h"

namespace farm {
namespace {

std::string flag_or_env(const std::string& flag, const char* variable) {
  if (!flag.empty()) return flag;
  const char* value = std::getenv(variable);
  return value != nullptr ? value : "";
}

}  // namespace

SchedulerConnection resolve_scheduler_connection(const SchedulerConnectionFlags& flags) {
  SchedulerConnection c;
  c.address = flag_or_env(flags.address, "FARM_SCHEDULER");
  if (c.address.empty()) c.address = kDefaultSchedulerAddress;
  c.identity.token = read_client_token(flags.token_file);
  c.identity.tls_files.ca = flag_or_env(flags.tls.ca.string(), "FARM_TLS_CA");
  c.identity.tls_files.cert = flag_or_env(flags.tls.cert.string(), "FARM_TLS_CERT");
  c.identity.tls_files.key = flag_or_env(flags.tls.key.string(), "FARM_TLS_KEY");
  c.identity.tls = !c.identity.tls_files.ca.empty() || c.identity.tls_files.has_certificate();
  return c;
}

}  // namespace farm
