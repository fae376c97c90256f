#pragma once
// Gives the heap's free pages back to the system. A server that has finished a burst of work keeps
// what glibc's allocator freed but holds: free chunks inside its arenas (one per thread that
// allocated, and gRPC and the dispatcher run many) are reused by later allocations but are not
// returned to the kernel unless they lie at the top of an arena. malloc_trim(0) releases every
// whole free page of every arena (MADV_DONTNEED), so the resident size follows what is in use.
namespace farm {

void return_free_memory_to_system();

}  // namespace farm
