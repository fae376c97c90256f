#pragma once
// A write refused for want of space: ENOSPC (no space left on the device), EDQUOT (over quota)
// or SQLite's SQLITE_FULL. Every write of the scheduler and the worker reports it as this one
// type, naming the folder, so that a full disk pauses work and is answered RESOURCE_EXHAUSTED
// ("disk full in <folder>: ...") instead of failing jobs, looping or ending a thread.
#include <grpcpp/support/status.h>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

namespace farm {

class DiskFull : public std::runtime_error {
 public:
  // `folder`: where the write went; `refused`: what was refused, naming the file and the cause;
  // `needed`: the bytes it wanted (0: unknown). what() says "disk full in <folder>" and how much
  // is free there.
  DiskFull(std::filesystem::path folder, const std::string& refused, std::uint64_t needed = 0);
  const std::filesystem::path& folder() const { return folder_; }
  std::uint64_t needed() const { return needed_; }

 private:
  std::filesystem::path folder_;
  std::uint64_t needed_;
};

// ENOSPC or EDQUOT.
bool is_disk_full_errno(int error);

// The failure of a write of `file` with `error` (an errno): DiskFull (its folder: the file's)
// when the disk is full, else std::system_error naming the file.
[[noreturn]] void throw_write_error(int error, const std::filesystem::path& file, std::uint64_t needed = 0);

// Writes all of `bytes` to `fd` (the open `file`), retrying interrupted writes; throw_write_error
// on failure.
void write_all(int fd, std::string_view bytes, const std::filesystem::path& file);

// Creates (or truncates) `file` and writes all of `bytes` to it, checking the close too (where some
// file systems first report a lack of space); throw_write_error on failure, the file then being
// left partial for the caller to remove.
void write_file(const std::filesystem::path& file, std::string_view bytes);

// Inside a catch block: the exception being handled again, as DiskFull naming `folder` when it is
// a std::system_error (std::filesystem::filesystem_error too) for a full disk, else unchanged.
[[noreturn]] void rethrow_as_disk_full(const std::filesystem::path& folder);

// Bytes an unprivileged writer may still use in the file system holding `folder` (statvfs);
// nullopt when it cannot be asked (the folder is gone).
std::optional<std::uint64_t> free_bytes(const std::filesystem::path& folder);

// "12.3 MiB", for messages about space.
std::string describe_bytes(std::uint64_t bytes);

// Whether a call's status is a peer's DiskFull (RESOURCE_EXHAUSTED, "disk full in ...").
bool is_disk_full(const grpc::Status& status);

}  // namespace farm
