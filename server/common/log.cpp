#include "server/common/log.h"

#include <fmt/format.h>
#include <spdlog/pattern_formatter.h>
#include <spdlog/sinks/stdout_sinks.h>

#include <algorithm>
#include <array>
#include <mutex>
#include <optional>
#include <vector>

#include "renderer/util/input_error.h"

namespace farm {

namespace {

struct LevelName {
  std::string_view name;
  LogLevel level;
};

// Our names, not spdlog's own (it also takes "warning", "err", "critical"): one spelling each,
// the one the CLI documents.
constexpr std::array<LevelName, 6> kLevels{{{"trace", LogLevel::trace},
                                            {"debug", LogLevel::debug},
                                            {"info", LogLevel::info},
                                            {"warn", LogLevel::warn},
                                            {"error", LogLevel::err},
                                            {"off", LogLevel::off}}};

// The loggers made so far (so that a later set_log_level reaches them too) and the operator's
// level once chosen. Loggers are not put in spdlog's registry: it wants unique names, and two
// owners in one process both log as "scheduler".
struct Loggers {
  std::mutex mutex;  // guards both fields
  std::optional<LogLevel> chosen;
  std::vector<std::weak_ptr<spdlog::logger>> made;
};

Loggers& loggers() {
  static Loggers instance;
  return instance;
}

// One sink for every logger: its lock keeps each line whole when two components log at once.
// Plain, not coloured: these lines end up in journald, Kubernetes and CI logs more often than on
// a terminal.
const spdlog::sink_ptr& stderr_sink() {
  static const spdlog::sink_ptr sink = [] {
    auto s = std::make_shared<spdlog::sinks::stderr_sink_mt>();
    s->set_formatter(std::make_unique<spdlog::pattern_formatter>("%Y-%m-%d %H:%M:%S.%e [%n] [%l] %v"));
    return s;
  }();
  return sink;
}

}  // namespace

LogLevel parse_log_level(std::string_view name) {
  for (const LevelName& l : kLevels) {
    if (l.name == name) return l.level;
  }
  std::vector<std::string_view> names;
  for (const LevelName& l : kLevels) names.push_back(l.name);
  throw InputError(fmt::format("log level '{}' is not one of {}", name, fmt::join(names, ", ")));
}

void set_log_level(std::string_view name) {
  const LogLevel level = parse_log_level(name);
  Loggers& all = loggers();
  std::lock_guard lock(all.mutex);
  all.chosen = level;
  for (const std::weak_ptr<spdlog::logger>& made : all.made) {
    if (const std::shared_ptr<spdlog::logger> logger = made.lock()) logger->set_level(level);
  }
}

std::shared_ptr<spdlog::logger> make_logger(const std::string& component, LogLevel default_level) {
  auto logger = std::make_shared<spdlog::logger>(component, stderr_sink());
  Loggers& all = loggers();
  std::lock_guard lock(all.mutex);
  logger->set_level(all.chosen.value_or(default_level));
  std::erase_if(all.made, [](const std::weak_ptr<spdlog::logger>& made) { return made.expired(); });
  all.made.push_back(logger);
  return logger;
}

}  // namespace farm
