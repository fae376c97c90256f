#pragma once
// A fixture for the layering check: the dashboard goes through the front door, never around it.
#include "server/scheduler/scheduler_core.h"
