#pragma once
// A small tmpfs mounted on a folder for one test: a disk that fills up, on purpose. Unmounted at
// scope exit whatever the test did (declare it after the TempDir holding the folder, so that it
// goes first). Mounting needs root (CAP_SYS_ADMIN): problem() says why there is no mount, for
// GTEST_SKIP.
#include <cstdint>
#include <filesystem>
#include <string>

namespace farm::test {

class TmpfsMount {
 public:
  // Creates `folder` and mounts a tmpfs of `bytes` on it.
  TmpfsMount(std::filesystem::path folder, std::uint64_t bytes);
  ~TmpfsMount();
  TmpfsMount(const TmpfsMount&) = delete;
  TmpfsMount& operator=(const TmpfsMount&) = delete;

  bool mounted() const { return mounted_; }
  const std::string& problem() const { return problem_; }  // empty when mounted
  const std::filesystem::path& folder() const { return folder_; }

  // Creates (or grows) `file` until the file system has at most `leave` bytes free; returns how
  // many bytes the file then holds.
  std::uint64_t fill(const std::filesystem::path& file, std::uint64_t leave) const;

 private:
  std::filesystem::path folder_;
  bool mounted_ = false;
  std::string problem_;
};

}  // namespace farm::test
