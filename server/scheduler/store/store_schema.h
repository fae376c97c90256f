#pragma once
// The job store's schema (job_store.h has the tables): made on a new store, upgraded in place on an
// older one, refused when newer than this farm reads.
#include <memory>
#include <string>

#include "server/scheduler/store/sql_connection.h"

namespace farm {

// Makes the tables of a new store or upgrades an older one's; one transaction (on PostgreSQL under
// a lock, since several schedulers may open one database at once). std::runtime_error naming the
// store for a version this farm cannot read.
void open_store_schema(SqlConnection& db);

// The connection for a store location: PostgreSQL for a postgresql:// (or postgres://) URL, else
// the SQLite file `location`. StoreUnavailable when the server cannot be reached.
std::unique_ptr<SqlConnection> connect_store(const std::string& location);

}  // namespace farm
