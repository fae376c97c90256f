// PLY headers: element counts are held against the bytes after the header before Assimp reads a
// PLY file (renderer/loaders/ply_header.h), so a tiny file declaring millions of faces is refused
// at once; honest ASCII and binary files still load.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <string>

#include "renderer/loaders/ply_header.h"
#include "renderer/scene/model.h"
#include "renderer/util/input_error.h"
#include "tests/support/temp_dir.h"

namespace farm {
namespace {

using test::TempDir;

std::string ascii_triangle(const std::string& face_count) {
  return "ply\nformat ascii 1.0\ncomment one triangle\nelement vertex 3\nproperty float x\n"
         "property float y\nproperty float z\nelement face " + face_count +
         "\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
}

// One triangle in binary_little_endian: 3 vertices of 3 floats, one face (uchar 3, 3 ints).
std::string binary_triangle() {
  std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                  "property float y\nproperty float z\nelement face 1\n"
                  "property list uchar int vertex_indices\nend_header\n";
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  s.append(reinterpret_cast<const char*>(v), sizeof v);
  s.push_back(3);
  const std::int32_t f[3] = {0, 1, 2};
  s.append(reinterpret_cast<const char*>(f), sizeof f);
  return s;
}

std::string load_error(const std::filesystem::path& file) {
  try {
    load_model(file);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PlyHeader, HonestAsciiAndBinaryTrianglesLoad) {
  TempDir dir;
  for (const auto& [name, text] : {std::pair{"ascii.ply", ascii_triangle("1")},
                                   std::pair{"binary.ply", binary_triangle()}}) {
    const Model m = load_model(dir.write(name, text));
    ASSERT_EQ(m.meshes.size(), 1u) << name;
    EXPECT_EQ(m.meshes[0].triangles.size(), 1u) << name;
    EXPECT_EQ(m.meshes[0].positions.size(), 3u) << name;
  }
}

TEST(PlyHeader, TenMillionFacesDeclaredInATinyFileAreRefusedBeforeLoading) {
  TempDir dir;
  const std::string text = ascii_triangle("10000000");
  ASSERT_LT(text.size(), 400u);  // the bomb: a few hundred bytes
  const std::string error = load_error(dir.write("bomb.ply", text));
  EXPECT_NE(error.find("bomb.ply"), std::string::npos) << error;
  EXPECT_NE(error.find("declares 10000000 'face' elements"), std::string::npos) << error;
}

TEST(PlyHeader, BinaryCountsAreHeldToTheExactBytes) {
  const std::string whole = binary_triangle();
  const PlyHeader header = parse_ply_header(whole, "t.ply");
  EXPECT_EQ(header.format, PlyHeader::Format::binary_little_endian);
  ASSERT_EQ(header.elements.size(), 2u);
  EXPECT_EQ(header.elements[0].min_bytes, 12u);  // three floats
  EXPECT_EQ(header.elements[1].min_bytes, 1u);   // an empty list: its uchar length
  EXPECT_NO_THROW(check_ply_counts(header, whole.size(), "t.ply"));
  // The face's list length needs one byte more than the vertices leave.
  EXPECT_THROW(check_ply_counts(header, header.header_bytes + 36, "t.ply"), InputError);
  EXPECT_NO_THROW(check_ply_counts(header, header.header_bytes + 37, "t.ply"));
}

TEST(PlyHeader, CountsThatWouldOverflowAreRefused) {
  const std::string text = ascii_triangle("18446744073709551615");
  EXPECT_THROW(check_ply_counts(parse_ply_header(text, "t.ply"), text.size(), "t.ply"), InputError);
  EXPECT_THROW(parse_ply_header(ascii_triangle("18446744073709551616"), "t.ply"), InputError);
  EXPECT_THROW(parse_ply_header(ascii_triangle("-1"), "t.ply"), InputError);
}

// Found by the fuzzer: an element of no properties takes no bytes, so its count escaped the size
// check and the body check walked 4.5e18 of them; an empty one of count 0 is harmless.
TEST(PlyHeader, AnElementOfNoPropertiesIsRefusedUnlessItIsEmpty) {
  TempDir dir;
  const std::string head = "ply\nformat binary_little_endian 1.0\nelement vertex 4569078768296817094\n";
  const std::string error = load_error(dir.write("empty.ply", head + "end_header\n\0\0"));
  EXPECT_NE(error.find("empty.ply"), std::string::npos) << error;
  EXPECT_NE(error.find("4569078768296817094 'vertex' elements of no properties"), std::string::npos) << error;
  std::string triangle = binary_triangle();
  triangle.insert(triangle.find("element vertex"), "element note 0\n");
  EXPECT_EQ(load_model(dir.write("noted.ply", triangle)).meshes.at(0).triangles.size(), 1u);
}

// Found by the fuzzer: Assimp's ASCII reader looped for ever on a NUL among the numbers, and on
// data that shared the end_header line, and allocated for whatever list length a face gave.
TEST(PlyHeader, AnAsciiBodyThatDoesNotFitItsHeaderIsRefusedNamingThePlace) {
  TempDir dir;
  std::string text = ascii_triangle("1");
  const std::size_t at = text.find("\n1 0 0") + 2;
  text[at] = '\0';
  const auto nul = dir.write("nul.ply", text);
  EXPECT_NE(load_error(nul).find("byte " + std::to_string(at) + " of this ASCII PLY file is 0x00"), std::string::npos)
      << load_error(nul);
  std::string shared = ascii_triangle("1");
  shared.replace(shared.find("end_header\n"), 11, "end_header\v");
  const auto joined = dir.write("joined.ply", shared);
  EXPECT_NE(load_error(joined).find("end_header must stand alone on its line"), std::string::npos) << load_error(joined);
  // A face whose list length its uchar type cannot hold (Assimp allocated for all of it), and one
  // whose values run out.
  std::string long_list = ascii_triangle("1");
  long_list.replace(long_list.find("3 0 1 2"), 7, "1111111111111113 0 1 2");
  const auto listed = dir.write("long.ply", long_list);
  EXPECT_NE(load_error(listed).find("PLY 'face' element 0: a list length of 1111111111111113 (at most 255"),
            std::string::npos) << load_error(listed);
  std::string short_list = ascii_triangle("1");
  short_list.replace(short_list.find("3 0 1 2"), 7, "9 0 1 2");
  const auto cut = dir.write("cut.ply", short_list);
  EXPECT_NE(load_error(cut).find("PLY 'face' element 0: its line ends before its list values"), std::string::npos)
      << load_error(cut);
  std::string word = ascii_triangle("1");
  word.replace(word.find("1 0 0"), 1, "x");
  const auto worded = dir.write("word.ply", word);
  EXPECT_NE(load_error(worded).find("PLY 'vertex' element 1: 'x' is not a number"), std::string::npos)
      << load_error(worded);
  // One vertex too many for its header: Assimp reads the extra line as the face, and then the
  // face's line as a list length of 3 with its values missing; here, the face line is refused.
  std::string shifted = ascii_triangle("1");
  shifted.replace(shifted.find("element vertex 3"), 16, "element vertex 2");
  const auto extra = dir.write("extra.ply", shifted);
  EXPECT_NE(load_error(extra).find("PLY 'face' element 0: its line holds more values than its properties take"),
            std::string::npos) << load_error(extra);
  const auto honest = dir.write("honest.ply", ascii_triangle("1"));
  EXPECT_EQ(load_error(honest), "");
}

// Found by the fuzzer: a carriage return inside a body line is whitespace to the line checks and
// a line end to Assimp, which read "0 1 0\r-1" as a vertex and then a face whose list length of
// -1 it allocated 32 GiB for (std::bad_alloc here; ASan's out-of-memory under the fuzzer). CRLF
// line ends still load.
TEST(PlyHeader, ACarriageReturnInsideAnAsciiLineIsRefusedAndCrlfLineEndsLoad) {
  TempDir dir;
  const std::string header =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
      "property float w\nelement face 1\nproperty list int int vertex_indices\nend_header\n";
  const std::string split = header + "0 0 0 0\n1 0 0 0\n0 1 0\r-1\n3 0 1 2\n";
  const std::size_t at = split.find('\r');
  const auto file = dir.write("split.ply", split);
  EXPECT_NE(load_error(file).find("byte " + std::to_string(at) + " of this ASCII PLY file is a carriage return inside a line"),
            std::string::npos) << load_error(file);
  std::string crlf;
  for (const char c : ascii_triangle("1")) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  const Model m = load_model(dir.write("crlf.ply", crlf));
  ASSERT_EQ(m.meshes.size(), 1u);
  EXPECT_EQ(m.meshes[0].triangles.size(), 1u);
}

// Found by the fuzzer: a binary face whose char length field is -1 (0xff), which Assimp takes
// for 4 billion indices and allocates 32 GiB for; and a length whose values run past the file.
TEST(PlyHeader, ABinaryListLengthOutsideItsTypeOrTheFileIsRefused) {
  TempDir dir;
  std::string negative = binary_triangle();
  negative.replace(negative.find("list uchar int"), 14, "list char int");
  negative[negative.size() - 13] = static_cast<char>(0xff);
  EXPECT_NE(load_error(dir.write("negative.ply", negative)).find("PLY 'face' element 0: a list length field of 0xff (at most 127"),
            std::string::npos) << load_error(dir.write("negative.ply", negative));
  std::string past = binary_triangle();
  past[past.size() - 13] = 4;  // four ints where three are
  EXPECT_NE(load_error(dir.write("past.ply", past)).find("a list of 4 values runs past the end of the file"),
            std::string::npos) << load_error(dir.write("past.ply", past));
  EXPECT_EQ(load_error(dir.write("honest.ply", binary_triangle())), "");
}

TEST(PlyHeader, MalformedHeadersNameTheFileAndTheLine) {
  auto error_of = [](const std::string& text) {
    try {
      parse_ply_header(text, "m.ply");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of("plx\n").find("m.ply: PLY header line 1"), std::string::npos);
  EXPECT_NE(error_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty quad x\nend_header\n")
                .find("line 4: unknown type 'quad'"), std::string::npos);
  // A misspelt keyword (found by the fuzzer: Assimp then allocated 32 GiB for a 243-byte file).
  EXPECT_NE(error_of("ply\nformat ascii 1.0\nelement vertex 3\npro[perty float x\nend_header\n")
                .find("line 4: unknown keyword 'pro[perty'"), std::string::npos);
  // Bytes outside ASCII in a keyword line (found by the fuzzer: Assimp read this element's line
  // its own way and asked for 32 GiB); a comment may hold any text.
  EXPECT_NE(error_of(std::string("ply\nformat binary_little_endian 1.0\nelement vertex\xff\xff\xc3\xed 2\n"
                                 "property float x\nend_header\n"))
                .find("line 3: byte 0xff in a 'element' line"), std::string::npos);
  EXPECT_EQ(error_of("ply\nformat ascii 1.0\ncomment caf\xc3\xa9\nelement vertex 0\nproperty float x\nend_header\n"), "");
  // A \r, NUL or form feed inside a line, a comment's too, ends the line for Assimp's reader,
  // which would then read a header line this one never saw; a \r before the \n is a CRLF end.
  for (const char c : {'\r', '\0', '\f'}) {
    std::string hidden = "ply\nformat ascii 1.0\ncomment a_element face 9\nelement vertex 0\nproperty float x\nend_header\n";
    hidden[hidden.find('_')] = c;
    EXPECT_NE(error_of(hidden).find(fmt::format("line 3: byte 0x{:02x} inside the line", static_cast<int>(c))),
              std::string::npos) << error_of(hidden);
  }
  EXPECT_EQ(error_of("ply\r\nformat ascii 1.0\r\ncomment crlf\r\nelement vertex 0\r\nproperty float x\r\nend_header\r\n"), "");
  EXPECT_NE(error_of("ply\nformat ascii 1.0\nelement vertex 3\n").find("ends before end_header"),
            std::string::npos);
  EXPECT_NE(error_of("ply\nelement vertex 3\nend_header\n").find("no format line"), std::string::npos);
  // An element declared twice: Assimp sized its faces by the first and wrote the second's past
  // them (valgrind: invalid writes in libassimp; the fuzzer's ASan caught the heap corrupted).
  EXPECT_NE(error_of("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nelement face 1\n"
                     "property list uchar int vertex_indices\nelement face 3\n"
                     "property list uchar int vertex_indices\nend_header\n")
                .find("line 7: a second element 'face'"), std::string::npos);
  EXPECT_NE(error_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nelement vertex 5\n"
                     "property float x\nend_header\n")
                .find("line 5: a second element 'vertex'"), std::string::npos);
  // A header that never ends is read no further than its bound.
  EXPECT_NE(error_of("ply\n" + std::string(kMaxPlyHeaderBytes, 'c') + "\n").find("no end_header within"),
            std::string::npos);
}

}  // namespace
}  // namespace farm
