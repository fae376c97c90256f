#pragma once
// Crash points for the tests that must stop a process at an exact step (docs/architecture.md,
// "Testing"): a process started with FARM_FAILPOINT=<name> kills itself with SIGKILL, as kill -9
// would, the first time it reaches failpoint(<name>). Unset (as in every real run), a failpoint is
// one comparison with a value read once. Names in use:
//   dependency-release   JobDependencies::release_waiting, its changes made, before its commit
#include <string_view>

namespace farm {

void failpoint(std::string_view name);

}  // namespace farm
