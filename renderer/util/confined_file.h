#pragma once
// The one gate every file named by input passes before anything reads it: a job's models, and what
// a model names in turn (an OBJ's material libraries and the maps they name, a glTF's buffers and
// images, a COLLADA file's images). The client that gathers a job's files, the scheduler and the
// worker that load it from their asset stores, and the loaders of `farm render` all call
// confine_file, so a file one of them refuses is refused by all, with the same words.
//
// A reference is refused when
//   - it is absolute (unless the form allows it: a job's own model paths, written by a person on
//     their machine; a model travels to other machines as it is, where an absolute path means
//     another file),
//   - it leads out of the root: lexically (`..` past the root) or through a symbolic link (a link
//     inside the root that points inside is fine),
//   - what it names is not a regular file: a FIFO (opening one would wait for a writer), a device,
//     a socket, a directory.
// Containment is checked before existence, so probing outside the root reveals nothing.
//
// open_confined (and read_confined over it) opens an allowed file without following a link and
// without blocking, then checks that what it opened is still the regular file confine_file saw.
#include <sys/types.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace farm {

enum class ReferenceForm {
  relative,              // a model's references: relative to the model's folder
  relative_or_absolute,  // a job's model paths (still confined to the root)
};

enum class Confinement {
  allowed,       // a regular file inside the root
  missing,       // inside the root, but nothing there (loaders decide what a missing file means)
  absolute,      // an absolute reference where only relative ones are allowed
  outside,       // leads out of the root (`..`, an absolute path elsewhere, a symbolic link)
  not_regular,   // a directory, FIFO, device or socket
  inaccessible,  // cannot be looked at (permissions, a NUL in the name, ...)
};

struct ConfinedFile {
  Confinement verdict = Confinement::missing;
  // The file under the name its referrer uses, lexically normal (the referrer's folder joined with
  // a relative reference): where a farm lays it out. Set unless refused as absolute.
  std::filesystem::path named;
  // Where it really is (no `..`, no symbolic link): what is opened. Set unless refused.
  std::filesystem::path resolved;
  std::uintmax_t size = 0;  // bytes, when allowed
  // Why it is not allowed: `reason` ("'<reference>' lies outside the asset root (/r)"), and
  // `message`, the same after "<referrer>: ". Both empty when allowed (and for an empty reference).
  std::string reason;
  std::string message;
  // Only for open_confined: the file that was checked.
  dev_t device = 0;
  ino_t inode = 0;

  bool allowed() const { return verdict == Confinement::allowed; }
  bool refused() const { return verdict != Confinement::allowed && verdict != Confinement::missing; }
};

// `reference`, as `referrer` writes it, resolved and confined to `resolved_root` (already
// canonical, e.g. weakly_canonical). The referrer's folder must be named lexically under the root
// as farms name it (a model's canonical path, or a name confine_file returned); a relative
// reference is taken from that folder. Never throws for a bad reference: the verdict says.
ConfinedFile confine_file(const std::filesystem::path& resolved_root, const std::filesystem::path& referrer,
                          const std::string& reference, ReferenceForm form = ReferenceForm::relative);

// How many references confine_file has resolved in this process: each costs a syscall per folder
// of the name, so callers that meet one name many times resolve it once (a test counts it).
std::uint64_t confine_file_calls();

// Opens an allowed file read-only (close-on-exec). -1 with `why` set when it is no longer the
// regular file confine_file saw (replaced by a link, a FIFO, another file) or cannot be opened.
int open_confined(const ConfinedFile& file, std::string* why);

// The whole of an allowed file, read through open_confined. False, with `why` set, when it cannot
// be opened or read.
bool read_confined(const ConfinedFile& file, std::string& bytes, std::string* why);
bool read_confined(const ConfinedFile& file, std::vector<unsigned char>& bytes, std::string* why);

}  // namespace farm
