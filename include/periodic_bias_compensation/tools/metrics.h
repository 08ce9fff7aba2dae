// Accuracy of motion estimates against the simulator's exact truth, one simulated run at a time,
// per axis (no ROS). Scorer compares a method's slow and wave motion with the truth sample by
// sample; PeriodScorer compares the compensator's dominant frequency with that of the true wave
// acceleration; integrateRaw and highPassBaseline are the two methods without compensation the
// compensator is measured against; median and percentile are the tables' order statistics
// (medians over runs, percentiles over FFT hops).
//
// Frames and units: positions in the truth's ENU frame [m], times in s, frequencies in Hz, shares
// in %. An estimate's slow motion starts at zero: it is compared with the true slow motion less
// the first sample's true slow position. Its wave motion is compared with the true wave motion as
// it is (both oscillate about zero).
//
//   metrics::Scorer scorer(samples.front(), settle);
//   for (const auto& s : samples) scorer.add(s, slow, wave);   // the estimate at sample s
//   const metrics::Errors errors = scorer.finish(samples.back(), slow, wave);
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <array>
#include <cmath>
#include <memory>
#include <vector>

#include "periodic_bias_compensation/core/compensator.h"
#include "periodic_bias_compensation/core/frequency_tracker.h"
#include "periodic_bias_compensation/core/wiener_heave.h"
#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation::metrics
{
/// Elapsed times at which the slow-motion error is reported (60 s, 10 min, 30 min) [s].
constexpr std::array<double, 3> kCheckpoints = { 60.0, 600.0, 1800.0 };

/// Errors of one method on one run, per axis.
struct Errors
{
  /// |filtered - true slow| at each of kCheckpoints [m]; NaN where the run is shorter.
  std::array<Vector3, kCheckpoints.size()> slow_at{ Vector3::Constant(NAN), Vector3::Constant(NAN),
                                                    Vector3::Constant(NAN) };
  Vector3 slow_final = Vector3::Zero();               ///< |filtered - true slow| at the end [m]
  Vector3 total_final = Vector3::Zero();              ///< |filtered + wave - true position| at the end [m]
  Vector3 slow_rms = Vector3::Constant(NAN);          ///< RMS(filtered - true slow) after settling [m]
  Vector3 total_rms = Vector3::Constant(NAN);         ///< RMS(filtered + wave - true position) after settling [m]
  Vector3 wave_rms_percent = Vector3::Constant(NAN);  ///< RMS(wave - true wave) / RMS(true wave) [%]
  /// RMS(wave - true wave) / significant wave height [%], Hs = 4 std(true wave) per axis (for z the
  /// usual significant wave height of heave).
  Vector3 wave_hs_percent = Vector3::Constant(NAN);
};

/// The errors of one method's slow and wave motion, sample by sample, against the truth. A
/// checkpoint's error is taken at the first sample within 0.1 s before it or after it (a 60 s
/// run's last sample is one period short of 60 s); the RMS errors count the samples from `settle`
/// on (elapsed time); the wave errors are NaN on an axis whose true wave motion is zero.
class Scorer
{
public:
  /// first: the run's first sample (its true slow position is the estimate's origin); settle:
  /// elapsed time from which the RMS errors count [s] (infinity: none, only checkpoints and end).
  Scorer(const sim::Sample& first, double settle);
  /// The method's slow motion (from zero) and wave motion at sample s [m].
  void add(const sim::Sample& s, const Vector3& slow, const Vector3& wave);
  /// The errors, with the method's final slow and wave motion at the last sample [m].
  Errors finish(const sim::Sample& last, const Vector3& slow, const Vector3& wave) const;

private:
  Vector3 slow0_;
  double settle_;
  Vector3 error2_ = Vector3::Zero(), truth2_ = Vector3::Zero(), slow2_ = Vector3::Zero(), total2_ = Vector3::Zero();
  Vector3 truth_sum_ = Vector3::Zero();
  int n_ = 0;
  std::array<bool, kCheckpoints.size()> checkpoint_done_{};
  std::array<Vector3, kCheckpoints.size()> slow_at_{ Vector3::Constant(NAN), Vector3::Constant(NAN),
                                                     Vector3::Constant(NAN) };
};

/// Period tracking of one run, per axis: the compensator's dominant frequency against the
/// dominant frequency of the true wave acceleration over the same window (same FFT settings),
/// compared at every FFT hop.
struct PeriodErrors
{
  Vector3 lock_time = Vector3::Constant(NAN);       ///< elapsed time of the first lock [s]
  Vector3 locked_percent = Vector3::Constant(NAN);  ///< hops locked after the first lock [%]
  Vector3 error_median = Vector3::Constant(NAN);    ///< median |f - f_true| / f_true while locked [%]
  Vector3 error_p95 = Vector3::Constant(NAN);       ///< 95th percentile of the same [%]
};

/// The compensator's period tracking over one run. From an axis's first lock on, every FFT hop
/// (fft_hop, counted in samples from the first sample) counts as locked or not where the
/// compensator takes up that hop's search (kSearchDelay later); at a locked one the compensator's
/// frequency f is compared with f_true, the dominant frequency a FrequencyTracker with the
/// compensator's window and band finds in the true wave acceleration over the span the
/// compensator's search saw (analyseFreshest over kRecentFftWindow, at the hop).
class PeriodScorer
{
public:
  /// config: the compensator's (fft_window, fft_hop, min_frequency, max_frequency); rate: the
  /// samples' rate [Hz].
  PeriodScorer(const CompensatorConfig& config, double rate);
  /// Sample s and the compensator's output for it.
  void add(const sim::Sample& s, const CompensatorOutput& out);
  PeriodErrors finish() const;

private:
  CompensatorConfig config_;
  std::array<std::unique_ptr<FrequencyTracker>, 3> truth_;
  int hop_ = 1, since_hop_ = 0;
  int delay_ = 1;                   ///< kSearchDelay in samples, 1..hop_
  std::array<double, 3> at_hop_{};  ///< f_true at the last hop (0: none found)
  bool due_ = false;                ///< the last hop's comparison is still to come
  double rate_ = 0.0;
  std::array<int, 3> hops_{}, locked_{};
  std::array<std::vector<double>, 3> relative_;
  PeriodErrors errors_;
};

/// First-order high-pass filter (bilinear transform with the corner prewarped: gain 1/sqrt(2) at
/// the corner, 0 at zero frequency), one per axis. Its state starts at zero: a constant input is a
/// step at the first sample, which decays by (1 - k) / (1 + k) per sample, k = tan(pi cutoff / rate).
class HighPass
{
public:
  /// cutoff: corner frequency [Hz]; rate: sample rate [Hz].
  HighPass(double cutoff, double rate);
  /// The output for the next input sample.
  Vector3 operator()(const Vector3& x);

private:
  double b_, a_;
  Vector3 x_ = Vector3::Zero(), y_ = Vector3::Zero();
};

/// The baseline of x-io's oscillatory motion tracking: gravity-free level acceleration (the
/// samples' reported orientation, `gravity` [m/s^2] off z) high-passed, integrated, high-passed,
/// integrated, high-passed (first-order, 0.1 Hz), run causally. Its one output is an oscillation
/// about zero: compared as the wave motion, its slow motion is zero. RMS errors from `settle` [s].
Errors highPassBaseline(const std::vector<sim::Sample>& samples, double gravity, double settle);

/// Plain double integration of the level, gravity-free acceleration (no compensation), by the
/// node's RawIntegrator (trapezoidal). Its position is slow and wave motion at once: scored as the
/// slow motion at the checkpoints and the end only (the RMS and wave errors are NaN).
Errors integrateRaw(const std::vector<sim::Sample>& samples, double gravity);

/// The lowest wave error a causal linear filter of each axis's own level acceleration reaches on
/// this run, with the truth to fit it: the acceleration (reported orientation, `gravity` off z)
/// through two moving averages over about kBoundStep (the spectral estimate's low-pass), an FIR of
/// kBoundSpan over those values kBoundStep apart ending at each sample, plus a constant; the taps
/// fitted by least squares to the true wave displacement of the IMU's point (base_link's plus the
/// lever arm's `R r - r`, `lever_arm` in base_link) on one half of the run and applied to the other
/// (each half predicted by the other's fit), where kBoundSpan of history exists. No causal linear
/// estimate from that axis alone does better on a stationary sea once it has that history; other
/// inputs (the attitude, the other axes) could. Scored as the wave motion at base_link from
/// `settle` + kBoundSpan [s] on (the first kBoundSpan lacks the history); its slow motion is the
/// truth.
constexpr double kBoundSpan = 120.0;                       ///< [s], the spectral heave estimate's longest span
constexpr double kBoundStep = WienerHeave::kDesignPeriod;  ///< [s]
Errors causalBound(const std::vector<sim::Sample>& samples, double gravity, double settle, const Vector3& lever_arm);

/// Value below which `share` (0..1) of `values` lie, nearest rank: the element of rank
/// floor(share n) (from 0) of the n values sorted, at most the largest; NaN for none.
double percentile(std::vector<double> values, double share);

/// Median of the finite values (the mean of the two middle ones for an even count); NaN and
/// infinite values are left out; NaN when none is finite.
double median(std::vector<double> values);
}  // namespace periodic_bias_compensation::metrics
