// Sim-to-real gap diagnosis, motion stage: the recording's motion against the scenario's
// (standing tilt, heading, sea state, wave responses), before any sensor effect. See docs/gap.md.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

#include "periodic_bias_compensation/gap/recording.h"
#include "periodic_bias_compensation/sim/scenario.h"

namespace periodic_bias_compensation::gap
{
/// The motion of one recording, as the diagnosis compares it.
struct MotionSummary
{
  double roll = 0.0;         ///< standing tilt: mean up as the orientation gives it, else the mean force [rad]
  double pitch = 0.0;        ///< [rad]
  double heading = NAN;      ///< mean heading from the reported orientation (NaN without) [rad]
  double wave_height = 0.0;  ///< 4 sqrt(m0) of the heave in the 2-25 s band [m]
  double peak_period = 0.0;  ///< 1 / centroid of the heave spectrum^4 in that band [s] (0: none)
  /// RMS in that band per degree of freedom (surge, sway, heave, roll, pitch, yaw): the
  /// horizontal specific force along and across the mean heading (through the reported
  /// orientation; without one the sensor's x and y) [m/s^2], the vertical one [m/s^2], the
  /// gyro's x, y, z [rad/s].
  std::array<double, 6> wave_rms{};
  std::vector<double> heave_frequency;   ///< bins of the heave spectrum in that band [Hz]
  std::vector<double> heave_density;     ///< the heave spectrum there [m^2/Hz]
  double vertical_df = 0.0;              ///< bin spacing of the vertical specific force's spectrum [Hz]
  std::vector<double> vertical_density;  ///< its spectrum from 0 Hz to the Nyquist frequency [(m/s^2)^2/Hz]
};

/// Heave from the vertical specific force (through the reported orientation when there is one,
/// else along the mean force): its Welch spectrum (segments of a quarter of the recording, 100 to
/// 400 s) divided by (2 pi f)^4; the peak interpolated between bins.
MotionSummary summariseMotion(const Recording& recording);

/// A motion fitted to the recording, to be tried on the withheld part.
struct MotionCandidate
{
  std::string what;        ///< "tilt and heading", "sea state", or both
  sim::Scenario scenario;  ///< the scenario with it
};

/// The recording's motion against the ensemble's, and the scenario fitted to it.
struct MotionFit
{
  bool differs = false;                     ///< a tilt, heading or sea state beyond the ensemble's spread
  MotionSummary real;                       ///< the recording's
  MotionSummary scenario;                   ///< the ensemble's mean (the heave spectrum bin by bin)
  std::vector<std::string> findings;        ///< one line per difference, in words
  std::vector<MotionCandidate> candidates;  ///< fits to try, the whole one first
  std::string adopted;                      ///< the candidate that brought the withheld part closest ("" none)
  sim::Scenario fitted;                     ///< the scenario with the adopted candidate (as given without)
  double gap_before = 0.0;                  ///< withheld gap against the scenario as given
  double gap_after = 0.0;                   ///< against `fitted` (equal when nothing is adopted)
  /// `fitted` leaves the withheld part far beyond the null gap: the motion is one the scenario's
  /// kind of motion cannot take.
  bool unexplained = false;
  /// Then the withheld features the motion reaches and the fit leaves departed ("channel quantity
  /// range segment"): left out of the sensor diagnosis.
  std::vector<std::string> left_out;
};

/// Compares the recording with runs of the scenario (same duration and rate). A standing tilt
/// beyond 0.005 rad becomes a candidate roll/pitch (a trim, list or mounting, not a sensor
/// mean); a heading beyond 0.05 rad a candidate heading (not for routes); a heave Hs or peak
/// period 15 % and three ensemble spreads off a candidate sea, every wave system's height and
/// period rescaled alike. `fitted` is left as given: the caller adopts a candidate (diagnose:
/// the one that brings the withheld part closest, if any does). `real` and `runs` are the
/// summaries (summariseMotion) of the recording and of the runs.
MotionFit fitMotion(const MotionSummary& real, const sim::Scenario& scenario, const std::vector<MotionSummary>& runs);

/// The scenario's sea responses (sim::Sea::response) of surge, sway, roll, pitch and yaw scaled
/// by the recording's wave-band RMS of each over the runs' mean, where it is 15 % and three
/// spreads off (at most 5); nullopt when none is, or the scenario has no sea. The runs' summaries
/// are of `scenario` (after its sea state is fitted: the heave is left to it). Adds a finding. With
/// `rotations_only`, roll, pitch and yaw alone (the gyro's: a lever arm, a scale factor or a
/// misalignment of the accelerometer changes surge and sway, not them).
std::optional<MotionCandidate> fitWaveResponses(const MotionSummary& real, const sim::Scenario& scenario,
                                                const std::vector<MotionSummary>& runs,
                                                std::vector<std::string>* findings, bool rotations_only = false);

/// The length that filters the scenario's short waves (sim::Sea::length: each component's
/// response divided by 1 + (length / wavelength)^2) fitted to the vertical specific force's
/// spectrum above the wave peak: a buoy or hull that does not follow the short waves of a
/// JONSWAP tail. A least-absolute-deviations fit in log power over the bins from kShortWaveLow
/// to kShortWaveHigh Hz (at most 0.4 x the rate) where the motion stands a decade above the
/// spectra's floor (their median over the top fifth of the band to the Nyquist frequency), the
/// floor kept as it is. nullopt when the scenario has no sea, too few bins qualify, the spectra
/// there agree within a factor e (the median over the bins), or the fitted length is within
/// kSeaTolerance (and 1 m) of the scenario's. Adds a finding. The runs' summaries are of
/// `scenario`.
std::optional<MotionCandidate> fitShortWaves(const MotionSummary& real, const sim::Scenario& scenario,
                                             const std::vector<MotionSummary>& runs,
                                             std::vector<std::string>* findings);

/// The heave spectra of the motion stage as CSV, "f,real,given,fitted" [Hz, m^2/Hz]: the
/// recording's, the mean of the scenario's runs as given, and the mean of `fitted_runs` (the
/// summaries of the adopted fit's runs).
std::string motionCsv(const MotionFit& fit, const std::vector<MotionSummary>& fitted_runs);
}  // namespace periodic_bias_compensation::gap
