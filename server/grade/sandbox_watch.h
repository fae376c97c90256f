#pragma once
// What the grader measures of a running sandbox from outside (sandbox.cpp): how many processes
// its user has, and how much its writable folders hold.
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <vector>

namespace farm {

// The processes (not threads) of `uid` on this machine, from the owners of /proc's entries.
// A process that is not dumpable shows as root's there and is not counted: this only tells when
// a program sits at its process limit, which the kernel enforces exactly regardless.
int count_processes_of(uid_t uid);

// The bytes the files and folders under `roots` take, each file at the larger of its size and
// its allocated blocks; symlinks are not followed. What cannot be read is skipped.
std::uint64_t disk_usage(const std::vector<std::filesystem::path>& roots);

}  // namespace farm
