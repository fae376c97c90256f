#pragma once
// Readable values of the renderer's enums in failure messages and parameterised test names
// (gtest finds PrintTo by argument-dependent lookup, so these live in namespace farm).
#include <ostream>

#include "renderer/job/render_settings.h"
#include "renderer/util/cancel_flag.h"

namespace farm {

inline void PrintTo(StopReason reason, std::ostream* os) {
  constexpr const char* kNames[] = {"None", "Cancelled", "Deadline"};
  *os << "StopReason::" << kNames[static_cast<int>(reason)];
}
inline void PrintTo(EngineKind engine, std::ostream* os) { *os << to_string(engine); }
inline void PrintTo(AccelKind accel, std::ostream* os) { *os << to_string(accel); }

}  // namespace farm
