#include "periodic_bias_compensation/core/frequency_drift.h"

#include <algorithm>
#include <cmath>

namespace periodic_bias_compensation
{
void FrequencyDrift::clear()
{
  history_.clear();
  slope_ = 0.0;
}

void FrequencyDrift::add(double now, double frequency, double span, bool whole_span, double hop)
{
  time_ = now - 0.5 * span;
  if (!whole_span)
    history_.clear();
  else
    history_.emplace_back(time_, frequency);
  if (history_.size() > kHistory)
    history_.pop_front();
  slope_ = 0.0;
  if (history_.size() < 4)
    return;
  double mt = 0.0, mf = 0.0;
  for (const auto& [t, f] : history_)
  {
    mt += t;
    mf += f;
  }
  mt /= history_.size();
  mf /= history_.size();
  double stt = 0.0, stf = 0.0;
  for (const auto& [t, f] : history_)
  {
    stt += (t - mt) * (t - mt);
    stf += (t - mt) * (f - mf);
  }
  if (stt <= 0.0)
    return;
  const double slope = stf / stt;
  double sse = 0.0;
  for (const auto& [t, f] : history_)
    sse += std::pow(f - mf - slope * (t - mt), 2);
  const double overlap = std::sqrt(span / hop);
  const double standard_error = overlap * std::sqrt(sse / (history_.size() - 2) / stt);
  if (std::abs(slope) > 3.0 * standard_error)
    slope_ = std::clamp(slope, -kMaxSlope, kMaxSlope);
}

double FrequencyDrift::at(double now, double frequency, double min_frequency) const
{
  return std::clamp(frequency + slope_ * (now - time_), std::max(min_frequency, (1.0 - kMaxExtrapolation) * frequency),
                    (1.0 + kMaxExtrapolation) * frequency);
}
}  // namespace periodic_bias_compensation
