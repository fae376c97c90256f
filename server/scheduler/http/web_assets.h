#pragma once
// The dashboard's static files (server/web/), compiled into the binary by the build
// (embed_web_assets.cmake), so a scheduler serves its pages from wherever it is installed and a
// page always matches the API of the binary that serves it.
#include <string_view>

namespace farm {

struct WebAsset {
  std::string_view name;   // "index.html"
  std::string_view type;   // its Content-Type
  std::string_view bytes;
};

// nullptr for a name that is not one of the files.
const WebAsset* find_web_asset(std::string_view name);

}  // namespace farm
