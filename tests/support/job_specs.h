#pragma once
// Job specs (farm.v1.JobSpec) for service tests, made from the project's own example assets.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "proto/farm.pb.h"

namespace farm::test {

std::string read_file(const std::filesystem::path& file);

// jobs/cornell.json with its render block replaced: `engine` at width x height, `spp` samples,
// and the variance AOV added to the job's depth, normal and albedo.
std::string cornell_job_json(const std::string& engine, int width, int height, int spp);

// A spec of `json` and the files it reads, each given as (path as the job names it, file on disk).
v1::JobSpec make_job_spec(const std::string& json,
                          const std::vector<std::pair<std::string, std::filesystem::path>>& files,
                          const std::string& file_name = "job.json");

// The Cornell box job: jobs/assets/cornell_box.obj and its .mtl, named as jobs/cornell.json does.
v1::JobSpec cornell_job_spec(const std::string& engine, int width, int height, int spp);
std::vector<std::pair<std::string, std::filesystem::path>> cornell_assets();

}  // namespace farm::test
