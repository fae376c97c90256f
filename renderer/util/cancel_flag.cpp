#include "renderer/util/cancel_flag.h"

namespace farm {

CancelFlag::Clock::time_point CancelFlag::steady_deadline(std::chrono::system_clock::time_point deadline) {
  using System = std::chrono::system_clock;
  if (deadline == System::time_point::max()) return Clock::time_point::max();
  const System::time_point system_now = System::now();
  const Clock::time_point now = Clock::now();
  if (deadline <= system_now) return now;
  const auto left = std::chrono::duration_cast<Clock::duration>(deadline - system_now);
  // A deadline centuries away (gRPC's "infinite" is near the clock's maximum) is none at all.
  if (left >= Clock::time_point::max() - now) return Clock::time_point::max();
  return now + left;
}

const CancelFlag& CancelFlag::never() {
  static const CancelFlag flag;
  return flag;
}

}  // namespace farm
