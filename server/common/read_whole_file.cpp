#include "server/common/read_whole_file.h"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

#include "renderer/util/input_error.h"

namespace farm {

std::string read_whole_file(const std::filesystem::path& file, std::string_view what) {
  std::ifstream in(file, std::ios::binary);
  std::ostringstream bytes;
  if (in) bytes << in.rdbuf();
  if (!in || in.bad()) throw InputError(fmt::format("{}: cannot read the {}", file.string(), what));
  return bytes.str();
}

}  // namespace farm
