#include "server/cli/progress_bar.h"

#include <fmt/format.h>
#include <unistd.h>

#include <cstdio>

namespace farm {

ProgressBar::ProgressBar(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled), start_(std::chrono::steady_clock::now()) {}

ProgressBar::~ProgressBar() {
  if (drawn_) std::fputc('\n', stderr);
}

bool ProgressBar::stderr_is_terminal() { return isatty(STDERR_FILENO) == 1; }

void ProgressBar::update(std::size_t done, std::size_t total, const std::string& note) {
  if (!enabled_ || total == 0) return;
  const int permille = static_cast<int>(done * 1000 / total);
  if (permille == last_permille_ && note == last_note_) return;
  last_permille_ = permille;
  last_note_ = note;
  constexpr int kWidth = 30;
  const int filled = permille * kWidth / 1000;
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  fmt::print(stderr, "\r{} [{}{}] {:5.1f}%  {}/{}{}  {:.1f}s", label_, std::string(filled, '#'),
             std::string(kWidth - filled, ' '), permille / 10.0, done, total, note.empty() ? "" : "  " + note,
             seconds);
  std::fflush(stderr);
  drawn_ = true;
}

void ProgressBar::clear() {
  if (!drawn_) return;
  fmt::print(stderr, "\r\x1b[K");
  std::fflush(stderr);
  drawn_ = false;
  last_permille_ = -1;
}

}  // namespace farm
