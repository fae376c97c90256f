#pragma once
// A fresh folder under the system temp dir for one test, removed with its contents at scope exit.
// Named after the test and the process, so tests running in parallel never share one.
#include <filesystem>
#include <string>

namespace farm::test {

class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::filesystem::path& name) const { return path_ / name; }

  // Writes `contents` to `name` (folders created as needed) and returns its path.
  std::filesystem::path write(const std::filesystem::path& name, const std::string& contents) const;

 private:
  std::filesystem::path path_;
};

}  // namespace farm::test
