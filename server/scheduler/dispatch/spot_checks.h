#pragma once
// Spot checks (`farm scheduler --verify-fraction F`). A tile's pixels are a pure function of its
// job (docs/architecture.md, "The engine contract"), so the same tile rendered on two workers must come back
// bit-identical; a worker whose pixels only look right (they pass tile_result_check.h) is caught
// by rendering some of its tiles again elsewhere.
//
// Which tiles: each tile of a job is chosen with probability F, by a hash of the job id and the
// tile index keyed with a secret of this scheduler process, so that a worker, which sees job ids
// and tile indices, cannot tell which of its tiles will be checked. One tile of each job is always
// chosen when F > 0. A batch holding chosen tiles is checked on the row segment from its first
// chosen tile to its last, and its tiles are not marked done until the check is settled.
//
// What the opinions say (judge): the first is the batch's own worker's; each further one comes
// from a worker not asked before. The first opinion that agrees bit for bit with an earlier one
// settles the check, and every opinion that differs from the two is wrong. Three opinions that
// all differ settle nothing: the batch fails and is rendered again.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "proto/farm.pb.h"
#include "renderer/image/tile_buffer.h"
#include "renderer/job/render_settings.h"
#include "server/scheduler/jobs/unit_grid.h"
#include "server/scheduler/store/job_store.h"

namespace farm {

// Tiles first .. first + count - 1 of a job's grid, one row segment, `rect` their union.
struct UnitSpan {
  std::uint32_t first = 0;
  std::uint32_t count = 0;
  Rect rect;
};

class SpotCheckChooser {
 public:
  // `fraction` in [0, 1]; `key` is the process's secret (random unless a test fixes it).
  SpotCheckChooser(double fraction, std::uint64_t key);

  bool enabled() const { return fraction_ > 0.0; }
  // Whether tile `index` of the job's `tiles` is checked.
  bool chosen(const std::string& job_id, std::uint32_t index, std::uint32_t tiles) const;
  // The part of `batch` to render again: its first chosen tile to its last; nullopt when it holds
  // none. `grid` lays out the job's units.
  std::optional<UnitSpan> span(const UnitBatch& batch, std::uint32_t tiles, const UnitGrid& grid) const;

 private:
  double fraction_;
  std::uint64_t key_;
};

// One worker's pixels for a checked span.
struct Opinion {
  std::string worker_id;  // the registry's id
  std::string worker;     // its address, for messages
  v1::TileData tile;      // the span's pixels as that worker rendered them
};

struct Judgement {
  enum class Outcome { NeedAnother, Agreed, NoAgreement };
  Outcome outcome = Outcome::NeedAnother;
  std::size_t agreed_with = 0;     // Agreed: the earlier opinion the new one matches
  std::vector<std::size_t> wrong;  // Agreed: the earlier opinions that differ from the two
};

// Weighs `next` against `opinions` (opinions[0] the batch's own worker's). NeedAnother and
// NoAgreement add it to `opinions`; Agreed leaves them as they were.
Judgement judge(std::vector<Opinion>& opinions, Opinion next);

}  // namespace farm
