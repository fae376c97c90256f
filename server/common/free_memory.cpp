#include "server/common/free_memory.h"

#include <malloc.h>

namespace farm {

void return_free_memory_to_system() {
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
}

}  // namespace farm
