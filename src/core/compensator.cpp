#include "periodic_bias_compensation/core/compensator.h"
#include "background.h"
#include "periodic_bias_compensation/core/broadband_wave.h"
#include "periodic_bias_compensation/core/calibration_window.h"
#include "periodic_bias_compensation/core/drift_observer.h"
#include "periodic_bias_compensation/core/frequency_drift.h"
#include "periodic_bias_compensation/core/harmonic_model.h"
#include "periodic_bias_compensation/core/leveller.h"
#include "periodic_bias_compensation/core/lever_arm.h"
#include "periodic_bias_compensation/core/paper_loop.h"
#include "periodic_bias_compensation/core/parameter_table.h"
#include "periodic_bias_compensation/core/periodic_wave.h"
#include "periodic_bias_compensation/core/turn_detector.h"
#include "periodic_bias_compensation/core/wave_consistency.h"
#include "real_fft.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

namespace periodic_bias_compensation
{
namespace
{
/// Periods of a held lock the FFT window must span before an estimate 20 % away replaces it.
constexpr double kResolvePeriods = 10.0;
/// Highest sample rate planned for [Hz]: a stamp step far below any IMU's period (a driver
/// glitch) must not size FFT windows and tables for an absurd rate.
constexpr double kMaxSampleRate = 10000.0;
/// The period search runs at the IMU rate decimated to at least this many times max_frequency
/// (anti-alias: FrequencyTracker's triangular filter, -25 dB where aliases fold into the band).
constexpr double kDecimatedRateFactor = 5.0;
/// Samples processed again per new sample after the calibration window ends: the window is
/// replayed over the next calibration_duration / (kReplayPerSample - 1) instead of within one
/// sample's call, its outputs held until it has caught up.
constexpr std::size_t kReplayPerSample = 16;

bool isFinite(const Vector3& v)
{
  return v.allFinite();
}

}  // namespace

std::string toString(Mode mode)
{
  return mode == Mode::kPaper ? "paper" : "default";
}

bool modeFromString(const std::string& name, Mode* mode)
{
  if (name == "paper")
    *mode = Mode::kPaper;
  else if (name == "default")
    *mode = Mode::kDefault;
  else
    return false;
  return true;
}

std::string toString(SampleStatus status)
{
  switch (status)
  {
    case SampleStatus::kAccepted:
      return "accepted";
    case SampleStatus::kRejectedNonFinite:
      return "rejected: NaN or Inf in a field";
    case SampleStatus::kRejectedBadQuaternion:
      return "rejected: non-unit orientation quaternion";
    case SampleStatus::kRejectedDuplicate:
      return "rejected: duplicated stamp";
    case SampleStatus::kRejectedOutOfRange:
      return "rejected: acceleration or angular rate out of range";
    case SampleStatus::kRejectedEarly:
      return "rejected: stamp far less than a period after the previous one";
    case SampleStatus::kHeld:
      return "held: stamp does not continue the stream";
    case SampleStatus::kResetBackwards:
      return "reset: stamps went backwards (confirmed)";
    case SampleStatus::kGapReset:
      return "reset: gap in the samples (confirmed)";
  }
  return "unknown";
}

std::string toString(ForceUnits units)
{
  switch (units)
  {
    case ForceUnits::kUnknown:
      return "not known yet";
    case ForceUnits::kPlausible:
      return "m/s^2";
    case ForceUnits::kLooksLikeG:
      return "looks like g, not m/s^2";
    case ForceUnits::kImplausible:
      return "implausible (neither m/s^2 nor g)";
  }
  return "unknown";
}

std::string toString(OutputState state)
{
  return state == OutputState::kCalibrating ? "calibrating (outputs held at zero)" : "tracking";
}

std::string toString(LevelSource source)
{
  switch (source)
  {
    case LevelSource::kNone:
      return "none needed yet";
    case LevelSource::kGravity:
      return "gravity direction of the calibration window";
    case LevelSource::kAttitudeBeforeLoss:
      return "mean IMU orientation before it stopped";
    case LevelSource::kGyroAttitude:
      return "attitude integrated from the gyro";
  }
  return "unknown";
}

bool CompensatorConfig::validate(std::string* why, const std::vector<std::string>& changed) const
{
  const ParameterTable<CompensatorConfig>& table = compensatorParameters();
  if (!checkRanges(table, *this, why))
    return false;
  for (const ParameterOrder& rule : compensatorOrderRules())
    if (!checkOrder(table, rule, *this, changed, why))
      return false;
  return true;
}

/// Estimator of one level axis.
struct AxisEstimator
{
  // Period search.
  std::unique_ptr<FrequencyTracker> tracker;
  bool locked = false;
  double frequency = 0.0;

  // Default mode: the periodic model over the lock's life + the fourth-order drift observer.
  PeriodicWave wave;
  FrequencyDrift frequency_drift;  ///< of the FFT estimates, to extrapolate the lock to now
  DriftObserver drift;             ///< default mode: the slow motion and the bias (paper mode: the bias)
  double residual_variance = 0.0;
  // Default mode with heave_filter: the broadband wave estimate and its share (broadbandWave).
  BroadbandWave broadband;
  WaveConsistency consistency;  ///< default mode: the wave output held to the measured acceleration

  // Paper mode: Eq. 2-7 (stepPaper).
  PaperLoop paper;
  double constant_d_p = 0.0;  ///< mean velocity of the calibration window [m/s] (Table 1)

  double d_v = 0.0, d_p = 0.0;  ///< drift terms of either mode, as published
  double time_since_reset = 0.0;
  double slow_start = -INFINITY;  ///< when the slow channel last started at zero [s]
};

class CompensatorImpl
{
public:
  explicit CompensatorImpl(const CompensatorConfig& config) : config_(config), lever_(config.lever_arm)
  {
    std::string why;
    if (!config_.validate(&why))
      throw std::invalid_argument("invalid compensator configuration: " + why);
    // Starts the planning thread here, not in the call of the sample that first gives the rate,
    // and plans the transforms of fixed size there: the noise floor's and the spectral designs'.
    planInBackground([] { warmFftPlans({ NoiseFloor::kBlock, WienerHeave::kDftSize }); });
    // The wave stages as configured (per axis: vertical or not, the wave band) from the first
    // sample on, calibration window or not (a bias from a file skips it).
    for (int i = 0; i < 3; ++i)
      makeWaveStages(i);
    resetMotion();
  }

  bool setConfig(const CompensatorConfig& config, std::string* why)
  {
    if (!config.validate(why, keys(changes(compensatorParameters(), config_, config))))
      return false;
    const bool restart_search = config.mode != config_.mode || config.fft_window != config_.fft_window ||
                                config.min_frequency != config_.min_frequency ||
                                config.max_frequency != config_.max_frequency || config.harmonics != config_.harmonics;
    const bool restart_heave = config.heave_filter != config_.heave_filter ||
                               config.heave_corner_frequency != config_.heave_corner_frequency ||
                               config.min_frequency != config_.min_frequency;
    if (config.lever_arm != config_.lever_arm)
    {
      lever_.setOffset(config.lever_arm);
      lever_at_window_.setOffset(config.lever_arm);
    }
    config_ = config;
    if (restart_heave)
      for (AxisEstimator& axis : axes_)
      {
        axis.broadband.configure(config_.heave_corner_frequency, config_.min_frequency);
        axis.consistency.setMinFrequency(config_.min_frequency);
      }
    if (restart_search && rate_ > 0.0)
    {
      planned_rate_ = rate_;
      planTrackers(rate_);
      resetMotion();
    }
    return true;
  }

  SampleStatus addSample(const ImuSample& sample, CompensatorOutput* out)
  {
    if (!std::isfinite(sample.t) || !isFinite(sample.specific_force) || !isFinite(sample.angular_rate) ||
        (sample.has_orientation && !sample.orientation.coeffs().allFinite()))
    {
      ++counters_.rejected_non_finite;
      return SampleStatus::kRejectedNonFinite;
    }
    if ((sample.specific_force.cwiseAbs().array() > kMaxSpecificForce).any() ||
        (sample.angular_rate.cwiseAbs().array() > kMaxAngularRate).any())
    {
      ++counters_.rejected_out_of_range;
      return SampleStatus::kRejectedOutOfRange;
    }
    ImuSample s = sample;
    if (s.has_orientation && s.orientation.coeffs().isZero(0.0))
    {
      // IMUs without an AHRS often fill the quaternion with zeros instead of flagging it absent.
      ++counters_.zero_orientation;
      s.has_orientation = false;
    }
    if (s.has_orientation)
    {
      const double norm = s.orientation.norm();
      if (std::abs(1.0 - norm) > config_.max_quaternion_norm_error)
      {
        ++counters_.rejected_bad_quaternion;
        return SampleStatus::kRejectedBadQuaternion;
      }
      s.orientation.normalize();
    }

    time_.setMaxGap(config_.max_gap);
    const StampVerdict verdict = time_.update(s.t);
    if (verdict != StampVerdict::kDuplicate && verdict != StampVerdict::kEarly)
      noteSpecificForce(s.specific_force.norm());
    counters_.timing_glitches = time_.glitches();
    switch (verdict)
    {
      case StampVerdict::kDuplicate:
        ++counters_.rejected_duplicate;
        return SampleStatus::kRejectedDuplicate;
      case StampVerdict::kEarly:
        ++counters_.rejected_early;
        return SampleStatus::kRejectedEarly;
      case StampVerdict::kHeld:
        ++counters_.held;
        held_[time_.heldCount() - 1] = s;
        return SampleStatus::kHeld;
      case StampVerdict::kAccept:
        ++counters_.accepted;
        updateRate();
        step(s, time_.step(), out);
        return SampleStatus::kAccepted;
      case StampVerdict::kRestart:
      case StampVerdict::kGap:
        break;
    }
    // A confirmed jump: the held samples and this one start a new record.
    const bool backwards = verdict == StampVerdict::kRestart;
    if (backwards)
    {
      ++counters_.resets_backwards;
      resetEstimator();
    }
    else
    {
      ++counters_.gap_resets;
      resetMotion();
      calibration_.clear();
    }
    counters_.held -= time_.heldCount() - 1;
    counters_.accepted += time_.heldCount();
    updateRate();
    held_[time_.heldCount() - 1] = s;
    for (int i = 0; i < time_.heldCount(); ++i)
      step(held_[i], time_.heldStep(i), i + 1 == time_.heldCount() ? out : nullptr);
    return backwards ? SampleStatus::kResetBackwards : SampleStatus::kGapReset;
  }

  ForceUnits forceUnits() const
  {
    if (force_time_ < kUnitsSettle)
      return ForceUnits::kUnknown;
    if (std::abs(mean_force_ - config_.gravity) < 0.25 * config_.gravity)
      return ForceUnits::kPlausible;
    if (std::abs(mean_force_ - 1.0) < 0.25)
      return ForceUnits::kLooksLikeG;
    return ForceUnits::kImplausible;
  }
  double meanSpecificForce() const
  {
    return mean_force_;
  }

  /// Forgets everything but the time base (a confirmed restart keeps what confirmed it).
  void resetEstimator()
  {
    planned_rate_ = 0.0;
    leveller_.reset();
    calibration_.clear();
    if (!bias_from_file_)
    {
      calibrated_ = false;
      constant_bias_.setZero();
    }
    for (int i = 0; i < 3; ++i)
    {
      axes_[i] = AxisEstimator();
      axes_[i].drift.setBias(constant_bias_[i]);  // zero unless it came from a file
      makeWaveStages(i);
    }
    resetMotion();
  }

  /// One sample that continues the record, dt [s] after the previous one (0: the first).
  void step(ImuSample s, double dt, CompensatorOutput* out)
  {
    // Paper mode keeps one level frame (the calibration window's gravity direction), as the
    // paper's constant-bias calibration assumes: its loop integrates any tilt change of the gyro's
    // attitude into the bias.
    leveller_.orient(&s, dt, config_.gyro_attitude && config_.mode == Mode::kDefault,
                     { config_.tilt_time_constant, config_.estimate_gyro_bias });
    CompensatorOutput output;
    if (!replay_.empty())
    {
      replay_.push_back({ s, dt });
      continueReplay(&output);
    }
    else if (searchingWindow())
    {
      // The window has ended; its samples and those since wait in it for the replay, each
      // processed meanwhile as during the window (its period search, its lock), outputs held.
      calibration_.add(s, dt, config_.calibration_duration);
      if (s.t >= window_due_)
      {
        finishCalibration(&output);
      }
      else
      {
        output = processHeld(s, dt);
      }
    }
    else if (needsCalibration())
    {
      if (calibration_.empty())
        lever_at_window_ = lever_;
      if (calibration_.add(s, dt, config_.calibration_duration) && planned_rate_ > 0.0)
      {
        endCalibrationWindow(s, dt, &output);
      }
      else
      {
        // Until the bias and level are known the double integral swings with whatever the
        // provisional bias leaves: nothing is claimed, the motion is held at zero.
        output = processHeld(s, dt);
        calibration_.noteLevel(level_);
      }
    }
    else
    {
      output = process(s, dt);
    }
    if (out)
      *out = output;
  }

  void reset()
  {
    time_.reset();
    mean_force_ = force_time_ = force_samples_ = 0.0;
    rate_ = 0.0;
    counters_.sample_rate = 0.0;
    lever_.reset();
    resetEstimator();
  }

  void setBackgroundDesigns(bool background)
  {
    background_designs_ = background;
    for (AxisEstimator& axis : axes_)
      axis.broadband.setBackgroundDesigns(background);
  }

  void recalibrate()
  {
    bias_from_file_ = false;
    calibrated_ = false;
    calibration_.clear();
    endReplay();
  }

  bool setConstantBias(const Vector3& bias)
  {
    if (!isFinite(bias) || (bias.cwiseAbs().array() > kMaxConstantBias).any())
      return false;
    constant_bias_ = bias;
    bias_from_file_ = true;
    calibrated_ = true;
    for (int i = 0; i < 3; ++i)
      axes_[i].drift.setBias(bias[i]);
    return true;
  }

  const CompensatorConfig& config() const
  {
    return config_;
  }
  bool calibrated() const
  {
    return calibrated_;
  }
  Vector3 constantBias() const
  {
    if (config_.mode == Mode::kDefault && calibrated_)
      return Vector3(axes_[0].drift.bias(), axes_[1].drift.bias(), axes_[2].drift.bias());
    return constant_bias_;
  }
  Quaternion levelOrientation() const
  {
    return leveller_.level();
  }
  LevelSource levelSource() const
  {
    return leveller_.source();
  }
  Vector3 gyroBias() const
  {
    return leveller_.gyro().gyroBias();
  }
  const CompensatorCounters& counters() const
  {
    return counters_;
  }

private:
  /// process() of a sample whose output is held (the calibration window and the samples that
  /// wait for its search).
  CompensatorOutput processHeld(const ImuSample& s, double dt)
  {
    CompensatorOutput out = process(s, dt);
    holdOutput(&out);
    return out;
  }

  static void holdOutput(CompensatorOutput* out)
  {
    out->state = OutputState::kCalibrating;
    for (Vector3* v : { &out->position_filtered, &out->velocity_filtered, &out->position_wave, &out->velocity_wave })
      v->setZero();
    for (Vector3* v : { &out->position_variance, &out->velocity_variance, &out->wave_position_variance,
                        &out->wave_velocity_variance })
      v->setConstant(kHeldVariance);
  }

  bool needsCalibration() const
  {
    const bool need_bias = config_.enable_constant && !calibrated_;
    const bool need_level = leveller_.needsCalibration();
    return need_bias || need_level;
  }

  /// Mean |specific force| over kUnitsAveraging (a plain mean until then), by the period.
  void noteSpecificForce(double magnitude)
  {
    const double period = time_.period() > 0.0 ? time_.period() : 0.0;
    force_time_ += period;
    ++force_samples_;
    const double weight = std::max(1.0 - std::exp(-period / kUnitsAveraging), 1.0 / force_samples_);
    mean_force_ += weight * (magnitude - mean_force_);
  }

  /// The rate from the time base; the FFT windows are planned again only when it moved by more
  /// than max_rate_change from the rate they were planned for (FrequencyTracker scales its
  /// frequencies by the rate of its own window's stamps, so a smaller change costs nothing).
  void updateRate()
  {
    rate_ = std::min(time_.rate(), kMaxSampleRate);
    counters_.sample_rate = rate_;
    if (rate_ <= 0.0 || !time_.settled())
      return;
    if (planned_rate_ <= 0.0)
    {
      planned_rate_ = rate_;
      planTrackers(rate_);
    }
    else if (std::abs(rate_ - planned_rate_) > config_.max_rate_change * planned_rate_)
    {
      ++counters_.rate_changes;
      planned_rate_ = rate_;
      planTrackers(rate_);
    }
  }

  void planTrackers(double rate)
  {
    const int window = std::max(16, static_cast<int>(std::lround(config_.fft_window * rate)));
    const int table = std::max(4, static_cast<int>(std::ceil(rate / config_.min_frequency)) + 2);
    // The period search needs rate / M >= 5 x max_frequency, not the IMU's rate: at 100 Hz and
    // 2 Hz the transform is 10 times shorter (docs/algorithm.md, "Period search").
    const int decimation =
        std::clamp(static_cast<int>(rate / (kDecimatedRateFactor * config_.max_frequency)), 1, window / 16);
    for (auto& axis : axes_)
    {
      axis.tracker = std::make_unique<FrequencyTracker>(window, rate, decimation, true);
      axis.locked = false;
      axis.frequency = 0.0;
      axis.paper.setCapacity(table);
      axis.wave.setCapacity(table);
    }
    if (!calibrated_)
    {
      const int samples = static_cast<int>(std::lround(config_.calibration_duration * rate));
      // The window, then the samples that arrive while it is replayed, in one buffer (the
      // replay's, finishCalibration) allocated now, a few per cent over for stamp jitter: growing
      // it would copy megabytes in one sample's call at a high rate.
      const std::size_t expected = static_cast<std::size_t>(samples) + samples / 50 + 16;
      calibration_.reserve(replayCapacity(expected, rate));
      // windowOffset plans the calibration window's transform on the sample that ends the
      // window: the sizes that window can have are planned now, in the background.
      planInBackground([samples] {
        std::vector<int> sizes;
        for (int extra = -2; extra <= 3; ++extra)
          sizes.push_back(fastFftSize(std::max(16, samples + extra)));
        sizes.erase(std::unique(sizes.begin(), sizes.end()), sizes.end());
        warmFftPlans(sizes);
      });
    }
    hop_samples_ = std::max(1, static_cast<int>(std::lround(config_.fft_hop * rate)));
    search_delay_ = std::clamp(static_cast<int>(std::lround(kSearchDelay * rate)), 1, hop_samples_);
    since_analysis_ = 0;
    hop_search_ = {};
  }

  /// Forgets the integrated motion and period search, keeps bias, level and sample rate.
  void resetMotion()
  {
    endReplay();
    turns_.reset();
    for (auto& axis : axes_)
    {
      if (axis.tracker)
        axis.tracker->clear();
      axis.locked = false;
      axis.frequency = 0.0;
      axis.wave.reset(config_.harmonics);
      axis.frequency_drift.clear();
      axis.drift.restartMotion();
      axis.slow_start = now_;
      axis.residual_variance = 0.0;
      // Reset in place: the spectral estimate keeps its buffers (sized for the rate).
      axis.broadband.configure(config_.heave_corner_frequency, config_.min_frequency);
      axis.consistency = WaveConsistency(config_.min_frequency);
      axis.paper.reset();
      axis.d_v = axis.d_p = 0.0;
      axis.time_since_reset = 0.0;
    }
    since_analysis_ = 0;
    hop_search_ = {};
  }

  /// Axis i's broadband wave estimate as configured: z the vertical one, each reading the other
  /// two axes.
  void makeWaveStages(int i)
  {
    axes_[i].broadband = BroadbandWave(i == 2, config_.heave_corner_frequency, config_.min_frequency, true);
    axes_[i].broadband.setBackgroundDesigns(background_designs_);
  }

  /// gyro_attitude: a sample without orientation gets the gyro's, which starts from the IMU's
  /// last orientation if there was one, from the specific force otherwise.
  Vector3 levelAcceleration(const ImuSample& s)
  {
    return leveller_.levelAcceleration(s, config_.gravity);
  }

  /// levelAcceleration() as the calibration window's functions take it.
  std::function<Vector3(const ImuSample&)> level()
  {
    return [this](const ImuSample& sample) { return levelAcceleration(sample); };
  }

  /// Ends the calibration window at its last sample s: the level frame from its mean specific
  /// force, then each level axis's constant bias (windowOffset). A period search over the window
  /// runs on the core's design thread and is taken up kSearchDelay of data later (the
  /// samples meanwhile wait in the window, each processed as during it, outputs held); a window
  /// at rest or a bias from a file finishes at once.
  void endCalibrationWindow(const ImuSample& s, double dt, CompensatorOutput* out)
  {
    bool any_without_orientation = false;
    const Vector3 mean_force = calibration_.meanSpecificForce(&any_without_orientation);
    leveller_.calibrate(mean_force, any_without_orientation);
    window_end_ = calibration_.samples().size();
    window_due_ = s.t;
    if (!bias_from_file_)
    {
      const auto axes = std::make_shared<const std::array<std::vector<double>, 3>>(calibration_.levelAxes(level()));
      const WindowOffsetOptions options = { config_.assume_static_calibration || config_.mode == Mode::kPaper,
                                            rate_,
                                            config_.min_frequency,
                                            config_.max_frequency,
                                            config_.min_peak_ratio,
                                            config_.harmonics };
      if (!options.at_rest)
        window_due_ += kSearchDelay;
      for (int i = 0; i < 3; ++i)
        window_search_[i] = designTask(
            [axes, options, i] {
              WindowSearch result;
              result.offset = windowOffset((*axes)[i], options, &result.frequency);
              return result;
            },
            background_designs_ && !options.at_rest);
    }
    if (window_due_ <= s.t)
    {
      finishCalibration(out);
    }
    else
    {
      *out = processHeld(s, dt);
    }
  }

  /// A window's period search is under way (endCalibrationWindow).
  bool searchingWindow() const
  {
    return window_search_[0].valid();
  }

  /// Takes up the window's constant bias and period, then the window is processed again with them
  /// (only past samples are used: causal), and the samples that came since.
  void finishCalibration(CompensatorOutput* out)
  {
    std::array<FrequencyEstimate, 3> window_frequency;
    if (searchingWindow())
    {
      for (int i = 0; i < 3; ++i)
      {
        // Not made yet: the searches still queued are made here meanwhile.
        const WindowSearch& result = awaitDesign(window_search_[i]);
        if (!bias_from_file_)
        {
          constant_bias_[i] = result.offset;
          window_frequency[i] = result.frequency;
        }
      }
    }
    calibrated_ = true;
    for (int i = 0; i < 3; ++i)
      axes_[i].drift.setBias(constant_bias_[i]);
    if (config_.mode == Mode::kPaper)
    {
      // The window alone: a paper-mode window is taken up at its last sample.
      const Vector3 drift = calibration_.constantPositionDrift(level(), constant_bias_);
      for (int i = 0; i < 3; ++i)
        axes_[i].constant_d_p = drift[i];
    }
    const std::size_t window_end = window_end_;  // resetMotion drops it with the replay
    resetMotion();
    // The window's period is known by now: the replay models it from the first sample on, so
    // that no wave motion leaks into the slow channel while the sliding FFT fills up again.
    for (int i = 0; i < 3; ++i)
      if (window_frequency[i].locked && config_.enable_periodic)
      {
        axes_[i].locked = true;
        axes_[i].frequency = window_frequency[i].frequency;
      }
    // The lever arm's tilt means are no part of the calibration: they go over the replayed
    // samples again from where they stood at the window's first, so they see each one once.
    lever_ = lever_at_window_;
    replay_ = calibration_.take();
    window_end_ = window_end;
    replay_.reserve(replayCapacity(window_end_, rate_));
    replayed_ = 0;
    continueReplay(out);
  }

  /// The replay's length for a window of `window` samples at `rate` [Hz]: those, the samples that
  /// arrive while its period search runs, and those that arrive while it catches up.
  static std::size_t replayCapacity(std::size_t window, double rate)
  {
    const std::size_t queued = window + static_cast<std::size_t>(std::ceil(kSearchDelay * rate)) + 1;
    return queued + queued / (kReplayPerSample - 1) + kReplayPerSample;
  }

  /// The next kReplayPerSample samples of the replay: the window's, then those that arrived
  /// while it ran, each processed as it would have been had the window been replayed at once;
  /// *out: the last one's output, held until the replay has caught up.
  void continueReplay(CompensatorOutput* out)
  {
    const std::size_t end = std::min(replay_.size(), replayed_ + kReplayPerSample);
    for (; replayed_ < end; ++replayed_)
    {
      *out = process(replay_[replayed_].sample, replay_[replayed_].dt);
      if (replayed_ + 1 == window_end_)
        restartSlowMotion(out);
    }
    if (replayed_ < replay_.size())
      holdOutput(out);
    else
      endReplay();
  }

  /// The replay is over, or dropped (a reset or recalibration during it or during the window's
  /// period search): nothing is queued.
  void endReplay()
  {
    replay_.clear();
    replayed_ = window_end_ = 0;
    window_search_ = {};
  }

  /// At the calibration window's last sample, as it is processed again. The replay's harmonic
  /// models filled over their first period, and the observer took that period's wave as slow
  /// motion: its position and velocity restart here, with the bias it learned (outputs held at
  /// zero until the replay has caught up).
  void restartSlowMotion(CompensatorOutput* out)
  {
    if (config_.mode != Mode::kDefault)
      return;
    for (int i = 0; i < 3; ++i)
    {
      axes_[i].drift.restartPosition();
      axes_[i].slow_start = now_;
      out->position_filtered[i] = out->velocity_filtered[i] = 0.0;
    }
  }

  CompensatorOutput process(const ImuSample& s, double dt)
  {
    CompensatorOutput out;
    out.t = s.t;
    now_ = s.t;
    out.orientation = s.has_orientation ? s.orientation : leveller_.level();
    const LeverArmOutput lever = lever_.update(out.orientation, dt);
    const Vector3 a = levelAcceleration(s);
    level_ = a;
    turns_.update(headingOf(out.orientation), (out.orientation * s.angular_rate).z(), dt, s.has_orientation);

    // Until the window ends the bias is provisional: the running mean of the level acceleration.
    if (!calibrated_ && config_.enable_constant)
    {
      const Vector3 provisional = calibration_.provisionalBias(a);
      for (int i = 0; i < 3; ++i)
        axes_[i].drift.setBias(provisional[i]);
    }

    // Every hop_samples_ the period searches of the three axes start, on the core's design thread;
    // search_delay_ samples later they are taken up (before the next ones start).
    ++since_analysis_;
    const bool take_up = since_analysis_ == search_delay_ && hop_search_.valid();
    const bool analyse = since_analysis_ >= hop_samples_;
    if (analyse)
      since_analysis_ = 0;
    std::array<std::function<FrequencySearch()>, 3> searches;

    for (int i = 0; i < 3; ++i)
    {
      AxisEstimator& axis = axes_[i];
      const double bias = config_.enable_constant
                              ? (config_.mode == Mode::kPaper && calibrated_ ? constant_bias_[i] : axis.drift.bias())
                              : 0.0;
      const double compensated = a[i] - bias;
      axis.time_since_reset += dt;
      if (axis.tracker)
      {
        // Default mode: less the calibrated offset only, as the harmonic model (the drift
        // observer's bias follows acceleration up to about 1 / (2 pi drift_time_constant), and
        // taking it off would shape the spectrum there).
        axis.tracker->push(config_.mode == Mode::kDefault
                               ? a[i] - (calibrated_ && config_.enable_constant ? constant_bias_[i] : 0.0)
                               : compensated,
                           s.t);
        if (take_up && config_.enable_periodic)
          updateFrequency(axis, awaitDesign(hop_search_)[i]);
        if (analyse && config_.enable_periodic)
          searches[i] = search(axis);
      }
      AxisState& state = out.axes[i];
      if (config_.mode == Mode::kDefault)
        stepDefault(axis, a[i], compensated, dt, i, &out);
      else
        stepPaper(axis, compensated, dt, i, &out);
      state.constant_bias = bias;
      state.frequency = axis.locked ? axis.frequency : 0.0;
      state.locked = axis.locked;
      state.period_samples = axis.locked && rate_ > 0.0 ? rate_ / axis.frequency : 0.0;
      state.d_v = axis.d_v;
      state.d_p = axis.d_p;
      out.acceleration_level[i] = compensated;
      out.acceleration_constant_compensated[i] = a[i] - (config_.enable_constant ? constant_bias_[i] : 0.0);
    }
    if (take_up)
      hop_search_ = {};
    if (searches[0])
    {
      hop_search_ = designTask(
          [searches] {
            std::array<FrequencySearch, 3> found;
            for (int i = 0; i < 3; ++i)
              found[i] = searches[i]();
            return found;
          },
          background_designs_);
      search_time_ = now_;
    }
    // Default mode: its wave outputs estimate the IMU's wave band, of which R r's is taken off.
    // Paper mode describes the IMU itself, as in the paper.
    if (config_.mode == Mode::kDefault)
    {
      out.position_wave -= lever.position;
      out.velocity_wave -= lever.velocity;
    }
    out.calibrated = calibrated_;
    out.state = OutputState::kTracking;
    return out;
  }

  /// The period search of the hop that ends at this sample, as a task (taken up search_delay_
  /// samples later by updateFrequency()).
  std::function<FrequencySearch()> search(AxisEstimator& axis)
  {
    const double f_max = std::min(config_.max_frequency, 0.45 * rate_);
    // The whole window finds long periods (a swell); a period that also fits three times in the
    // newest kRecentFftWindow seconds is taken from those: a drifting encounter frequency is followed
    // with less lag.
    // Paper mode keeps the newest kRecentFftWindow seconds alone (its results before the 60 s
    // window): its loop needs the period as it is now, and on the x-io oscillation rig the whole
    // window's dominant period moved its end error from 0.021 to 2.6 m.
    const int recent = static_cast<int>(kRecentFftWindow * rate_);
    return axis.tracker->searchTask(config_.min_frequency, f_max, config_.min_peak_ratio, recent,
                                    config_.mode == Mode::kDefault);
  }

  /// Takes up a period search made over the window as it stood at search_time_.
  void updateFrequency(AxisEstimator& axis, const FrequencySearch& found)
  {
    const FrequencyEstimate& estimate = found.estimate;
    const int span_samples = found.span_samples;
    const double span = span_samples / rate_;
    // Only estimates over a span that no longer grows go into the drift regression.
    const bool whole_span = found.full || span_samples < found.samples;
    if (!estimate.locked)
    {
      // A window shorter than three periods of a held lock (seeded at the end of calibration)
      // cannot disprove it yet.
      const bool too_short = axis.locked && found.samples < 3.0 * rate_ / axis.frequency;
      if (axis.locked && !too_short)
        axis.wave.retire();
      axis.locked = axis.locked && too_short;
      return;
    }
    const bool jump = !axis.locked || std::abs(estimate.frequency - axis.frequency) > 0.2 * axis.frequency;
    // Nor can a filling window move a held lock by more than 20 % before it spans kResolvePeriods
    // of it (its resolution, 1 / span, is then a tenth of the lock's frequency or finer).
    if (jump && axis.locked && !found.full && found.samples < kResolvePeriods * rate_ / axis.frequency)
      return;
    // A new horizontal lock is fitted to the last period of input: within a period of a turn that
    // holds the turn's centripetal acceleration, which the model would then describe as a wave.
    // (The time since the last yaw as it was at the search's last sample, or negative.)
    if (jump && config_.mode == Mode::kDefault && &axis != &axes_[2] &&
        turns_.sinceYaw() - (now_ - search_time_) < std::max(1.0 / estimate.frequency, config_.harmonic_memory))
      return;
    axis.locked = true;
    axis.frequency = estimate.frequency;
    if (jump)
    {
      axis.frequency_drift.clear();
      axis.wave.start(axis.frequency, rate_, config_.harmonic_memory, config_.harmonics, config_.mode == Mode::kDefault,
                      now_ - axis.slow_start);
      // The slow channel integrated the wave while nothing modelled it: the new model takes that
      // velocity over, by its share of the wave output.
      const double broadband = config_.heave_filter && config_.enable_periodic ? axis.broadband.weight() : 0.0;
      axis.drift.shiftVelocity(-(1.0 - broadband) * axis.wave.startVelocity());
    }
    axis.frequency_drift.add(search_time_, axis.frequency, span, whole_span, config_.fft_hop);
  }

  /// Default mode with heave_filter: the broadband wave estimate of axis i (BroadbandWave),
  /// blended into the harmonic model's wave output by its share. A horizontal axis takes a share
  /// only when the TurnDetector allows it.
  BroadbandWaveOutput broadbandWave(AxisEstimator& axis, int i, double raw, double residual, double dt, double* wave_a,
                                    double* wave_x, double* wave_v)
  {
    BroadbandWaveInput in;
    in.raw = raw;
    // The measured acceleration less the calibrated offset (fixed once calibrated, so no loop with
    // the drift observer): gravity mismatch and bias are no step into the filters at their start.
    in.offset_free = offsetFree(raw, i);
    // The other axes, in the order x, y, z: every axis moves with the same sea.
    for (int j = 0, c = 0; j < 3; ++j)
      if (j != i)
        in.companions[c++] = offsetFree(level_[j], j);
    in.residual = residual;
    in.harmonic_position = *wave_x;
    in.locked = axis.locked;
    in.frequency = axis.frequency;
    in.allowed = turns_.horizontalShareAllowed();
    in.manoeuvre = turns_.recordManoeuvre();
    in.turning = turns_.turned();
    in.dt = dt;
    in.rate = rate_;
    in.rate_settled = time_.settled();
    const BroadbandWaveOutput out = axis.broadband.update(in);
    *wave_a += out.weight * (out.estimate.acceleration - *wave_a);
    *wave_x += out.weight * (out.estimate.position - *wave_x);
    *wave_v += out.weight * (out.estimate.velocity - *wave_v);
    return out;
  }

  /// The level acceleration of axis i less the calibrated constant offset (none before
  /// calibration).
  double offsetFree(double raw, int i) const
  {
    return raw - (calibrated_ ? constant_bias_[i] : 0.0);
  }

  /// Default mode: the periodic acceleration is tracked by a harmonic estimator at the tracked
  /// frequency (its displacement is obtained in closed form, drift free); what is left feeds a
  /// fourth-order observer whose position is pulled to zero mean with time constant
  /// drift_time_constant, its integral states being the bias and its rate of change.
  void stepDefault(AxisEstimator& axis, double raw, double compensated, double dt, int i, CompensatorOutput* out)
  {
    double wave_a = 0.0, wave_x = 0.0, wave_v = 0.0, variance_factor = 0.0, velocity_variance_factor = 0.0;
    double residual = compensated;  // what the harmonic model leaves of the acceleration
    if (axis.locked && config_.enable_periodic)
    {
      // The FFT reports the frequency at the centre of its window; a drifting encounter
      // frequency is extrapolated from there to now (FrequencyDrift).
      const double frequency = axis.frequency_drift.at(now_, axis.frequency, config_.min_frequency);
      // Fitted to the acceleration less the calibrated offset, not less the drift observer's
      // moving bias: the model's own constant follows slow bias, and the observer's bias, which
      // follows acceleration up to about 1 / (2 pi drift_time_constant), stays out of its residual.
      const double lambda = std::exp(-dt / config_.harmonic_memory);
      const PeriodicWaveOutput model = axis.wave.update(offsetFree(raw, i), frequency, dt, rate_, lambda);
      residual = model.residual;
      const double beta = 1.0 - lambda;
      axis.residual_variance = (1.0 - beta) * axis.residual_variance + beta * residual * residual;
      wave_a = model.acceleration;
      wave_x = model.position;
      wave_v = model.velocity;
      variance_factor = model.position_variance_factor;
      velocity_variance_factor = model.velocity_variance_factor;
    }
    else
    {
      axis.wave.push(offsetFree(raw, i));
      if (dt > 0.0)
      {
        const double beta = 1.0 - std::exp(-dt / config_.harmonic_memory);
        axis.residual_variance = (1.0 - beta) * axis.residual_variance + beta * compensated * compensated;
      }
    }
    axis.wave.fade(dt, &wave_a, &wave_x, &wave_v);

    BroadbandWaveOutput broadband;
    if (config_.heave_filter && config_.enable_periodic)
    {
      broadband = broadbandWave(axis, i, raw, residual, dt, &wave_a, &wave_x, &wave_v);
      // No more wave than the measured acceleration shows (a model describing a motion that has
      // stopped fades out); the slow channel then takes the measured acceleration itself.
      const double consistent = axis.consistency.update(offsetFree(raw, i), wave_v, axis.broadband.noiseVariance(), dt);
      wave_a *= consistent;
      wave_x *= consistent;
      wave_v *= consistent;
    }

    // The slow motion: what the wave model leaves, through the drift observer.
    axis.drift.update(raw - wave_a, dt, config_.drift_time_constant, config_.enable_constant,
                      calibrated_ && config_.enable_constant);
    axis.d_v = axis.drift.velocityCorrection();
    axis.d_p = axis.drift.positionCorrection();

    out->position_filtered[i] = axis.drift.position();
    out->velocity_filtered[i] = axis.drift.velocity();
    out->position_wave[i] = wave_x;
    out->velocity_wave[i] = wave_v;
    out->axes[i].periodic_bias = wave_a;
    DriftObserver::noiseVariances(axis.residual_variance, rate_, config_.drift_time_constant,
                                  &out->position_variance[i], &out->velocity_variance[i]);
    // The blend's variance (broadbandWave), errors taken as independent: the harmonic model's own
    // noise plus what it misses of the wave (all of it while it has no lock).
    const double harmonic_share = (1.0 - broadband.weight) * (1.0 - broadband.weight);
    const double broadband_share = broadband.weight * broadband.weight;
    out->wave_position_variance[i] =
        harmonic_share * (axis.residual_variance * variance_factor + broadband.harmonic_miss_variance) +
        broadband_share * broadband.position_variance;
    out->wave_velocity_variance[i] = harmonic_share * (axis.residual_variance * velocity_variance_factor +
                                                       broadband.harmonic_miss_velocity_variance) +
                                     broadband_share * broadband.velocity_variance;
  }

  /// Paper mode, Eq. 1-7 with the decisions of docs/algorithm.md: integrals on the corrected
  /// values, d_v and d_p are the corrections over one period spread over its L steps, the
  /// "peaks" are the extremes of the corrected signal's table over the last period.
  void stepPaper(AxisEstimator& axis, double compensated, double dt, int i, CompensatorOutput* out)
  {
    PaperStep in;
    in.acceleration = compensated;
    in.dt = dt;
    const int period = axis.locked && rate_ > 0.0 ? static_cast<int>(std::lround(rate_ / axis.frequency)) : 0;
    out->axes[i].period_too_short = config_.enable_periodic && axis.locked && period < kMinPaperPeriod;
    in.period = config_.enable_periodic ? period : 0;
    in.constant_drift = config_.enable_constant && calibrated_ ? axis.constant_d_p : 0.0;
    in.memory = config_.harmonic_memory;
    in.time_since_reset = axis.time_since_reset;
    const PaperOutput paper = axis.paper.step(in, config_.gains[i]);
    axis.d_v = paper.d_v;
    axis.d_p = paper.d_p;
    out->position_filtered[i] = paper.position_filtered;
    out->velocity_filtered[i] = paper.velocity_filtered;
    out->position_wave[i] = paper.position_wave;
    out->velocity_wave[i] = paper.velocity_wave;
    out->axes[i].periodic_bias = paper.periodic_bias;
    out->position_variance[i] = out->wave_position_variance[i] = paper.position_variance;
    out->velocity_variance[i] = out->wave_velocity_variance[i] = paper.velocity_variance;
  }

  CompensatorConfig config_;
  CompensatorCounters counters_;
  std::array<AxisEstimator, 3> axes_;
  TimeBase time_;
  double mean_force_ = 0.0;  ///< mean |specific force| (noteSpecificForce) [m/s^2]
  double force_time_ = 0.0;  ///< data behind it [s]
  double force_samples_ = 0.0;
  std::array<ImuSample, kConfirmSamples> held_;    ///< samples held while a jump is confirmed
  std::vector<CalibrationWindow::Sample> replay_;  ///< the ended window's samples and those since
  std::size_t window_end_ = 0;                     ///< samples of the ended window (of replay_, the first ones)
  std::size_t replayed_ = 0;                       ///< of replay_ processed again
  /// A window's constant bias and dominant frequency (windowOffset).
  struct WindowSearch
  {
    double offset = 0.0;
    FrequencyEstimate frequency;
  };
  std::array<std::shared_future<WindowSearch>, 3> window_search_;  ///< per level axis, while it runs
  double window_due_ = 0.0;                                        ///< data time at which the search is taken up [s]
  double rate_ = 0.0;                                              ///< sample rate [Hz] (time_)
  double planned_rate_ = 0.0;                                      ///< rate the FFT windows were planned for [Hz]
  int hop_samples_ = 1;
  int since_analysis_ = 0;
  int search_delay_ = 1;                                           ///< kSearchDelay in samples, 1..hop_samples_
  std::shared_future<std::array<FrequencySearch, 3>> hop_search_;  ///< the last hop's, until taken up
  double search_time_ = 0.0;                                       ///< the last hop's sample time [s]
  double now_ = 0.0;                                               ///< time of the sample being processed [s]
  Vector3 level_ = Vector3::Zero();                                ///< its level acceleration [m/s^2]
  TurnDetector turns_;  ///< turns told from the yaw a sea induces (wave estimate)

  Leveller leveller_;
  LeverArm lever_;            ///< the IMU's offset taken off the wave outputs
  LeverArm lever_at_window_;  ///< lever_ before the calibration window's first sample

  bool background_designs_ = true;  ///< setBackgroundDesigns
  bool calibrated_ = false;
  bool bias_from_file_ = false;
  Vector3 constant_bias_ = Vector3::Zero();
  CalibrationWindow calibration_;
};

Compensator::Compensator(const CompensatorConfig& config) : impl_(std::make_unique<CompensatorImpl>(config))
{
}
Compensator::~Compensator() = default;

bool Compensator::setConfig(const CompensatorConfig& config, std::string* why)
{
  return impl_->setConfig(config, why);
}
const CompensatorConfig& Compensator::config() const
{
  return impl_->config();
}
SampleStatus Compensator::addSample(const ImuSample& sample, CompensatorOutput* out)
{
  return impl_->addSample(sample, out);
}
void Compensator::reset()
{
  impl_->reset();
}
void Compensator::setBackgroundDesigns(bool background)
{
  impl_->setBackgroundDesigns(background);
}
void Compensator::recalibrate()
{
  impl_->recalibrate();
}
bool Compensator::setConstantBias(const Vector3& bias)
{
  return impl_->setConstantBias(bias);
}
bool Compensator::calibrated() const
{
  return impl_->calibrated();
}
Vector3 Compensator::constantBias() const
{
  return impl_->constantBias();
}
Quaternion Compensator::levelOrientation() const
{
  return impl_->levelOrientation();
}
LevelSource Compensator::levelSource() const
{
  return impl_->levelSource();
}
Vector3 Compensator::gyroBias() const
{
  return impl_->gyroBias();
}
ForceUnits Compensator::forceUnits() const
{
  return impl_->forceUnits();
}
double Compensator::meanSpecificForce() const
{
  return impl_->meanSpecificForce();
}
const CompensatorCounters& Compensator::counters() const
{
  return impl_->counters();
}

}  // namespace periodic_bias_compensation
