// Everything of the ship IMU simulator (no ROS): scenario, motion, effects, simulator.
#pragma once

#include "periodic_bias_compensation/sim/effects.h"
#include "periodic_bias_compensation/sim/motion.h"
#include "periodic_bias_compensation/sim/random.h"
#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/sim/simulator.h"
#include "periodic_bias_compensation/sim/types.h"
