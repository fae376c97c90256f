#include "server/grade/student_folder.h"

#include <fmt/format.h>

#include <stdexcept>

namespace farm {
namespace {

std::string percent(unsigned char c) { return fmt::format("%{:02X}", static_cast<unsigned>(c)); }

}  // namespace

std::string student_folder_name(std::string_view student) {
  if (student.empty()) throw std::invalid_argument("a student id is empty: it names no folder");
  std::string folder;
  folder.reserve(student.size());
  for (char ch : student) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '/' || c == '\\' || c == '%' || c < 0x20 || c == 0x7f) {
      folder += percent(c);
    } else {
      folder += ch;
    }
  }
  if (folder == ".") return "%2E";
  if (folder == "..") return "%2E%2E";
  return folder;
}

std::string url_path_segment(std::string_view folder) {
  std::string url;
  for (char ch : folder) {
    const auto c = static_cast<unsigned char>(ch);
    const bool unreserved = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '-' ||
                            c == '.' || c == '_' || c == '~';
    url += unreserved ? std::string(1, ch) : percent(c);
  }
  return url;
}

}  // namespace farm
