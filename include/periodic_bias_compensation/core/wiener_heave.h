// Heave from the measured spectrum: a causal Wiener filter designed from the vertical
// acceleration itself (estimation core, no ROS).
//
// A fixed double integrator with drift removal (HeaveFilter) must put its corner well below the
// wave band, and everything between the corner and the band, a bias random walk above all, is
// doubly integrated into heave. The sea's own spectrum says where heave is: a wind sea or a
// swell has almost no energy below about 0.6 times its peak frequency. WienerHeave therefore
//
//  1. low-passes the acceleration (two moving averages of D samples, D dt ~ 0.25 s) and keeps it
//     at the full rate, and every D-th value at the design rate 1 / (D dt) ~ 4 Hz;
//  2. every kRedesignInterval (kEarlyRedesignInterval while the record is shorter than
//     kEarlyRecord: each design from a short record improves on the last by more), from the last
//     kDesignWindow of design-rate values: a spectrum, Welch's (Hann segments of kSegment, half
//     overlap; the whole record as one segment while it is shorter than two) less what a bin
//     may owe through the window to the lines below min_frequency; on the vertical axis, once
//     the record holds two segments, Burg's maximum-entropy estimate instead (an autoregressive
//     model of kMaxOrder, with the white-noise floor under it), whose resolution separates a
//     slow bias line from a swell without a window's main lobe (on a horizontal axis too while
//     the window holds no manoeuvre, noteManoeuvre()), and on a shorter vertical record
//     whose window cannot resolve its displacement peak from zero frequency (a swell in the
//     first minute) Burg's estimate of order kShortOrder times its length, its band started
//     kEdgeResolution / T above min_frequency and above the skirt of a line below; the wave
//     acceleration in it (the spectrum less three times the white-noise floor, nothing below
//     min_frequency), and from that the cross-correlation between displacement (acceleration /
//     -omega^2) and the low-passed acceleration, and the acceleration's autocorrelation from the
//     same spectrum;
//  3. solves the Wiener-Hopf (normal) equations for a causal FIR over a span of six peak
//     periods (kSpanPeriods, kMinSpan..kMaxSpan; no longer than the input held since reset())
//     at the design rate, for displacement and velocity (Levinson recursion);
//  4. applies the FIR at every sample to the low-passed values D samples apart ending at that
//     sample, so the output has the input's rate; a new design fades in over kDesignFade. Above
//     kMaxPhases samples per design-rate period (256 Hz), the values are kept, and the FIR
//     applied, at kMaxPhases phases of the period only (every 4 ms or less), and the samples
//     between take the last two such outputs extrapolated: the full-rate histories would be
//     megabytes (24 MB at 2.8 kHz) read cold at every sample, for outputs low-passed to a few
//     hertz that a straight line follows over 4 ms.
//
// With companions (the other two level axes' accelerations, given at every sample) and no
// manoeuvre in the record, a second design reads all three inputs: a sea moves every axis with the
// same waves, and the other axes' accelerations say what this axis's noise and bias wander hide
// (on a long-crested sea surge and heave are one wave seen twice). On the vertical axis, once the
// record holds kCrossSegments Welch segments, its spectral matrix is the own estimate above on the
// diagonal and Welch's cross-spectra beside it, each shrunk by how far its coherence stands above
// what K segments of unrelated inputs show (weight (C - 2 / K) / (1 - 2 / K), none below). On a
// horizontal axis, once the record holds kHorizontalCrossSegments and the own design holds a sea
// (kCompanionSea), it is Welch's matrix alone, the own wave from Welch's density of the same
// segments, with white noise of kLoading added to every input and the companions'
// cross-spectra bounded per bin by the own wave; where that design is not taken, the vertical
// axis's kind is tried. The other inputs' FIRs are kCrossSpan long; the block-Toeplitz normal
// equations are solved by a multichannel Levinson recursion, and a design is taken when its
// expected error is below the own design's.
//
// Below min_frequency and under the noise floor the filter passes nothing, so bias wander and
// white noise are weighted by what the spectrum holds, not by a fixed corner. Until the first
// design (kFirstDesign of data, kRestartDesign after restartRecord()) it has no output: the owner
// uses another estimate.
//
// A design is made from the record as it stands on the sample it falls due and is applied
// kDesignDelay of data later: on the core's design thread, so that the sample's call does not pay
// the milliseconds a design costs (or on the calling thread, setBackgroundDesigns(false)). The
// outputs are the same sample for sample either way: the sample that takes a design up is set by
// the data, and waits for the design if the thread has not finished it, making the designs queued
// behind it (other axes') meanwhile, so that offline two designs are made at once. A gap in the
// companions is the exception: the design that follows it is made and taken up in the gap's call.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <array>
#include <complex>
#include <future>
#include <limits>
#include <memory>
#include <vector>

#include "periodic_bias_compensation/core/unshared_transform.h"
#include "periodic_bias_compensation/core/zeroed_buffer.h"

namespace periodic_bias_compensation
{
/// One step's output of WienerHeave.
struct WienerHeaveOutput
{
  bool valid = false;                    ///< false until the first design, and while it is stale
  double position = 0.0;                 ///< wave displacement [m]
  double velocity = 0.0;                 ///< [m/s]
  double error_variance = 0.0;           ///< the design's expected displacement error variance [m^2]
  double velocity_error_variance = 0.0;  ///< [m^2/s^2]
  /// The displacement variance of the wave in the design's spectrum (0 when it holds none) [m^2].
  double wave_variance = 0.0;
};

class WienerHeave
{
public:
  static constexpr double kDesignPeriod = 0.25;          ///< target spacing of the design rate [s]
  static constexpr double kFirstDesign = 20.0;           ///< data before the first design [s]
  static constexpr double kRestartDesign = 50.0;         ///< of a record restartRecord() began [s]
  static constexpr double kDesignWindow = 600.0;         ///< data a design uses at most [s]
  static constexpr double kRedesignInterval = 30.0;      ///< [s]
  static constexpr double kEarlyRedesignInterval = 5.0;  ///< while the record is short [s]
  static constexpr double kEarlyRecord = 300.0;          ///< a record shorter than this is short [s]
  static constexpr int kSegment = 512;                   ///< Welch segment [design-rate samples]
  static constexpr int kMaxOrder = 320;                  ///< of the Burg model [design-rate samples]
  static constexpr int kMinSegment = 80;                 ///< the shortest record designed from
  static constexpr int kDftSize = 2048;                  ///< zero-padded transform of a segment
  static constexpr double kSpanPeriods = 6.0;            ///< FIR span in peak periods
  static constexpr double kMinSpan = 20.0;               ///< [s]
  static constexpr double kMaxSpan = 120.0;              ///< [s]
  static constexpr double kNoiseMargin = 3.0;            ///< multiples of the noise floor taken as noise
  static constexpr double kDesignFade = 2.0;             ///< [s]
  static constexpr double kDesignDelay = 0.3;            ///< from a design's data to its use [s]
  static constexpr double kMinPeriod = 1e-4;             ///< shortest sample period taken (10 kHz) [s]
  static constexpr double kMaxPeriod = 10.0;             ///< longest [s]
  /// Relative change of the sample period that starts the record over (the buffers and the
  /// design are the old rate's) [-].
  static constexpr double kPeriodChange = 0.1;
  /// Phases of the design-rate period at which the low-passed values are kept and the FIR is
  /// applied (every phase at rates up to kMaxPhases / kDesignPeriod) [-].
  static constexpr int kMaxPhases = 64;
  /// A window resolves a displacement peak from zero frequency once the record holds this many of
  /// its cycles [-].
  static constexpr double kResolvedCycles = 3.0;
  /// Burg's order on a short vertical record, a share of its length [-].
  static constexpr double kShortOrder = 0.5;
  /// Width above min_frequency that a short record cannot tell from below it, over its length [-].
  static constexpr double kEdgeResolution = 0.5;
  /// Welch segments the record holds before the other axes are read: coherence from fewer is
  /// mostly chance [-].
  static constexpr int kCrossSegments = 6;
  /// Span of the other inputs' FIRs, and of the own input's in a design that reads them [s].
  static constexpr double kCrossSpan = 60.0;
  /// Welch segments a horizontal record holds before the other axes are read: its design reads
  /// Welch's matrix alone, white noise added, which bears a short record's chance coherence [-].
  static constexpr int kHorizontalCrossSegments = 2;
  /// White noise added to every input of a horizontal design that reads the other axes, a share of
  /// the inputs' mean variance: the taps fit no coherence a few segments hold by chance [-].
  static constexpr double kLoading = 4e-3;
  /// A horizontal axis reads the other axes where its own design holds a sea: its wave this many
  /// times the design's expected error (at rest the others' slow drifts would make one) [-].
  static constexpr double kCompanionSea = 2.0;
  /// The other two level axes' accelerations, as update() takes them.
  using Companions = std::array<double, 2>;

  /// min_frequency [Hz]: the lowest wave frequency; below it nothing is heave. `vertical`: the
  /// record holds no manoeuvre, and Burg's estimate serves its long records and the short ones a
  /// window cannot resolve; a horizontal axis's long records take it while they hold no manoeuvre
  /// (noteManoeuvre()). `companions`: update() is given the other two axes' accelerations too.
  explicit WienerHeave(double min_frequency = 0.04, bool vertical = false, bool companions = false);

  /// Forgets everything; the next sample starts a new record.
  void reset();
  /// The sea as met has changed (the ship turned, so every encounter frequency moved): the
  /// spectrum is measured anew from the next sample. The last design stays applied but is marked
  /// stale (`valid` false) until the first design from the new record, kRestartDesign of it.
  void restartRecord();
  /// The record holds a manoeuvre from now on (a turn, or the horizontal axes blocked): designs
  /// whose window reaches back to it read no companion, and on a horizontal axis take Welch's
  /// estimate, which says what the band owes the manoeuvre's lines below it (an autoregressive
  /// model's peaks fall off too slowly beside them).
  void noteManoeuvre()
  {
    since_manoeuvre_ = 0.0;
  }
  void setMinFrequency(double min_frequency);
  /// Phases of the design-rate period kept (kMaxPhases unless set; at least 1); a value of
  /// kDesignPeriod times the rate or more keeps every sample, the full-rate filter the kept phases
  /// approximate. Starts over (reset()).
  void setMaxPhases(int max_phases);
  /// Designs run on the core's design thread (true, the default) or in the call of the sample
  /// they fall due on (false); the outputs are the same.
  void setBackgroundDesigns(bool background)
  {
    background_ = background;
  }

  /// Takes the vertical acceleration a [m/s^2] (gravity removed), the sample period [s] as the
  /// owner's time base has it (samples are taken one period apart: stamp jitter and a dropped
  /// sample are the time base's concern; 0 while it does not know the rate, and any period
  /// outside kMinPeriod..kMaxPeriod: the sample is not taken; one more than kPeriodChange from the
  /// period the record began with starts it over) and the white-noise density of the
  /// acceleration squared, one-sided [(m/s^2)^2/Hz], used at the next design.
  WienerHeaveOutput update(double a, double period, double noise_density_squared);
  /// The same with the other two axes' level accelerations [m/s^2] (a WienerHeave made with
  /// companions; a sample without them, or with one not finite, is a gap in their records: no
  /// design reads them while its window holds one).
  WienerHeaveOutput update(double a, double period, double noise_density_squared, const Companions& companions);

  /// A design has been made since the last reset() (it may be stale after restartRecord()).
  bool designed() const
  {
    return current_ != nullptr;
  }
  /// The design rate's spacing in samples (0 before the first sample).
  int decimation() const
  {
    return decimation_;
  }
  /// Peak frequency of the displacement spectrum at the last design [Hz] (0: none yet).
  double peakFrequency() const
  {
    return peak_frequency_;
  }
  /// The input the current design's FIR reads, taps times the design rate's spacing [s] (0: no
  /// design yet).
  double span() const
  {
    return current_ ? static_cast<double>(current_->position[0].size()) * decimation_ * dt_ : 0.0;
  }
  /// The current design reads the companions.
  bool readsCompanions() const
  {
    return current_ != nullptr && !current_->position[1].empty();
  }

private:
  /// The own input ([0]) and the companions.
  static constexpr int kChannels = 3;
  /// One input's low-pass and records.
  struct Channel
  {
    // Two moving averages of decimation_ samples.
    std::vector<double> first, second;
    double first_sum = 0.0, second_sum = 0.0;
    // Low-passed values at the kept phases in min(D, max_phases_) rings of ring_length_ (one per
    // kept sample phase modulo D, so that the FIR reads consecutive values); the newest at newest_.
    ZeroedBuffer history;
    // Design-rate values, oldest first, at most kDesignWindow.
    std::vector<double> decimated;
  };
  struct Design
  {
    /// FIR taps per input (a companion's empty: not read): newest first as solved, oldest first
    /// once prepare() has made the design ready for apply().
    std::array<std::vector<double>, kChannels> position;
    std::array<std::vector<double>, kChannels> velocity;
    /// The design window's mean input, taken off first.
    std::array<double, kChannels> mean{};
    /// What the mean adds to each FIR's output (the mean times the taps' sum; prepare()).
    std::array<double, kChannels> position_offset{}, velocity_offset{};
    double error_variance = 0.0;
    double velocity_error_variance = 0.0;
    double wave_variance = 0.0;
    /// Turns the taps oldest first and sets the offsets: the last step of a design.
    void prepare();
  };
  /// How a density of the record was estimated, which decides what is taken as wave in it.
  enum class Estimate
  {
    kWelch,     ///< Welch's: a bin less what it owes the lines below min_frequency through the window
    kBurg,      ///< Burg's: no window; the white-noise floor is put under its density
    kShortBurg  ///< Burg's of a short record: its band also starts kEdgeResolution / T above
                ///< min_frequency and above the skirt of a line below it
  };
  /// The wave in a density estimate of the record.
  struct Wave
  {
    std::vector<double> density;  ///< the estimate's two-sided density (the floor under Burg's)
    std::vector<double> wave;     ///< wave acceleration density per bin (0 outside the band)
    std::vector<double> gain;     ///< the low-pass's power response per bin
    double displacement_variance = 0.0;
    double velocity_variance = 0.0;
    double peak_frequency = 0.0;  ///< of the displacement spectrum [Hz] (0: no wave)
  };
  /// What a design takes from the wave: correlations at lags 0..taps-1 (taps: six periods of the
  /// displacement's peak, kMinSpan..kMaxSpan), empty when it holds no wave.
  struct Statistics
  {
    std::vector<double> autocorrelation;  ///< of the low-passed acceleration
    std::vector<double> r_position;       ///< of displacement with it
    std::vector<double> r_velocity;       ///< of velocity with it
    /// Displacement's cross-spectrum with the low-passed acceleration per bin, E[X conj(U)].
    std::vector<std::complex<double>> cross;
  };
  /// The own input's design-rate values.
  const std::vector<double>& record() const
  {
    return channels_[0].decimated;
  }
  /// Two-sided density of the design-rate values less `mean` [(m/s^2)^2/Hz] at kDftSize / 2 + 1
  /// frequencies: Welch's with Hann segments of `segment` values, half overlap, and in
  /// *response the window's power response relative to its peak at the same frequencies.
  std::vector<double> welch(int segment, double mean, std::vector<double>* response) const;
  /// A Hann window of `segment` values' power response relative to its peak at the same
  /// frequencies.
  std::vector<double> windowResponse(int segment) const;
  /// The same by Burg's method, an autoregressive model of `order` fitted to the whole record
  /// (no window).
  std::vector<double> burg(int order, double mean) const;
  /// The wave acceleration per bin of `density` (`response`: Welch's window response, kWelch
  /// only): less kNoiseMargin times the white-noise floor, nothing below min_frequency, and what
  /// `kind` takes off besides.
  Wave wave(std::vector<double> density, const std::vector<double>& response, double noise_density_squared,
            Estimate kind) const;
  /// The two moving averages' response at omega [rad/s] from its power response `gain`: AA.
  std::complex<double> lowPass(double gain, double omega) const;
  /// The correlations at lags 0..taps-1 of a two-sided (Hermitian) spectrum given per bin times
  /// the bin width, spectrum(k) for k = 0..kDftSize / 2: its inverse transform.
  template <typename Spectrum>
  std::vector<double> correlation(const Spectrum& spectrum, int taps) const;
  Statistics statistics(const Wave& wave) const;
  /// The design that reads the companions too, from the own wave `sea` and its statistics `own`,
  /// into *next (its taps and expected errors); false when the equations are not well posed.
  bool companionDesign(const Wave& sea, const Statistics& own, const std::array<double, kChannels>& mean,
                       Design* next) const;
  /// The design that reads the companions from Welch's matrix alone (the own input's wave
  /// included), white noise of kLoading added to every input and the companions' cross-spectra
  /// bounded by the own wave: a horizontal axis's.
  bool welchCompanionDesign(const std::array<double, kChannels>& mean, double noise_density_squared,
                            Design* next) const;
  using SpectralMatrix = std::array<std::array<std::vector<std::complex<double>>, kChannels>, kChannels>;
  /// Welch's spectral matrix of the inputs less `mean`, S_ab = E[U_a conj(U_b)] two-sided at
  /// kDftSize / 2 + 1 frequencies (Hann segments of kSegment, half overlap), and its *segments.
  SpectralMatrix welchMatrix(const std::array<double, kChannels>& mean, int* segments) const;
  /// Solves the block-Toeplitz normal equations of `taps` per input from `matrix` (the own input's
  /// autocorrelation `own_autocorrelation` where given, else from the matrix), the own input's
  /// wave `sea` and its statistics `own`, white noise of `loading` times the inputs' mean variance
  /// added to each input, the companions' cross-spectra `bounded` by the own wave, into *next (taps
  /// and expected errors); false when not well posed.
  bool solveJoint(const SpectralMatrix& matrix, const std::vector<double>& own_autocorrelation, const Wave& sea,
                  const Statistics& own, int taps, double loading, bool bounded,
                  const std::array<double, kChannels>& mean, Design* next) const;
  /// What a design changes: the new design and its peak frequency (design null: the last one
  /// stays, and its peak).
  struct Outcome
  {
    std::shared_ptr<const Design> design;
    double peak_frequency = 0.0;
  };
  /// A copy of what a design reads (the records, the rate, the flags and the transform), not of
  /// the full-rate histories.
  struct ForDesign
  {
  };
  WienerHeave(const WienerHeave& source, ForDesign);
  Outcome design(double noise_density_squared) const;
  /// Starts a design from the record as it stands, due `delay` samples later (0: made and taken up
  /// in this call).
  void startDesign(double noise_density_squared, long delay);
  /// Waits for the pending design and takes it up.
  void finishDesign();
  WienerHeaveOutput step(double a, double period, double noise_density_squared, const Companions* companions);
  void apply(const Design& d, double* x, double* v) const;

  double min_frequency_;
  bool vertical_;
  int channels_used_;      ///< 1, or kChannels with companions
  double dt_ = 0.0;        ///< the sample period, the owner's latest [s]
  double sized_dt_ = 0.0;  ///< the period the record began with, which sized the buffers [s]
  int decimation_ = 0;
  long samples_ = 0;
  std::array<Channel, kChannels> channels_;
  int ring_length_ = 0;
  int newest_ = 0;               ///< the newest value's place in every channel's history
  int max_phases_ = kMaxPhases;  ///< kept phases of the design-rate period at most
  /// Per sample phase modulo decimation_, its ring, or -1 where its values are not kept.
  std::vector<int> ring_of_phase_;
  /// The last output the FIR made (at a kept phase), to carry to the samples between.
  struct Carried
  {
    long made = 0;    ///< outputs made at kept phases since reset()
    long sample = 0;  ///< samples_ when the last was made
    double position = 0.0, velocity = 0.0;
    /// Each output's change since the one before, per second.
    double position_slope = 0.0, velocity_slope = 0.0;
  } carried_;
  double since_design_ = 0.0;
  /// Data since noteManoeuvre() [s] (infinite: none since reset()).
  double since_manoeuvre_ = std::numeric_limits<double>::infinity();
  /// Data since a sample without (finite) companions [s].
  double since_gap_ = std::numeric_limits<double>::infinity();
  bool stale_ = false;  ///< the design is from a record restartRecord() ended
  // Designs are never changed once made: copies of this object share them.
  std::shared_ptr<const Design> current_, previous_;
  double fade_ = 1.0;  ///< weight of current_ against previous_
  double peak_frequency_ = 0.0;
  /// The transform of the design, made at the first design; a pending design's copy shares it,
  /// and reset() leaves it to that copy.
  UnsharedTransform transform_;
  bool background_ = true;
  /// The design started and not yet taken up (invalid: none), and the count of samples_ that
  /// takes it up.
  std::shared_future<Outcome> pending_;
  long pending_due_ = 0;
  long delay_samples_ = 0;  ///< kDesignDelay in samples at the record's rate
  bool urgent_ = false;     ///< the next design is taken up in the call that starts it
};

}  // namespace periodic_bias_compensation
