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
  // Per property, in order.
  struct Property {
    std::uint64_t list_max = 0;     // 0 for a scalar, else the largest length its count type holds
    std::uint64_t count_bytes = 0;  // a list's length field (binary)
    std::uint64_t value_bytes = 0;  // a scalar, or each value of a list (binary)
  };
  std::vector<Property> properties;
};

struct PlyHeader {
  enum class Format { ascii, binary_little_endian, binary_big_endian } format = Format::ascii;
  std::vector<PlyElement> elements;
  std::uint64_t header_bytes = 0;  // up to and including the end_header line
};

// Parses the header at the start of `bytes` (at most kMaxPlyHeaderBytes of it are looked at).
// Throws InputError naming `file` and the header line for anything malformed, and for a line,
// a comment's too, that Assimp would split where this reader does not (a \r, NUL or form feed
// inside it).
PlyHeader parse_ply_header(std::string_view bytes, const std::string& file);

// Throws InputError naming `file`, the element, its declared count and the bytes it would need
// when the elements cannot all fit in `file_bytes`.
void check_ply_counts(const PlyHeader& header, std::uint64_t file_bytes, const std::string& file);

inline constexpr std::size_t kMaxPlyHeaderBytes = 64 * 1024;

// An ASCII body read against its header: each element is one line of exactly the values its
// properties take (a \r only before a \n, where Assimp's reader and this one both end the line),
// every value a number, every list's length a whole number its count type holds. Assimp's
// ASCII reader trusts all of this (a list length of 1111111111111113 in a 200-byte file, a NUL
// among the numbers), so the body is checked before it reads it. Throws InputError naming
// `file`, the element and its index, or the byte.
void check_ply_ascii_body(const PlyHeader& header, std::string_view body, std::uint64_t body_offset,
                          const std::string& file);

// A binary body walked against its header: every list's length field (in the file's byte order,
// signed where its type is) is no more than its type's limit, at least 0, and its values lie
// inside the file. Assimp takes a char length of -1 for 4 billion and allocates 32 GiB.
void check_ply_binary_body(const PlyHeader& header, std::string_view body, const std::string& file);

// All of the above for an allowed file.
void check_ply_file(const ConfinedFile& file, const std::string& name);

}  // namespace farm
