#pragma once
// `farm info FILE`: what a model file or a job file contains, without rendering.
#include <filesystem>

#include "renderer/scene/job.h"

namespace farm {

void run_info_command(const std::filesystem::path& file, const JobLoadOptions& load);

}  // namespace farm
