#include "server/cli/log_level_option.h"

#include <fmt/format.h>

#include <string>

#include "renderer/util/input_error.h"
#include "server/common/log.h"

namespace farm {

void add_log_level_option(CLI::App& command, const char* default_level) {
  command
      .add_option_function<std::string>(
          "--log-level", [](const std::string& name) { set_log_level(name); },
          fmt::format("Log messages at this level and above on stderr: trace, debug, info, warn, error "
                      "or off (default {})",
                      default_level))
      // Checked while parsing, so a bad name is a usage error (exit 2) naming the choices.
      ->check(CLI::Validator(
          [](std::string& name) -> std::string {
            try {
              parse_log_level(name);
              return {};
            } catch (const InputError& e) {
              return e.what();
            }
          },
          "LEVEL"));
}

}  // namespace farm
