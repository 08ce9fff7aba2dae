// Sim-to-real gap diagnosis: the sample-by-sample comparison of a recording with the ideal IMU of
// its truth, and the compensator's own pipeline stages on a recording. See docs/gap.md.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "periodic_bias_compensation/gap/features.h"
#include "periodic_bias_compensation/gap/recording.h"

namespace periodic_bias_compensation::gap
{
/// The ideal IMU a truth track drives, at the given stamps (N x 6, REP-145): specific force
/// R^T (a + g z) and angular rate in the body frame (sim::idealImu). The world acceleration is the
/// central difference of the world velocity (the twist rotated into the world, or position
/// differences), the angular rate the twist's (or from orientation differences); both are
/// smoothed by a centred moving average of `smooth` s, then interpolated to the stamps.
Eigen::MatrixXd idealFromTruth(const TruthTrack& truth, const std::vector<double>& stamps, double gravity,
                               double smooth);

/// Centred moving average of `smooth` s over the columns (stamps give the rate).
Eigen::MatrixXd movingAverage(const Eigen::MatrixXd& x, double rate, double smooth);

/// Real minus the ideal IMU driven by its truth, both smoothed alike (N x 6).
Eigen::MatrixXd truthResidual(const Recording& r, double gravity, double smooth);

/// Per channel and time segment: mean and standard deviation of a truth residual (layout: for
/// each channel, `segments` means then `segments` standard deviations).
std::vector<double> truthFeatures(const Eigen::MatrixXd& residual, int segments);

/// Layout of truthFeatures() (stage "truth", range = the segment's time span since the start).
FeatureLayout truthLayout(double duration, int segments);

/// The compensator's own pipeline stages (core Compensator, default mode) on a recording, per
/// level axis and time segment: constant-bias estimate, dominant frequency while locked, rms of
/// the filtered velocity, of the filtered position (error growth) and of the wave position.
std::vector<double> stageFeatures(const Recording& r, int segments);

/// Layout of stageFeatures() (stage "compensator", channel "level x/y/z").
FeatureLayout stageLayout(double duration, int segments);
}  // namespace periodic_bias_compensation::gap
