#pragma once
// A one-line progress bar on stderr, drawn only when stderr is a terminal (logs and CI output
// stay clean). Redraws at most when the shown percentage changes.
#include <chrono>
#include <cstddef>
#include <string>

namespace farm {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled);
  ~ProgressBar();  // finishes the line if anything was drawn

  // `note` follows the counts (a job's "frame 3/48"); a new note redraws the line.
  void update(std::size_t done, std::size_t total, const std::string& note = {});
  // Erases the bar's line, if drawn, so that a line of output can take its place; the next
  // update draws the bar again below it.
  void clear();

  static bool stderr_is_terminal();

 private:
  std::string label_;
  bool enabled_;
  bool drawn_ = false;
  int last_permille_ = -1;
  std::string last_note_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace farm
