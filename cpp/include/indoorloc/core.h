// Umbrella header of indoorloc's shared core: checks, random streams, log-weights, resampling,
// deterministic parallel runs, Options/Summary helpers.
#pragma once

#include "indoorloc/core/check.h"
#include "indoorloc/core/log_weights.h"
#include "indoorloc/core/options.h"
#include "indoorloc/core/parallel.h"
#include "indoorloc/core/random.h"
#include "indoorloc/core/resampling.h"
#include "indoorloc/core/version.h"
