#pragma once
// `farm token NAME --roles ROLES`: makes a new random bearer token and prints it, with the line
// that grants it to add to a server's tokens file (server/common/token_table.h).
#include "server/cli/command_table.h"

namespace farm {

void add_token_command(CLI::App& app, CommandTable& commands);

}  // namespace farm
