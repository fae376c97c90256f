#pragma once
// libpq, loaded when the first PostgreSQL store is opened instead of when `farm` starts: linked,
// it and the twenty libraries it needs (Kerberos, LDAP, GnuTLS...) were loaded and relocated by
// every farm command, 2.8 ms of each start-up, for the few processes that ever use PostgreSQL
// (docs/architecture.md, 9.1). The types and constants still come from <libpq-fe.h>.
#include <libpq-fe.h>

namespace farm {

// The libpq functions the PostgreSQL store calls, named as libpq names them less the "PQ".
struct LibPq {
  decltype(&::PQconnectdbParams) connectdbParams;
  decltype(&::PQstatus) status;
  decltype(&::PQfinish) finish;
  decltype(&::PQreset) reset;
  decltype(&::PQsetNoticeProcessor) setNoticeProcessor;
  decltype(&::PQerrorMessage) errorMessage;
  decltype(&::PQhost) host;
  decltype(&::PQuser) user;
  decltype(&::PQport) port;
  decltype(&::PQdb) db;
  decltype(&::PQexec) exec;
  decltype(&::PQexecParams) execParams;
  decltype(&::PQprepare) prepare;
  decltype(&::PQexecPrepared) execPrepared;
  decltype(&::PQresultStatus) resultStatus;
  decltype(&::PQresultErrorMessage) resultErrorMessage;
  decltype(&::PQresultErrorField) resultErrorField;
  decltype(&::PQclear) clear;
  decltype(&::PQntuples) ntuples;
  decltype(&::PQnfields) nfields;
  decltype(&::PQgetisnull) getisnull;
  decltype(&::PQgetvalue) getvalue;
  decltype(&::PQgetlength) getlength;
  decltype(&::PQcmdTuples) cmdTuples;
  decltype(&::PQunescapeBytea) unescapeBytea;
  decltype(&::PQescapeIdentifier) escapeIdentifier;
  decltype(&::PQfreemem) freemem;
  decltype(&::PQnotifies) notifies;
  decltype(&::PQsocket) socket;
  decltype(&::PQconsumeInput) consumeInput;
};

// Loads libpq.so.5 on the first call (thread-safe), and then hands back the same functions.
// Throws std::runtime_error, saying which package to install, when libpq cannot be loaded or
// lacks one of them; every later call throws the same.
const LibPq& libpq();

}  // namespace farm
