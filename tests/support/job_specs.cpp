#include "tests/support/job_specs.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>

#include "server/common/sha256.h"

namespace farm::test {

namespace fs = std::filesystem;

std::string read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("cannot read " + file.string());
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string cornell_job_json(const std::string& engine, int width, int height, int spp) {
  nlohmann::json job = nlohmann::json::parse(read_file(fs::path(FARM_SOURCE_DIR) / "jobs/cornell.json"));
  job["render"] = {{"engine", engine}, {"width", width}, {"height", height}, {"spp", spp}};
  // Every AOV a farm merges: variance too (zeros but for the path engine).
  job["output"]["aovs"].push_back("variance");
  return job.dump(2);
}

v1::JobSpec make_job_spec(const std::string& json,
                          const std::vector<std::pair<std::string, fs::path>>& files,
                          const std::string& file_name) {
  v1::JobSpec spec;
  spec.set_job_json(json);
  spec.set_file_name(file_name);
  for (const auto& [path, file] : files) {
    const std::string bytes = read_file(file);
    v1::AssetRef* ref = spec.add_assets();
    ref->set_path(path);
    ref->set_sha256(sha256_hex(bytes));
    ref->set_size(bytes.size());
  }
  return spec;
}

std::vector<std::pair<std::string, fs::path>> cornell_assets() {
  const fs::path jobs = fs::path(FARM_SOURCE_DIR) / "jobs";
  return {{"assets/cornell_box.obj", jobs / "assets/cornell_box.obj"},
          {"assets/cornell_box.mtl", jobs / "assets/cornell_box.mtl"}};
}

v1::JobSpec cornell_job_spec(const std::string& engine, int width, int height, int spp) {
  return make_job_spec(cornell_job_json(engine, width, height, spp), cornell_assets(),
                       "cornell.json");
}

}  // namespace farm::test
