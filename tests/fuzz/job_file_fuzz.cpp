// The job file parser (renderer/job/job.cpp over json_reader): an input is a job file's text,
// parsed as if it lay in the repository's jobs/ folder, so that the example jobs' model paths
// (assets/cornell_box.obj, ...) resolve and the parser reaches the keys after them. Nothing is
// written there: parse_job only checks that model files exist inside the asset root.
#include <string>

#include "renderer/job/job.h"
#include "renderer/util/input_error.h"
#include "tests/fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(farm::fuzz::as_bytes(data, size));
  try {
    const farm::Job job = farm::parse_job(text, std::string(FARM_SOURCE_DIR) + "/jobs/fuzz.json");
    // A job that parses is one the engines can be given (job.h: validated strictly).
    if (job.render.width <= 0 || job.render.height <= 0 || job.render.spp <= 0) {
      farm::fuzz::property_failed("a parsed job with an empty image or no samples");
    }
  } catch (const farm::InputError&) {
  }
  return 0;
}
