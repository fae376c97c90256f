#include "server/cli/exit_without_teardown.h"

#include <cstdio>
#include <cstdlib>
#include <iostream>

namespace farm {

void exit_without_teardown(int code) {
  std::cout.flush();
  std::cerr.flush();
  std::fflush(nullptr);  // fmt prints to the C streams
  std::_Exit(code);
}

}  // namespace farm
