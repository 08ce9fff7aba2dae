// Plain double integration of a gravity-free level acceleration (estimation core, no ROS): the
// "raw" track the node shows next to the compensated one in rviz (its input has the constant
// bias removed, nothing else), and the benchmark's "raw" method (nothing removed).
#pragma once

#include "periodic_bias_compensation/core/types.h"

namespace periodic_bias_compensation
{
/// Trapezoidal double integration of acceleration samples.
class RawIntegrator
{
public:
  /// Adds one sample. The first sample after reset() only sets the start; a sample after a gap
  /// (restart = true) keeps position and velocity and does not integrate across the gap.
  /// @param t sample time [s]
  /// @param acceleration gravity-free level acceleration [m/s^2]
  void add(double t, const Vector3& acceleration, bool restart);
  /// Back to zero position and velocity (stamps went backwards).
  void reset();
  const Vector3& position() const
  {
    return position_;
  }  ///< [m]

private:
  bool started_ = false;
  double t_ = 0.0;
  Vector3 acceleration_{ 0, 0, 0 };
  Vector3 velocity_{ 0, 0, 0 };
  Vector3 position_{ 0, 0, 0 };
};

}  // namespace periodic_bias_compensation
