#include "server/scheduler/store/owner_shares.h"

#include <fmt/format.h>

#include "server/scheduler/store/store_part.h"

namespace farm {

namespace {

// The pass an owner entering the queue starts from: the least of the owners with active jobs, or,
// with none, the greatest of all (an empty farm forgets who used it).
std::int64_t entry_pass(SqlConnection& db) {
  {
    Query s(db.prepared(fmt::format("SELECT MIN(o.pass) FROM owners o WHERE EXISTS (SELECT 1 FROM jobs j "
                                    "WHERE j.owner = o.owner AND j.state IN {})",
                                    kActiveSql)));
    if (s.step() && !s.is_null(0)) return s.i64(0);
  }
  Query s(db.prepared("SELECT COALESCE(MAX(pass), 0) FROM owners"));
  return s.step() ? s.i64(0) : 0;
}

}  // namespace

void enter_owner(SqlConnection& db, const std::string& owner, std::optional<std::int64_t> weight_milli) {
  const std::int64_t pass = entry_pass(db);
  Query(db.prepared("INSERT INTO owners (owner, pass) VALUES (?1, ?2) ON CONFLICT (owner) DO UPDATE SET "
                    "pass = CASE WHEN owners.pass < ?2 THEN ?2 ELSE owners.pass END"))
      .bind(1, owner).bind(2, pass).run();
  if (weight_milli) {
    Query(db.prepared("UPDATE owners SET weight_milli = ? WHERE owner = ?")).bind(1, *weight_milli).bind(2, owner).run();
  }
}

void charge_owner(SqlConnection& db, const std::string& owner, std::int64_t units) {
  Query(db.prepared("UPDATE owners SET pass = pass + (? * 1000000) / weight_milli WHERE owner = ?"))
      .bind(1, units).bind(2, owner).run();
}

}  // namespace farm
