// Constant and periodic accelerometer bias compensation (estimation core, no ROS).
//
// One Compensator takes IMU samples one at a time (time as a plain double, specific force in
// the sensor frame, optional orientation) and returns, for every accepted sample, the
// drift-compensated slow motion and the drift-free wave motion in a level ENU frame.
//
// Threading: a Compensator is not thread-safe; the owner serialises calls.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "periodic_bias_compensation/core/frequency_tracker.h"
#include "periodic_bias_compensation/core/gyro_attitude.h"
#include "periodic_bias_compensation/core/time_base.h"
#include "periodic_bias_compensation/core/types.h"

namespace periodic_bias_compensation
{
/// Largest specific force accepted per axis [m/s^2] (about 200 g: above any accelerometer fitted
/// on a ship). A finite value beyond it is a driver glitch, not a measurement: integrated, it
/// would overflow the estimator state.
constexpr double kMaxSpecificForce = 2000.0;
/// Largest angular rate accepted per axis [rad/s].
constexpr double kMaxAngularRate = 100.0;
/// Largest constant bias accepted per axis [m/s^2] (setConstantBias, calibration files).
constexpr double kMaxConstantBias = 50.0;
/// Shortest period, in samples, that paper mode corrects (Eq. 6-7). Below it the comb loop can
/// diverge with gains that validate() accepts (L = 2: |alpha/2 - beta/4| < 1 is needed, so beta
/// = 10.4 diverges); from 6 samples on it stays bounded for every accepted gain (scanned,
/// test_bad_input: PaperModeShortPeriod...).
constexpr int kMinPaperPeriod = 6;
/// Newest part of the FFT window analysed again for a period that fits three times in it
/// (FrequencyTracker::analyseFreshest) [s].
constexpr double kRecentFftWindow = 30.0;
/// From a period search's last sample to taking up its result, the search running on the core's
/// design thread meanwhile [s of data]: the calibration window's (milliseconds over 10 s at 1 kHz
/// and more) and each fft_hop's (at most one hop; tens of microseconds, on memory the sample's
/// call would otherwise have to fetch after sleeping between samples).
constexpr double kSearchDelay = 0.2;

/// How the periodic drift terms d_v, d_p are computed.
enum class Mode
{
  kPaper,    ///< Eq. 1-7 of Kim et al. as written, open points decided in docs/algorithm.md
  kDefault,  ///< the project's estimator (harmonic tracking + comb drift removal)
};

/// "paper" / "default" <-> Mode. modeFromString returns false on an unknown name.
std::string toString(Mode mode);
bool modeFromString(const std::string& name, Mode* mode);

/// Gains of Eq. 6-7 for one axis (paper Table 3 gives the defaults).
struct AxisGains
{
  double alpha_v = 0.5;  ///< velocity error gain [-] (range: compensatorParameters())
  double alpha_p = 0.5;  ///< position error gain [-]
  double beta_v = 6.0;   ///< periodic offset gain, velocity [-]
  double beta_p = 2.0;   ///< periodic offset gain, position [-]
};

/// Everything that configures a Compensator. Key, range, unit and meaning of every field:
/// compensatorParameters() (core/parameter_table.h), listed in docs/ros_api.md.
struct CompensatorConfig
{
  Mode mode = Mode::kDefault;
  /// Table 3 of the paper: x, y, z.
  std::array<AxisGains, 3> gains{ { { 0.5, 0.5, 6.0, 2.0 }, { 0.5, 0.1, 5.0, 1.0 }, { 0.5, 0.1, 5.0, 4.0 } } };

  bool enable_constant = true;             ///< estimate/remove the constant bias
  bool enable_periodic = true;             ///< estimate/remove the periodic bias
  double calibration_duration = 10.0;      ///< constant-bias window at start [s]
  bool assume_static_calibration = false;  ///< window is at rest (paper Sec. 3.1); else motion allowed

  double fft_window = 60.0;          ///< FFT window length [s]
  double fft_hop = 1.0;              ///< time between FFT updates [s]
  double min_frequency = 0.05;       ///< lowest dominant frequency searched [Hz]
  double max_frequency = 2.0;        ///< highest dominant frequency searched [Hz]
  double min_peak_ratio = 30.0;      ///< peak power / median power in band needed for a lock [-]
  int harmonics = 2;                 ///< harmonics of the dominant frequency tracked (default mode)
  double harmonic_memory = 3.0;      ///< time constant of the harmonic estimator [s] (default mode)
  double drift_time_constant = 2.0;  ///< slow-motion drift removal time constant [s] (default)
  /// Default mode: the vertical wave motion (heave) from the whole wave band (HeaveFilter)
  /// rather than from the harmonic model of the dominant period.
  bool heave_filter = true;
  double heave_corner_frequency = 0.015;  ///< HeaveFilter corner [Hz]

  /// Default mode, samples without orientation: level them with an attitude integrated from the gyro
  /// (GyroAttitude) rather than with one fixed level frame, which leaks g sin(roll) and
  /// g sin(pitch) of the hull's motion into the level axes. It starts from the IMU's last
  /// orientation when that stops, from the specific force otherwise.
  bool gyro_attitude = true;
  double tilt_time_constant = 30.0;  ///< GyroAttitudeConfig::tilt_time_constant [s]
  bool estimate_gyro_bias = true;    ///< GyroAttitudeConfig::estimate_bias

  /// The IMU's position from the point whose motion the outputs describe, in the frame of the
  /// samples (LeverArm): its tilt's wave part is taken off the wave outputs of the default
  /// mode [m].
  Vector3 lever_arm{ 0, 0, 0 };

  double gravity = kStandardGravity;        ///< local gravity magnitude [m/s^2]
  double max_gap = 0.5;                     ///< a confirmed gap longer than this resets the integration [s]
  double max_rate_change = 0.2;             ///< relative sample-rate change that re-plans the FFT [-]
  double max_quaternion_norm_error = 0.01;  ///< |1 - |q|| above this rejects the sample [-]

  /// Checks every key's range (compensatorParameters(), which holds the loop stability limits)
  /// and the rules between keys (compensatorOrderRules()). On failure returns false and, if
  /// why != nullptr, writes a message naming the offending key; a rule between two keys names
  /// first the one among `changed` (the keys the user set), when the caller knows them.
  bool validate(std::string* why, const std::vector<std::string>& changed = {}) const;
};

/// One IMU sample. REP-145: specific force including gravity, in the sensor frame.
struct ImuSample
{
  double t = 0.0;                     ///< sample time [s]
  Vector3 specific_force{ 0, 0, 0 };  ///< accelerometer [m/s^2]
  Vector3 angular_rate{ 0, 0, 0 };    ///< gyro [rad/s]
  bool has_orientation = false;
  Quaternion orientation{ 1, 0, 0, 0 };  ///< sensor -> level ENU frame
};

/// Per-axis estimator state, as published in BiasState.
struct AxisState
{
  double constant_bias = 0.0;   ///< [m/s^2]
  double periodic_bias = 0.0;   ///< current periodic acceleration estimate [m/s^2]
  double frequency = 0.0;       ///< dominant frequency [Hz], 0 if not locked
  double period_samples = 0.0;  ///< L [samples], 0 if not locked
  bool locked = false;
  double d_v = 0.0;  ///< [m/s]
  double d_p = 0.0;  ///< [m]
  /// Paper mode: locked, but the period is shorter than kMinPaperPeriod samples, so the
  /// periodic correction is off on this axis (it could diverge).
  bool period_too_short = false;
};

/// Where the level frame of samples without orientation comes from.
enum class LevelSource
{
  kNone,                ///< no sample without orientation yet
  kGravity,             ///< mean specific force (gravity direction) of the calibration window
  kAttitudeBeforeLoss,  ///< mean IMU orientation over the last kAttitudeMemory s before it stopped
  kGyroAttitude,        ///< attitude integrated from the gyro (gyro_attitude), sample by sample
};
std::string toString(LevelSource source);

/// Time constant of the mean IMU orientation kept for when orientation disappears [s]: long
/// against a wave period, so the hull's roll and pitch average out.
constexpr double kAttitudeMemory = 30.0;

/// What happened to a sample handed to addSample().
enum class SampleStatus
{
  kAccepted,
  kRejectedNonFinite,      ///< NaN/Inf in a used field: dropped
  kRejectedBadQuaternion,  ///< non-unit orientation: dropped (all zeros means none: accepted)
  kRejectedDuplicate,      ///< same stamp as the previous sample: dropped
  kRejectedOutOfRange,     ///< finite but beyond kMaxSpecificForce / kMaxAngularRate: dropped
  kRejectedEarly,          ///< stamp far less than a period after the previous one: dropped
  kHeld,                   ///< stamp does not continue the stream: held until the jump is
                           ///< confirmed (then processed) or the stream goes on (then dropped)
  kResetBackwards,         ///< confirmed jump backwards (bag loop): state reset, the held samples
                           ///< and this one start anew
  kGapReset,               ///< confirmed gap longer than max_gap: integration reset, likewise
};
std::string toString(SampleStatus status);
/// True when addSample filled its output for this sample (accepted, or accepted after a reset).
inline bool producedOutput(SampleStatus status)
{
  return status == SampleStatus::kAccepted || status == SampleStatus::kGapReset ||
         status == SampleStatus::kResetBackwards;
}

/// How far an output can be trusted.
enum class OutputState
{
  kCalibrating,  ///< calibration window running: positions and velocities held at zero, their
                 ///< variances kHeldVariance
  kTracking,     ///< calibrated: the estimates and their variances are the estimator's
};
std::string toString(OutputState state);
/// Variance given to outputs held at zero while calibrating [m^2, m^2/s^2].
constexpr double kHeldVariance = 1e6;

/// Output for one accepted sample, level ENU frame.
struct CompensatorOutput
{
  double t = 0.0;
  OutputState state = OutputState::kCalibrating;
  Vector3 position_filtered{ 0, 0, 0 };   ///< slow motion, drift and wave removed [m]
  Vector3 velocity_filtered{ 0, 0, 0 };   ///< [m/s]
  Vector3 position_wave{ 0, 0, 0 };       ///< wave (periodic) motion about the slow motion [m]
  Vector3 velocity_wave{ 0, 0, 0 };       ///< [m/s]
  Vector3 acceleration_level{ 0, 0, 0 };  ///< gravity-free level acceleration, bias removed [m/s^2]
  /// Gravity-free level acceleration with only the calibrated constant bias removed (no
  /// adaptive correction): what plain constant compensation integrates [m/s^2].
  Vector3 acceleration_constant_compensated{ 0, 0, 0 };
  Quaternion orientation{ 1, 0, 0, 0 };       ///< sensor -> level frame used for this sample
  Vector3 position_variance{ 0, 0, 0 };       ///< per-axis variance of position_filtered [m^2]
  Vector3 velocity_variance{ 0, 0, 0 };       ///< [m^2/s^2]
  Vector3 wave_position_variance{ 0, 0, 0 };  ///< [m^2]
  Vector3 wave_velocity_variance{ 0, 0, 0 };  ///< [m^2/s^2]
  std::array<AxisState, 3> axes;
  bool calibrated = false;
};

/// What the mean specific force says of the accelerometer's units.
enum class ForceUnits
{
  kUnknown,      ///< less than kUnitsSettle of data
  kPlausible,    ///< within 25 % of the gravity parameter: m/s^2
  kLooksLikeG,   ///< within 25 % of 1: the driver publishes in g, not m/s^2 (REP-145)
  kImplausible,  ///< neither
};
std::string toString(ForceUnits units);
/// Time constant of the mean specific force behind ForceUnits [s].
constexpr double kUnitsAveraging = 10.0;
/// Data needed before ForceUnits is more than kUnknown [s].
constexpr double kUnitsSettle = 1.0;

/// Running counters for diagnostics.
struct CompensatorCounters
{
  std::uint64_t accepted = 0;
  std::uint64_t rejected_non_finite = 0;
  std::uint64_t rejected_bad_quaternion = 0;
  std::uint64_t zero_orientation = 0;  ///< all-zero quaternion taken as "no orientation" (accepted)
  std::uint64_t rejected_duplicate = 0;
  std::uint64_t rejected_out_of_range = 0;
  std::uint64_t rejected_early = 0;
  std::uint64_t held = 0;             ///< samples held while a jump in the stamps was confirmed
  std::uint64_t timing_glitches = 0;  ///< lone stamps dropped: early, or held and then discarded
  std::uint64_t resets_backwards = 0;
  std::uint64_t gap_resets = 0;
  std::uint64_t rate_changes = 0;
  double sample_rate = 0.0;  ///< current estimate [Hz] (TimeBase: line fit of the stamps)
};

class CompensatorImpl;

class Compensator
{
public:
  /// @throws std::invalid_argument if the config does not validate.
  explicit Compensator(const CompensatorConfig& config = CompensatorConfig());
  ~Compensator();
  Compensator(const Compensator&) = delete;
  Compensator& operator=(const Compensator&) = delete;

  /// Replaces the configuration at run time. Invalid configs are refused (false, message in
  /// *why) and the running estimate is untouched. Gains take effect on the next sample;
  /// changes of the FFT window, band or mode restart the period search but keep the bias.
  bool setConfig(const CompensatorConfig& config, std::string* why);
  const CompensatorConfig& config() const;

  /// Processes one sample. Fills *out (if not null) only when the status is kAccepted,
  /// kResetBackwards or kGapReset.
  SampleStatus addSample(const ImuSample& sample, CompensatorOutput* out);

  /// Forgets everything, including the constant bias unless it came from a file.
  void reset();
  /// Starts a new constant-bias calibration window at the next sample.
  void recalibrate();
  /// Sets the constant bias [m/s^2] (level frame) and marks the compensator calibrated.
  /// Returns false (and changes nothing) for a non-finite value or one beyond kMaxConstantBias.
  bool setConstantBias(const Vector3& bias);
  bool calibrated() const;
  Vector3 constantBias() const;
  /// Orientation sensor -> level used when samples carry none (from the calibration window, or
  /// the mean IMU orientation before it disappeared: see levelSource()).
  Quaternion levelOrientation() const;
  LevelSource levelSource() const;
  /// Gyro bias estimated by the gyro attitude, sensor frame [rad/s] (zero until it runs, and
  /// without estimate_gyro_bias).
  Vector3 gyroBias() const;
  /// The accelerometer's units as the mean specific force over the last kUnitsAveraging seconds
  /// shows them, and that mean [m/s^2 if plausible].
  ForceUnits forceUnits() const;
  double meanSpecificForce() const;

  const CompensatorCounters& counters() const;

  /// The spectral wave filter's designs run on the core's design thread (true, the default) or in
  /// the call of the sample they fall due on (false): the outputs are the same; the former keeps
  /// their milliseconds out of addSample (docs/architecture.md).
  void setBackgroundDesigns(bool background);

private:
  std::unique_ptr<CompensatorImpl> impl_;
};

}  // namespace periodic_bias_compensation
