#pragma once
// The services' logs, through spdlog: one logger per component ("scheduler", "worker"), every one
// writing to stderr through one shared sink (so that lines of two components never interleave),
// a line a message:
//
//   2024-05-01 12:00:00.123 [scheduler] [warning] job 3f2a... tiles 4-7: worker ...: UNAVAILABLE: ...
//
// stdout is not logged to: it carries the lines other programs read ("worker listening on
// HOST:PORT").
//
// Levels: a component is made with the level its owner gives as the default (`farm scheduler`
// and `farm worker` log info and up; the embedded farm of `farm render` only warnings and
// errors, under its progress bar). An operator's choice, set_log_level(), overrides every
// default in the process.
#include <spdlog/logger.h>

#include <memory>
#include <string>
#include <string_view>

namespace farm {

using LogLevel = spdlog::level::level_enum;

// "trace", "debug", "info", "warn", "error" or "off" (exactly these, lower case) -> the level.
// InputError for any other name; the message names the bad value and the accepted ones.
LogLevel parse_log_level(std::string_view name);

// The operator's level for the whole process (the CLI's `--log-level NAME`): every farm logger,
// those made before the call and those made after it, logs messages at NAME and above, whatever
// default its component was made with. InputError as parse_log_level for a bad name, and then
// nothing changes. Thread-safe; meant to be called once, at start-up, before servers start.
void set_log_level(std::string_view name);

// A new logger named `component`, at `default_level` unless set_log_level has chosen a level
// (then at that one). Each owner makes its own, so that two in one process (a test's scheduler
// core and its embedded farm) keep their own defaults.
std::shared_ptr<spdlog::logger> make_logger(const std::string& component, LogLevel default_level);

}  // namespace farm
