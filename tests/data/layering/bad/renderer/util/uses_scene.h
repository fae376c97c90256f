#pragma once
// A fixture for the layering check: util sits below the scene model.
#include "renderer/scene/job.h"
