#pragma once
// A sandbox's writable folders, lent to the user its program runs as (sandbox.h): everything in
// them chowned to that user for the run, so that it may write there and nowhere else, and given
// back when the loan ends: everything in them then belongs to the owner each folder had before.
// Symlinks are changed themselves, never followed.
#include <sys/types.h>

#include <filesystem>
#include <vector>

namespace farm {

class FolderLoan {
 public:
  // Throws std::runtime_error naming the folder that could not be lent (what was lent is given
  // back first).
  FolderLoan(const std::vector<std::filesystem::path>& folders, uid_t uid, gid_t gid);
  ~FolderLoan();
  FolderLoan(const FolderLoan&) = delete;
  FolderLoan& operator=(const FolderLoan&) = delete;

 private:
  void give_back();

  struct Owner {
    std::filesystem::path folder;
    uid_t uid;
    gid_t gid;
  };
  std::vector<Owner> owners_;
};

}  // namespace farm
