// The services' log levels by name (server/common/log.h), as the CLI's --log-level passes them.
#include <gtest/gtest.h>

#include <string>

#include "renderer/util/input_error.h"
#include "server/common/log.h"

namespace farm {
namespace {

TEST(LogLevelTest, EachDocumentedNameIsItsLevel) {
  EXPECT_EQ(parse_log_level("trace"), LogLevel::trace);
  EXPECT_EQ(parse_log_level("debug"), LogLevel::debug);
  EXPECT_EQ(parse_log_level("info"), LogLevel::info);
  EXPECT_EQ(parse_log_level("warn"), LogLevel::warn);
  EXPECT_EQ(parse_log_level("error"), LogLevel::err);
  EXPECT_EQ(parse_log_level("off"), LogLevel::off);
}

TEST(LogLevelTest, ABadNameIsAnInputErrorNamingItAndTheAcceptedOnes) {
  for (const std::string bad : {"verbose", "INFO", "warning", ""}) {
    try {
      parse_log_level(bad);
      ADD_FAILURE() << "'" << bad << "' was accepted";
    } catch (const InputError& e) {
      const std::string message = e.what();
      EXPECT_NE(message.find("'" + bad + "'"), std::string::npos) << message;
      EXPECT_NE(message.find("trace, debug, info, warn, error, off"), std::string::npos) << message;
    }
  }
}

TEST(LogLevelTest, SetLogLevelRejectsABadNameAndChangesNothing) {
  const auto logger = make_logger("test", LogLevel::warn);
  EXPECT_THROW(set_log_level("loud"), InputError);
  EXPECT_EQ(logger->level(), LogLevel::warn);
  EXPECT_EQ(make_logger("test", LogLevel::err)->level(), LogLevel::err);
}

}  // namespace
}  // namespace farm
