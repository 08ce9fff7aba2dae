// The drift of a tracked dominant frequency (estimation core, no ROS).
//
// The FFT reports the frequency at the centre of its window, half a window in the past; an
// encounter frequency moves as the ship changes course or speed, and a tide's or a day's forcing
// has its own slow changes. The slope of the last kHistory estimates (a least-squares line of
// frequency against window centre time) extrapolates it to now. It is believed only when it stands
// out of the estimates' own scatter by 3 standard errors, inflated by sqrt(span / hop): windows
// one hop apart share most of their data, so their errors are correlated. Only estimates over a
// span that no longer grows enter (while the window fills, the interpolation bias changes with
// the data length and would read as a drift). The slope is bounded to kMaxSlope, and the
// extrapolated frequency to kMaxExtrapolation of the estimate and no lower than the band's lower
// edge: a noisy slope extrapolated over a long window must never take the frequency towards zero,
// where a displacement (the acceleration over omega^2) would explode.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <cstddef>
#include <deque>
#include <utility>

namespace periodic_bias_compensation
{
class FrequencyDrift
{
public:
  /// Estimates in the regression [-].
  static constexpr std::size_t kHistory = 20;
  /// Largest slope believed [Hz/s].
  static constexpr double kMaxSlope = 0.01;
  /// Largest relative change of the extrapolated frequency from the newest estimate [-].
  static constexpr double kMaxExtrapolation = 0.15;

  /// Forgets the estimates (a new lock, a restart): no slope until four have come again.
  void clear();
  /// A new estimate: `frequency` [Hz] of a window `span` [s] long ending at `now` [s];
  /// whole_span: its span no longer grows; hop: the time between estimates [s].
  void add(double now, double frequency, double span, bool whole_span, double hop);

  /// The slope believed [Hz/s] (0 when none stands out).
  double slope() const
  {
    return slope_;
  }
  /// `frequency` [Hz], the newest estimate, extrapolated to `now` [s] with the slope, within the
  /// bounds above and no lower than min_frequency [Hz].
  double at(double now, double frequency, double min_frequency) const;

private:
  std::deque<std::pair<double, double>> history_;  ///< window centre time [s], frequency [Hz]
  double slope_ = 0.0;
  double time_ = 0.0;  ///< centre time of the newest window [s]
};
}  // namespace periodic_bias_compensation
