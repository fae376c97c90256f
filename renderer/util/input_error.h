#pragma once
// Bad input from a user (job file, model file, command-line value). The CLI maps it to exit code 2
// and the services to INVALID_ARGUMENT; the message always names the file and the place in it.
#include <stdexcept>
#include <string>

namespace farm {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

}  // namespace farm
