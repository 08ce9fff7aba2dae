// Automatic tuning of the paper mode's gains alpha and beta (the paper's stated future work),
// estimation core, no ROS.
#pragma once

#include <array>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "periodic_bias_compensation/core/compensator.h"

namespace periodic_bias_compensation
{
/// Candidate values searched for each gain pair. Defaults span validate()'s range
/// (0 <= alpha < 2, 0 <= beta <= 12) with the paper's Table 3 values among them.
struct GainGrid
{
  std::vector<double> alpha{ 0.1, 0.25, 0.5, 0.75, 1.0, 1.25, 1.5 };
  std::vector<double> beta{ 0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0 };
};

struct GainTuningResult
{
  std::array<AxisGains, 3> gains;  ///< the best gains found, per level axis x, y, z
  Vector3 score_start{ 0, 0, 0 };  ///< criterion with the starting gains, per axis [m]
  Vector3 score{ 0, 0, 0 };        ///< criterion with the gains found, per axis [m]
  int runs = 0;                    ///< compensator runs over the recording
};

/// Tunes alpha_v, beta_v, alpha_p, beta_p per level axis for paper mode on a recording of a
/// vessel that holds its station (moored, at anchor, dynamic positioning, a test bench): its true
/// slow motion is zero, so whatever slow motion paper mode reports is error. Criterion per axis:
/// the RMS of `position_filtered` from `settle` seconds after the first sample to the end.
/// Search: coordinate descent over the grid, (alpha_v, beta_v) with the position gains fixed,
/// then (alpha_p, beta_p), repeated `rounds` times; the axes are independent in paper mode, so one
/// run scores a candidate on all three. Runs diverging to a non-finite output are never chosen.
/// `base` is the paper-mode configuration to start from (its gains are the starting point), `bias`
/// a constant bias from a calibration at rest, if any. `progress(done, total)` is called after
/// every run. Throws std::invalid_argument on an empty recording, a non-paper `base`, or a grid
/// value that validate() refuses.
GainTuningResult tunePaperGains(const std::vector<ImuSample>& samples, const CompensatorConfig& base,
                                const std::optional<Vector3>& bias, double settle, const GainGrid& grid = {},
                                int rounds = 2, const std::function<void(int, int)>& progress = {});

/// The gains as the ROS parameters of config/compensator.yaml (alpha_v_x: ..., one per line),
/// with a comment line first.
std::string gainsToYaml(const std::array<AxisGains, 3>& gains, const std::string& comment);
}  // namespace periodic_bias_compensation
