#pragma once
// How a sandboxed run ended, told from what the grader saw of it (sandbox.h): bwrap's exit
// status, the CPU time and peak memory of all its processes, and whether the grader itself
// stopped it. SandboxResult::reason lives here too.
#include "server/grade/sandbox.h"
#include "server/grade/sandbox_process.h"

namespace farm {

// Why the grader killed the sandbox, if it did.
enum class SandboxStop { none, wall_time, processes, work_folder };

// Sets result.end, exit_code, signal, detail, cpu_seconds and peak_memory_bytes; reads
// result.output (the messages of bwrap or setpriv when they, not the program, failed).
void judge_sandbox_exit(SandboxResult& result, SandboxStop stop, const SandboxExit& exit, const SandboxLimits& limits);

}  // namespace farm
