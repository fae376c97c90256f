#include "renderer/loaders/ply_header.h"

#include <fmt/format.h>

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>

#include "renderer/util/input_error.h"

namespace farm {
namespace {

// The largest list length each integer type can count.
const std::map<std::string, std::uint64_t, std::less<>>& count_type_max() {
  static const std::map<std::string, std::uint64_t, std::less<>> max{
      {"char", 127},     {"uchar", 255},          {"int8", 127},    {"uint8", 255},
      {"short", 32767},  {"ushort", 65535},       {"int16", 32767}, {"uint16", 65535},
      {"int", 2147483647}, {"uint", 4294967295u}, {"int32", 2147483647}, {"uint32", 4294967295u}};
  return max;
}

// Bytes of each scalar type PLY names, under both spellings.
const std::map<std::string, std::uint64_t, std::less<>>& scalar_sizes() {
  static const std::map<std::string, std::uint64_t, std::less<>> sizes{
      {"char", 1},   {"uchar", 1},  {"int8", 1},    {"uint8", 1},   {"short", 2},
      {"ushort", 2}, {"int16", 2},  {"uint16", 2},  {"int", 4},     {"uint", 4},
      {"int32", 4},  {"uint32", 4}, {"float", 4},   {"float32", 4}, {"double", 8},
      {"float64", 8}};
  return sizes;
}

// Where `line` (without its \n) holds a byte Assimp's line reader ends a line at (ParsingUtils'
// IsLineEnd: \r, NUL, form feed) anywhere but a \r last, or npos: the two readers agree on where
// its lines end only without one.
std::size_t mid_line_break(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line.find_first_of(std::string_view("\r\0\f", 3));
}

std::vector<std::string> words_of(std::string_view line) {
  std::vector<std::string> words;
  std::istringstream in{std::string(line)};
  for (std::string w; in >> w;) words.push_back(w);
  return words;
}

}  // namespace

PlyHeader parse_ply_header(std::string_view bytes, const std::string& file) {
  PlyHeader header;
  const std::string_view head = bytes.substr(0, kMaxPlyHeaderBytes);
  std::size_t pos = 0;
  int line_number = 0;
  bool format_seen = false;
  auto fail = [&](const std::string& why) {
    throw InputError(file + ": PLY header line " + std::to_string(line_number) + ": " + why);
  };
  while (true) {
    const std::size_t end = head.find('\n', pos);
    ++line_number;
    if (end == std::string_view::npos) {
      fail(bytes.size() > head.size()
               ? "no end_header within the first " + std::to_string(kMaxPlyHeaderBytes) + " bytes"
               : "the file ends before end_header");
    }
    const std::string_view line = head.substr(pos, end - pos);
    const std::vector<std::string> w = words_of(line);
    pos = end + 1;
    // Assimp's line reader also ends a line at \r, NUL and form feed, in comments too: a comment
    // holding "\relement face 1" would be a header line to it and none here.
    if (const std::size_t at = mid_line_break(line); at != std::string_view::npos) {
      fail(fmt::format("byte 0x{:02x} inside the line (Assimp's reader would end the line there; a line "
                       "ends with \\n or \\r\\n)",
                       static_cast<unsigned char>(line[at])));
    }
    if (line_number == 1) {
      if (w.size() != 1 || w[0] != "ply") fail("a PLY file starts with the line 'ply'");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header") {
      // The body starts after this line's newline, for Assimp as for the counts below: anything
      // else on it (a vertical tab, then data) would put the two readers in different places.
      if (line.substr(0, line.find_last_not_of(" \t\r") + 1) != "end_header") {
        fail("end_header must stand alone on its line");
      }
      break;
    }
    // Every keyword line left is printable ASCII words: Assimp splits and reads other bytes its
    // own way ('element vertex\xff..\xff 2', found by the fuzzer, was two vertices here and a
    // list of 2^32 values to it: it asked for 32 GiB), so the two readers would describe
    // different bodies.
    for (const char c : line) {
      const auto byte = static_cast<unsigned char>(c);
      if ((byte < 0x20 || byte > 0x7e) && c != '\t' && c != '\r') {
        fail(fmt::format("byte 0x{:02x} in a '{}' line (a PLY header's keyword lines are plain ASCII)", byte,
                         w[0].substr(0, 16)));
      }
    }
    if (w[0] == "format") {
      if (w.size() != 3) fail("expected 'format ascii|binary_little_endian|binary_big_endian 1.0'");
      if (w[1] == "ascii") header.format = PlyHeader::Format::ascii;
      else if (w[1] == "binary_little_endian") header.format = PlyHeader::Format::binary_little_endian;
      else if (w[1] == "binary_big_endian") header.format = PlyHeader::Format::binary_big_endian;
      else fail("unknown format '" + w[1] + "'");
      format_seen = true;
    } else if (w[0] == "element") {
      if (w.size() != 3) fail("expected 'element NAME COUNT'");
      // Assimp reads the count from where the name starts when the name starts with a digit
      // ("element 900000000vertex 3" is 900 million vertices to it, 3 to a reader of words), so
      // such a name would slip a count past the check below: names start with a letter or '_'.
      const unsigned char first = static_cast<unsigned char>(w[1][0]);
      if (!std::isalpha(first) && first != '_') {
        fail("element name '" + w[1] + "' does not start with a letter");
      }
      // Assimp sizes its faces (or vertices) by the first element of a name and then writes every
      // later one's into the same array: a second `element face 3` after `element face 1` wrote
      // two faces past its end (valgrind; the fuzzer's heap checks caught it some runs later).
      for (const PlyElement& earlier : header.elements) {
        if (earlier.name == w[1]) fail("a second element '" + w[1] + "' (each element is declared once)");
      }
      PlyElement e{w[1], 0, 0, {}};
      const auto [p, ec] = std::from_chars(w[2].data(), w[2].data() + w[2].size(), e.count);
      if (ec != std::errc() || p != w[2].data() + w[2].size()) {
        fail("element '" + w[1] + "' has count '" + w[2] + "', not a whole number");
      }
      header.elements.push_back(std::move(e));
    } else if (w[0] == "property") {
      if (header.elements.empty()) fail("a property before any element");
      const bool ascii = header.format == PlyHeader::Format::ascii;
      const auto& sizes = scalar_sizes();
      std::uint64_t bytes_needed = 0;
      if (w.size() == 5 && w[1] == "list") {
        const auto length = sizes.find(w[2]);
        if (length == sizes.end() || sizes.find(w[3]) == sizes.end()) fail("unknown type in a list property");
        const auto count_max = count_type_max().find(w[2]);
        if (count_max == count_type_max().end()) fail("a list's length type '" + w[2] + "' is not an integer type");
        bytes_needed = ascii ? 2 : length->second;  // an empty list is its length alone
        header.elements.back().properties.push_back({count_max->second, length->second, sizes.find(w[3])->second});
      } else if (w.size() == 3) {
        const auto scalar = sizes.find(w[1]);
        if (scalar == sizes.end()) fail("unknown type '" + w[1] + "'");
        bytes_needed = ascii ? 2 : scalar->second;
        header.elements.back().properties.push_back({0, 0, scalar->second});
      } else {
        fail("expected 'property TYPE NAME' or 'property list TYPE TYPE NAME'");
      }
      header.elements.back().min_bytes += bytes_needed;
    } else {
      // Not a PLY keyword: Assimp's reader does not skip such a line cleanly (a header with
      // 'pro[perty float x' made it allocate 32 GiB), and the counts above would no longer
      // describe the body it reads.
      fail("unknown keyword '" + w[0].substr(0, 64) +
           "' (a PLY header has only ply, format, comment, obj_info, element, property and end_header lines)");
    }
  }
  if (!format_seen) throw InputError(file + ": PLY header has no format line");
  header.header_bytes = pos;
  return header;
}

void check_ply_counts(const PlyHeader& header, std::uint64_t file_bytes, const std::string& file) {
  const std::uint64_t body = file_bytes > header.header_bytes ? file_bytes - header.header_bytes : 0;
  std::uint64_t needed = 0;
  for (const PlyElement& e : header.elements) {
    // An element of no properties takes no bytes, so no file size bounds its count, and every
    // reader (ours below, Assimp's) walks it one element at a time: 4.5e18 of them never end.
    if (e.properties.empty() && e.count > 0) {
      throw InputError(file + ": the PLY header declares " + std::to_string(e.count) + " '" + e.name +
                       "' elements of no properties (an element holds at least one value)");
    }
    // Checked arithmetic: a count near 2^64 must not wrap into something small.
    const bool too_many = e.min_bytes > 0 && e.count > (std::numeric_limits<std::uint64_t>::max() - needed) / e.min_bytes;
    if (!too_many) needed += e.count * e.min_bytes;
    if (too_many || needed > body) {
      throw InputError(file + ": the PLY header declares " + std::to_string(e.count) + " '" + e.name +
                       "' elements, which need more bytes than the " + std::to_string(body) +
                       " that follow the header (the file is truncated or its counts are false)");
    }
  }
}

void check_ply_ascii_body(const PlyHeader& header, std::string_view body, std::uint64_t body_offset,
                          const std::string& file) {
  for (std::size_t i = 0; i < body.size(); ++i) {
    const auto c = static_cast<unsigned char>(body[i]);
    // A \r is whitespace to the line checks below but a line end to Assimp: one inside a line
    // ("0 1 0\r-1") made a face of it whose list length -1 asked for 32 GiB (found by the fuzzer).
    if (c == '\r' && i + 1 < body.size() && body[i + 1] != '\n') {
      throw InputError(fmt::format("{}: byte {} of this ASCII PLY file is a carriage return inside a line "
                                   "(a line ends with \\n or \\r\\n)",
                                   file, body_offset + i));
    }
    if ((c >= 0x20 && c < 0x7f) || c == '\n' || c == '\r' || c == '\t') continue;
    throw InputError(fmt::format("{}: byte {} of this ASCII PLY file is {:#04x}, which no number or "
                                 "separator holds (is it binary?)",
                                 file, body_offset + i, c));
  }
  // Assimp reads an ASCII body a line per element, so each element must be one line holding
  // exactly the values its properties take: a token count alone would let a value on the next
  // line, read by Assimp as the next element's list length, slip by.
  std::size_t line_start = 0;
  for (const PlyElement& e : header.elements) {
    for (std::uint64_t k = 0; k < e.count; ++k) {
      const auto fail = [&](const std::string& why) {
        throw InputError(fmt::format("{}: PLY '{}' element {}: {}", file, e.name, k, why));
      };
      if (line_start >= body.size()) fail("the file ends before it");
      const std::size_t line_end = std::min(body.find('\n', line_start), body.size());
      const std::string_view line = body.substr(line_start, line_end - line_start);
      line_start = line_end + 1;
      std::size_t pos = 0;
      const auto number = [&](const char* what) {
        pos = line.find_first_not_of(" \t\r", pos);
        if (pos == std::string_view::npos) fail(std::string("its line ends before its ") + what);
        const std::size_t end = std::min(line.find_first_of(" \t\r", pos), line.size());
        const std::string_view word = line.substr(pos, end - pos);
        pos = end;
        double value = 0;
        const auto [stop, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
        if (ec != std::errc() || stop != word.data() + word.size()) {
          fail(fmt::format("'{}' is not a number", word.substr(0, 32)));
        }
        return value;
      };
      for (const PlyElement::Property& property : e.properties) {
        const std::uint64_t list_max = property.list_max;
        if (list_max == 0) {
          number("value");
          continue;
        }
        const double length = number("list length");
        if (!(length >= 0 && length <= static_cast<double>(list_max)) || length != std::floor(length)) {
          fail(fmt::format("a list length of {} (at most {} for its type)", length, list_max));
        }
        for (auto v = static_cast<std::uint64_t>(length); v > 0; --v) number("list values");
      }
      if (line.find_first_not_of(" \t\r", pos) != std::string_view::npos) {
        fail("its line holds more values than its properties take");
      }
    }
  }
}

void check_ply_binary_body(const PlyHeader& header, std::string_view body, const std::string& file) {
  const bool big_endian = header.format == PlyHeader::Format::binary_big_endian;
  std::uint64_t pos = 0;
  for (const PlyElement& e : header.elements) {
    for (std::uint64_t k = 0; k < e.count; ++k) {
      const auto fail = [&](const std::string& why) {
        throw InputError(fmt::format("{}: PLY '{}' element {}: {}", file, e.name, k, why));
      };
      for (const PlyElement::Property& property : e.properties) {
        if (property.list_max == 0) {
          if (property.value_bytes > body.size() - std::min<std::uint64_t>(pos, body.size())) {
            fail("the file ends before it");
          }
          pos += property.value_bytes;
          continue;
        }
        if (property.count_bytes > body.size() - std::min<std::uint64_t>(pos, body.size())) {
          fail("the file ends before its list length");
        }
        std::uint64_t raw = 0;
        for (std::uint64_t b = 0; b < property.count_bytes; ++b) {
          const std::uint64_t at = big_endian ? b : property.count_bytes - 1 - b;
          raw = (raw << 8) | static_cast<unsigned char>(body[pos + at]);
        }
        pos += property.count_bytes;
        // A signed type's limit is below its top bit: a length with the top bit set is negative
        // there, and over the limit either way.
        if (raw > property.list_max) {
          fail(fmt::format("a list length field of {:#x} (at most {} for its type)", raw, property.list_max));
        }
        if (raw > (body.size() - pos) / std::max<std::uint64_t>(property.value_bytes, 1)) {
          fail(fmt::format("a list of {} values runs past the end of the file", raw));
        }
        pos += raw * property.value_bytes;
      }
    }
  }
}

void check_ply_file(const ConfinedFile& file, const std::string& name) {
  std::string why;
  const int fd = open_confined(file, &why);
  if (fd < 0) throw InputError(name + ": " + why);
  std::string head(kMaxPlyHeaderBytes + 1, '\0');
  std::size_t got = 0;
  while (got < head.size()) {
    const ssize_t n = ::read(fd, head.data() + got, head.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int err = errno;
      ::close(fd);
      throw InputError(name + ": cannot read: " + std::strerror(err));
    }
    if (n == 0) break;
    got += static_cast<std::size_t>(n);
  }
  ::close(fd);
  head.resize(got);
  const PlyHeader header = parse_ply_header(head, name);
  check_ply_counts(header, file.size, name);
  // The whole file, as Assimp will read it whole too.
  std::string text;
  if (!read_confined(file, text, &why)) throw InputError(name + ": " + why);
  const std::string_view body = std::string_view(text).substr(std::min<std::size_t>(header.header_bytes, text.size()));
  if (header.format == PlyHeader::Format::ascii) {
    check_ply_ascii_body(header, body, header.header_bytes, name);
  } else {
    check_ply_binary_body(header, body, name);
  }
}

}  // namespace farm
