#pragma once
// The folder a student's report files go in (feedback/<folder>/, gradescope/<folder>/).
//
// The runner takes student ids from submission folder names, so an id is one path component
// already; but ids are hostile input, and a report writer must never write outside its output
// folder nor let two students share a folder (one student would be handed another's feedback).
// So the mapping is injective and always yields one safe component:
//   - every byte that a component cannot hold or that could climb out ('/', '\\', NUL, control
//     characters) and the escape character '%' itself become %XX (two upper-case hex digits);
//   - "." and ".." (after that) become "%2E" and "%2E%2E";
//   - every other byte (UTF-8 included) is kept, so an ordinary id names its folder as it is.
// An empty id has no folder: std::invalid_argument.
#include <string>
#include <string_view>

namespace farm {

std::string student_folder_name(std::string_view student);

// The folder name as one relative URL path segment (for links between report pages):
// every byte but A-Z a-z 0-9 - . _ ~ percent-encoded.
std::string url_path_segment(std::string_view folder);

}  // namespace farm
