#pragma once
// The scene hash of a job spec: what workers cache prepared scenes by and what the scheduler
// records with a job. Defined in proto/farm.proto (message JobSpec); this is its one
// implementation.
#include <string>

#include "proto/farm.pb.h"

namespace farm {

// 64 lowercase hex digits. Independent of the order of spec.assets and of spec.file_name.
std::string scene_hash(const v1::JobSpec& spec);

}  // namespace farm
