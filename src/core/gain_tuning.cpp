#include "periodic_bias_compensation/core/gain_tuning.h"
#include "periodic_bias_compensation/core/parameter_table.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace periodic_bias_compensation
{
namespace
{
/// RMS of the reported slow motion per axis after `settle`; +Inf on an axis whose output is ever
/// non-finite.
Vector3 slowMotionRms(const std::vector<ImuSample>& samples, const CompensatorConfig& config,
                      const std::optional<Vector3>& bias, double settle)
{
  Compensator compensator(config);
  if (bias && !compensator.setConstantBias(*bias))
    throw std::invalid_argument("tunePaperGains: the constant bias is not finite or too large");
  CompensatorOutput out;
  Vector3 sum2 = Vector3::Zero();
  std::array<bool, 3> diverged{};
  long n = 0;
  const double start = samples.front().t;
  for (const ImuSample& s : samples)
  {
    if (!producedOutput(compensator.addSample(s, &out)) || s.t - start < settle)
      continue;
    for (int i = 0; i < 3; ++i)
      if (std::isfinite(out.position_filtered[i]))
        sum2[i] += out.position_filtered[i] * out.position_filtered[i];
      else
        diverged[i] = true;
    ++n;
  }
  Vector3 rms = Vector3::Constant(std::numeric_limits<double>::infinity());
  for (int i = 0; i < 3; ++i)
    if (n > 0 && !diverged[i] && std::isfinite(sum2[i]))
      rms[i] = std::sqrt(sum2[i] / n);
  return rms;
}
}  // namespace

GainTuningResult tunePaperGains(const std::vector<ImuSample>& samples, const CompensatorConfig& base,
                                const std::optional<Vector3>& bias, double settle, const GainGrid& grid, int rounds,
                                const std::function<void(int, int)>& progress)
{
  if (samples.empty())
    throw std::invalid_argument("tunePaperGains: the recording has no samples");
  if (base.mode != Mode::kPaper)
    throw std::invalid_argument("tunePaperGains: the base configuration is not paper mode");
  if (grid.alpha.empty() || grid.beta.empty())
    throw std::invalid_argument("tunePaperGains: the grid is empty");
  const int total = 1 + 2 * rounds * static_cast<int>(grid.alpha.size() * grid.beta.size());

  GainTuningResult result;
  result.gains = base.gains;
  auto run = [&](const std::array<AxisGains, 3>& gains) {
    CompensatorConfig config = base;
    config.gains = gains;
    std::string why;
    if (!config.validate(&why))
      throw std::invalid_argument("tunePaperGains: " + why);
    const Vector3 score = slowMotionRms(samples, config, bias, settle);
    ++result.runs;
    if (progress)
      progress(result.runs, total);
    return score;
  };
  result.score_start = result.score = run(result.gains);

  for (int round = 0; round < rounds; ++round)
    for (const bool velocity : { true, false })
    {
      std::array<AxisGains, 3> best = result.gains;
      for (double alpha : grid.alpha)
        for (double beta : grid.beta)
        {
          std::array<AxisGains, 3> candidate = result.gains;
          for (AxisGains& g : candidate)
            (velocity ? g.alpha_v : g.alpha_p) = alpha, (velocity ? g.beta_v : g.beta_p) = beta;
          const Vector3 score = run(candidate);
          for (int i = 0; i < 3; ++i)
            if (score[i] < result.score[i])
            {
              result.score[i] = score[i];
              best[i] = candidate[i];
            }
        }
      result.gains = best;
    }
  return result;
}

std::string gainsToYaml(const std::array<AxisGains, 3>& gains, const std::string& comment)
{
  std::ostringstream out;
  out.precision(6);
  out << "# " << comment << "\n";
  for (int axis = 0; axis < 3; ++axis)
    for (const GainTerm& term : kGainTerms)
      out << gainKey(term, axis) << ": " << gains[axis].*term.field << "\n";
  return out.str();
}
}  // namespace periodic_bias_compensation
