// The unit-file reader (server/scheduler/jobs/tile_results.cpp): the scheduler's finished batches on
// disk, read back at merge time, perhaps after a crash, a full disk or a disk that flipped bits.
// An input's first byte says how its rest becomes the file:
//   0  the rest is the whole file, as found on disk (header and all)
//   1  the rest is the payload under a correct header, so that the fuzzer reaches the protobuf
//      parse and the merge's decode behind the checksum, which it cannot forge
//   2  as 1, with the header's length one more than the payload (a file cut short)
// Properties: read() throws DamagedTileResult or returns a reply; a reply it returns writes and
// reads back to the same bytes, and its tile decodes or is an InputError (never a crash).
#include <cstdint>
#include <filesystem>
#include <string>

#include "proto/farm.pb.h"
#include "renderer/util/input_error.h"
#include "server/common/sha256.h"
#include "server/common/tile_codec.h"
#include "server/scheduler/jobs/tile_results.h"
#include "tests/fuzz/fuzz_support.h"

namespace {

// The header as tile_results.h documents it: "FARMTIL1", the payload's length (8 bytes, little
// endian), the payload's SHA-256 (64 hex digits). Written here from the documentation, not by
// the code under test, so a disagreement between the two shows up as a failed read of mode 1.
std::string framed(std::string_view payload, std::uint64_t length) {
  std::string file = "FARMTIL1";
  for (int i = 0; i < 8; ++i, length >>= 8) file.push_back(static_cast<char>(length & 0xff));
  return file + farm::sha256_hex(payload) + std::string(payload);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const farm::TileResults results(farm::fuzz::scratch_dir() / "tiles");
  // The job's folder, as TileResults::write makes it for a job's first result.
  static const bool job_folder = std::filesystem::create_directories(results.path_of("job", 0).parent_path());
  (void)job_folder;
  const std::string job_id = "job";
  const std::uint32_t part = 7;
  const std::string_view rest = farm::fuzz::as_bytes(data + 1, size - 1);
  std::string file;
  switch (data[0] % 3) {
    case 0: file = std::string(rest); break;
    case 1: file = framed(rest, rest.size()); break;
    default: file = framed(rest, rest.size() + 1); break;
  }
  farm::fuzz::write_scratch_file("tiles/" + job_id + "/" + std::to_string(part), file);

  farm::v1::RenderTileResponse reply;
  try {
    reply = results.read(job_id, part);
  } catch (const farm::DamagedTileResult&) {
    if (data[0] % 3 == 1) {
      // A correct header over bytes that do not parse is damage too; any other refusal of a
      // well-framed file means the reader and its documented format disagree.
      farm::v1::RenderTileResponse probe;
      if (probe.ParseFromArray(rest.data(), static_cast<int>(rest.size()))) {
        farm::fuzz::property_failed("a well-framed result that parses was refused");
      }
    }
    return 0;
  }
  if (data[0] % 3 == 2) farm::fuzz::property_failed("a result cut short was read as whole");

  results.write(job_id, part, reply);
  const farm::v1::RenderTileResponse again = results.read(job_id, part);
  if (again.SerializeAsString() != reply.SerializeAsString()) {
    farm::fuzz::property_failed("a result written and read back changed");
  }
  try {
    (void)farm::decode_tile(reply.tile());
  } catch (const farm::InputError&) {
  }
  return 0;
}
