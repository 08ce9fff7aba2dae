// The IMU's mounting on the vehicle as the node and compensate_bag decide it: none needed when
// the IMU's frame is base_frame or identity_mounting is set, otherwise the rotation of the
// imu_frame -> base_frame transform in a tf2 buffer (filled from /tf and /tf_static by the node's
// listener, or from a bag's messages by compensate_bag). No NodeHandle, no master needed.
#pragma once

#include <string>

#include <tf2/buffer_core.h>

#include "periodic_bias_compensation/ros/conversions.h"
#include "periodic_bias_compensation/ros/parameters.h"

namespace periodic_bias_compensation
{
/// Where a mounting came from.
enum class MountingSource
{
  kNotNeeded,  ///< the IMU's frame is base_frame, or identity_mounting: no lookup
  kTransform,  ///< the imu_frame -> base_frame transform
  kMissing,    ///< no usable transform (yet): identity until one is found
};

struct MountingLookup
{
  MountingSource source = MountingSource::kMissing;
  Mounting mounting;  ///< identity unless source is kTransform
  std::string why;    ///< kMissing: what tf2 said
};

/// The mounting of an IMU whose messages are in `imu_frame`, for the frames and switches of
/// `options` (base_frame, identity_mounting), from the latest transform in `tf`. A transform
/// with a non-finite or zero rotation counts as missing.
MountingLookup lookupMounting(const tf2::BufferCore& tf, const std::string& imu_frame, const RosOptions& options);

/// The rotation as roll, pitch and yaw about the base frame's fixed axes, "rpy 0 0 1.571 rad".
std::string describeMounting(const Mounting& mounting);
}  // namespace periodic_bias_compensation
