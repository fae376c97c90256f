#pragma once
// A job file turned into what a scheduler is sent (farm.v1.JobSpec): the job's text and every
// file it reads, named by content. Used by `farm submit` and by `farm render`'s embedded farm,
// so both send the same thing.
//
// Asset paths in the spec are relative to the asset root (the job file's folder unless
// --asset-root says otherwise). When the job's own folder is that root and nothing is
// overridden, the job text goes as it is, byte for byte; otherwise the document parsed from it
// (once: the same one the Job was read from) goes with its model paths rewritten relative to the
// root and the overrides written into it, its keys sorted.
#include <cstddef>
#include <filesystem>
#include <map>
#include <string>

#include "proto/farm.pb.h"
#include "renderer/job/job.h"
#include "server/client/render_overrides.h"

namespace farm {

struct JobSubmission {
  v1::JobSpec spec;
  Job job;                                          // the job as parsed here, overrides applied
  std::map<std::string, std::filesystem::path> files;  // sha256 -> a local file with those bytes
  // What building it read, so the cost stays visible: each model and material library is scanned
  // for the files it names once, and each file hashed once, however many objects name it.
  std::size_t files_scanned = 0;
  std::size_t files_hashed = 0;
};

// Throws InputError (naming the file and the place) for a bad job or a model with a reference
// that confine_file refuses (renderer/util/confined_file.h): nothing refused is read or sent.
// Every AssetRef's size is the count of the bytes its hash was computed over.
JobSubmission make_job_submission(const std::filesystem::path& job_file, const JobLoadOptions& load,
                                  const RenderOverrides& overrides);

}  // namespace farm
