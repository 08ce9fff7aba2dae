// Sim-to-real gap diagnosis (no ROS), all of it: the recording (recording.h), its signal processing
// (signal.h), features and the gap metric (features.h), the truth and pipeline comparisons
// (truth.h), the motion stage (motion.h) and the diagnosis with its report (diagnose.h). Each
// stage's header can be included alone. See docs/gap.md.
#pragma once

#include "periodic_bias_compensation/gap/diagnose.h"
#include "periodic_bias_compensation/gap/features.h"
#include "periodic_bias_compensation/gap/motion.h"
#include "periodic_bias_compensation/gap/recording.h"
#include "periodic_bias_compensation/gap/signal.h"
#include "periodic_bias_compensation/gap/truth.h"
