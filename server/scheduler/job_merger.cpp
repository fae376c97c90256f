#include "server/scheduler/job_merger.h"

#include <fmt/format.h>

#include <stdexcept>

#include "renderer/image/preview.h"
#include "server/common/tile_codec.h"

namespace farm {

namespace fs = std::filesystem;

MergedFrame merge_tiles(const TileResults& results, const MergeRequest& request) {
  MergedFrame merged;
  // The parts cover the image exactly (tiles of split_into_tiles, in batches), so the film need
  // not be cleared first.
  merged.film.reset_for_overwrite(request.image, request.aovs);
  for (std::uint32_t part : request.parts) {
    const v1::RenderTileResponse tile = results.read(request.job_id, part);
    const TileBuffer buffer = decode_tile(tile.tile());
    if (buffer.rect().intersect(request.image) != buffer.rect()) {
      throw std::runtime_error(fmt::format("result {} of job {} lies outside the image", part,
                                           request.job_id));
    }
    merged.film.paste(buffer);
    merged.film.stats() += decode_stats(tile.stats());
  }
  return merged;
}

MergedFiles write_merged(const TileBuffer& film, const fs::path& dir, const std::string& stem,
                         ExrPixelType type) {
  fs::create_directories(dir);
  MergedFiles files{dir / (stem + ".exr"), dir / (stem + ".png")};
  write_exr(film, files.exr, type);
  // write_preview has no temp+rename of its own: write beside and rename.
  const fs::path temp = dir / (".tmp-" + stem + ".png");
  write_preview(film, temp);
  fs::rename(temp, files.preview);
  return files;
}

}  // namespace farm
