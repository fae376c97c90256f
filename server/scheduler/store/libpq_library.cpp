#include "server/scheduler/store/libpq_library.h"

#include <dlfcn.h>
#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace farm {
namespace {

// libpq's soname since PostgreSQL 8.0: Debian's libpq5.
constexpr const char* kLibPq = "libpq.so.5";

template <typename Function>
void bind(void* library, const char* name, Function& function) {
  function = reinterpret_cast<Function>(dlsym(library, name));
  if (!function) {
    throw std::runtime_error(fmt::format("PostgreSQL job store: {} has no {} (libpq too old or damaged)", kLibPq, name));
  }
}

LibPq load() {
  // Never closed: its functions are called until the process ends.
  void* library = dlopen(kLibPq, RTLD_NOW | RTLD_LOCAL);
  if (!library) {
    const char* why = dlerror();
    throw std::runtime_error(fmt::format("PostgreSQL job store: cannot load {} ({}); install libpq "
                                         "(Debian and Ubuntu: apt install libpq5)",
                                         kLibPq, why ? why : "unknown error"));
  }
  LibPq pq{};
  bind(library, "PQconnectdbParams", pq.connectdbParams);
  bind(library, "PQstatus", pq.status);
  bind(library, "PQfinish", pq.finish);
  bind(library, "PQreset", pq.reset);
  bind(library, "PQsetNoticeProcessor", pq.setNoticeProcessor);
  bind(library, "PQerrorMessage", pq.errorMessage);
  bind(library, "PQhost", pq.host);
  bind(library, "PQuser", pq.user);
  bind(library, "PQport", pq.port);
  bind(library, "PQdb", pq.db);
  bind(library, "PQexec", pq.exec);
  bind(library, "PQexecParams", pq.execParams);
  bind(library, "PQprepare", pq.prepare);
  bind(library, "PQexecPrepared", pq.execPrepared);
  bind(library, "PQresultStatus", pq.resultStatus);
  bind(library, "PQresultErrorMessage", pq.resultErrorMessage);
  bind(library, "PQresultErrorField", pq.resultErrorField);
  bind(library, "PQclear", pq.clear);
  bind(library, "PQntuples", pq.ntuples);
  bind(library, "PQnfields", pq.nfields);
  bind(library, "PQgetisnull", pq.getisnull);
  bind(library, "PQgetvalue", pq.getvalue);
  bind(library, "PQgetlength", pq.getlength);
  bind(library, "PQcmdTuples", pq.cmdTuples);
  bind(library, "PQunescapeBytea", pq.unescapeBytea);
  bind(library, "PQescapeIdentifier", pq.escapeIdentifier);
  bind(library, "PQfreemem", pq.freemem);
  bind(library, "PQnotifies", pq.notifies);
  bind(library, "PQsocket", pq.socket);
  bind(library, "PQconsumeInput", pq.consumeInput);
  return pq;
}

}  // namespace

const LibPq& libpq() {
  // A failed load throws out of the initialiser, and the next call tries again: a missing libpq
  // says so to every store that asks.
  static const LibPq functions = load();
  return functions;
}

}  // namespace farm
