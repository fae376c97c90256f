#pragma once
// CSV as RFC 4180 writes it (what spreadsheets and Python's csv module read back): a field with a
// comma, a double quote, CR or LF is enclosed in double quotes, its quotes doubled; records end
// in CRLF. Student ids are folder names, so any of these may occur in them.
#include <string>
#include <string_view>
#include <vector>

namespace farm {

std::string csv_field(std::string_view field);

// The fields joined by commas, each through csv_field, ended by CRLF.
std::string csv_record(const std::vector<std::string>& fields);

}  // namespace farm
