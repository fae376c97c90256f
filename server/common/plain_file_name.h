#pragma once
// A name from another process (a scheduler's suggested file name, a submitter's job or output
// name) made safe to use as one file name inside a folder chosen here: letters, digits, '.', '-'
// and '_' stay, anything else (a '/', a quote, a line break) becomes '_', as do leading dots (no
// hidden files), and a name of dots only ('.', '..') or none at all becomes `fallback`. Never a
// path, never outside its folder; at most 255 bytes.
#include <string>
#include <string_view>

namespace farm {

std::string plain_file_name(std::string_view name, std::string_view fallback = "result");

}  // namespace farm
