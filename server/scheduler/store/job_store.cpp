#include "server/scheduler/store/job_store.h"

#include "server/scheduler/store/sqlite_connection.h"

namespace farm {

JobStore::JobStore(const std::filesystem::path& sqlite_file)
    : JobStore(std::make_unique<SqliteConnection>(sqlite_file)) {}

JobStore::JobStore(std::unique_ptr<SqlConnection> db)
    : session_(std::make_unique<StoreSession>(std::move(db))),
      jobs_(*session_),
      units_(*session_),
      frames_(*session_),
      leases_(*session_),
      log_(*session_),
      dependencies_(*session_) {
  SqlConnection& sql = *session_->db;
  open_store_schema(sql);
  // Units in flight when the last scheduler stopped: their results died with it. A SQLite store
  // has one scheduler, so every running unit was its; on PostgreSQL only those of no scheduler
  // (an older version's), the others coming back when their scheduler's lease runs out
  // (SchedulerLeases::reap_expired).
  sql.exec(sql.dialect() == SqlDialect::SQLite
               ? "UPDATE tiles SET state = 0, worker = '', scheduler = '' WHERE state = 1"
               : "UPDATE tiles SET state = 0, worker = '' WHERE state = 1 AND scheduler = ''");
  // Likewise the merges and ends the last scheduler had claimed (on PostgreSQL: reaped with its lease).
  if (sql.dialect() == SqlDialect::SQLite) sql.exec("DELETE FROM claims");
}

JobStore::~JobStore() = default;

std::string JobStore::describe() const { return session_->db->describe(); }

}  // namespace farm
