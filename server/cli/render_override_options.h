#pragma once
// The options that replace a job's render settings (--engine --width --height --spp
// --tile-size), declared once for every command that takes them (`farm render`, `farm submit`),
// so their names, checks and help cannot drift apart.
#include <CLI/CLI.hpp>

#include "server/client/render_overrides.h"

namespace farm {

// Adds the options to `command`, bound to `overrides` (which must outlive the parse).
void add_render_override_options(CLI::App& command, RenderOverrides& overrides);

}  // namespace farm
