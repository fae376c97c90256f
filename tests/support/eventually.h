#pragma once
// Waiting in a test for something another thread does, bounded: polls `done` every 10 ms until it
// holds (true) or `timeout` has passed (false). For conditions, never for durations.
#include <chrono>
#include <functional>

namespace farm::test {

bool eventually(const std::function<bool()>& done,
                std::chrono::milliseconds timeout = std::chrono::seconds(60));

}  // namespace farm::test
