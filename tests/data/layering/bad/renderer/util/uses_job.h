#pragma once
// A fixture for the layering check: util sits below the job format.
#include "renderer/job/job.h"
