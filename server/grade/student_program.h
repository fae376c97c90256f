#pragma once
// A `run` task's program: the submission copied into a private work folder (links and anything
// but plain files and folders left out), built there if the rubric says how, then run on the
// task's job in the sandbox (sandbox.h) to write its image.
#include <filesystem>
#include <optional>
#include <string>

#include "server/grade/grade_rubric.h"

namespace farm {

struct ProgramRun {
  std::optional<std::filesystem::path> image_file;  // what it wrote at {output}, on the host
  std::string output;  // the build's and the program's stdout and stderr, bounded
  std::string reason;  // why there is no image: "the build failed: exited with code 2", ...
};

// `job_folder` (the job and its assets) is mounted read-only at /job; the copy of `submission`
// is the writable /work. Everything is left under `work_dir`, which is emptied first.
ProgramRun run_student_program(const RunSpec& spec, const std::filesystem::path& submission,
                               const std::filesystem::path& job_folder, const std::filesystem::path& job_file,
                               const std::filesystem::path& work_dir);

}  // namespace farm
