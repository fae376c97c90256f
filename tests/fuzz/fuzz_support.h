#pragma once
// What the fuzz targets share: a scratch folder of the process's own (the loaders read files, and
// the services keep a data dir), and the bytes of one input as a file in it.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace farm::fuzz {

// A fresh folder under the system's temporary folder, made on first use and removed when the
// process exits normally. libFuzzer runs inputs one after another in one thread, so one folder
// a process is enough.
const std::filesystem::path& scratch_dir();

// Writes `bytes` to scratch_dir()/name, replacing what was there; returns the path.
std::filesystem::path write_scratch_file(const std::string& name, std::string_view bytes);

inline std::string_view as_bytes(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A property of the code under test does not hold: prints `what` and aborts, which libFuzzer (and
// the replay runner) report as a crash with this input.
[[noreturn]] void property_failed(const std::string& what);

}  // namespace farm::fuzz

// libFuzzer's entry point, defined by each <target>_fuzz.cpp.
extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
