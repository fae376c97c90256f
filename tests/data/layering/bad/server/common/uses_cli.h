#pragma once
// A fixture for the layering check: common must not reach up into the CLI.
#include "server/cli/render_command.h"
