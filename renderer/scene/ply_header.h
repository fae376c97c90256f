#pragma once
// A PLY file declares how many elements it holds before any of them (`element face 10000000`), and
// Assimp's reader sizes its arrays and loops by those counts. So before Assimp sees a PLY file,
// its header is read here and every count is held against the bytes that follow the header: an
// element needs at least two characters a property in ASCII (a digit and a separator) and its
// scalars' sizes in binary (a list at least its length field). A 200-byte file that declares ten
// million faces is refused at once instead of holding a thread and a gigabyte.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "renderer/util/confined_file.h"

namespace farm {

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::uint64_t min_bytes = 0;  // the fewest bytes one element can take in the file's format
};

struct PlyHeader {
  enum class Format { ascii, binary_little_endian, binary_big_endian } format = Format::ascii;
  std::vector<PlyElement> elements;
  std::uint64_t header_bytes = 0;  // up to and including the end_header line
};

// Parses the header at the start of `bytes` (at most kMaxPlyHeaderBytes of it are looked at).
// Throws InputError naming `file` and the header line for anything malformed.
PlyHeader parse_ply_header(std::string_view bytes, const std::string& file);

// Throws InputError naming `file`, the element, its declared count and the bytes it would need
// when the elements cannot all fit in `file_bytes`.
void check_ply_counts(const PlyHeader& header, std::uint64_t file_bytes, const std::string& file);

inline constexpr std::size_t kMaxPlyHeaderBytes = 64 * 1024;

// Both of the above for an allowed file, reading no more than its header.
void check_ply_file(const ConfinedFile& file, const std::string& name);

}  // namespace farm
