#include "tests/support/store_downgrade.h"

#include <fmt/format.h>

namespace farm::test {

std::vector<std::string> back_to_version(int version) {
  // What each version added, undone (indexes before their columns).
  const std::vector<std::pair<int, std::vector<std::string>>> added = {
      {10, {"DROP INDEX jobs_by_owner", "DROP INDEX jobs_by_frames_followed", "DROP TABLE dependencies",
            "DROP TABLE owners", "ALTER TABLE jobs DROP COLUMN max_workers",
            "ALTER TABLE jobs DROP COLUMN max_units_in_flight", "ALTER TABLE jobs DROP COLUMN after_frames_seq"}},
      {9, {"ALTER TABLE jobs DROP COLUMN required_tags", "ALTER TABLE jobs DROP COLUMN min_threads"}},
      {8, {"ALTER TABLE jobs DROP COLUMN paused", "DROP TABLE job_log"}},
      {7, {"ALTER TABLE tiles DROP COLUMN scheduler", "DROP TABLE schedulers"}},
      {6, {"ALTER TABLE tiles DROP COLUMN pass", "ALTER TABLE jobs DROP COLUMN passes"}},
      {5, {"DROP INDEX tiles_by_frame", "DROP TABLE frames", "ALTER TABLE tiles DROP COLUMN frame",
           "ALTER TABLE jobs DROP COLUMN frame_first", "ALTER TABLE jobs DROP COLUMN frame_last",
           "ALTER TABLE jobs DROP COLUMN frame_step", "ALTER TABLE jobs DROP COLUMN frames_total",
           "ALTER TABLE jobs DROP COLUMN frames_done"}},
      {4, {"ALTER TABLE tiles DROP COLUMN lost_attempts"}},
      {3, {"ALTER TABLE jobs DROP COLUMN owner"}},
      {2, {"ALTER TABLE tiles DROP COLUMN part"}},
  };
  std::vector<std::string> statements;
  for (const auto& [v, undo] : added) {
    if (v > version) statements.insert(statements.end(), undo.begin(), undo.end());
  }
  statements.push_back(fmt::format("UPDATE schema_version SET version = {}", version));
  return statements;
}

}  // namespace farm::test
