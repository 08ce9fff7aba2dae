// Broadband wave motion of one level axis, and its share against the harmonic model (estimation
// core, no ROS).
//
// The harmonic model of the default mode describes one dominant period; a broad sea leaves much
// of the wave out. BroadbandWave estimates the whole wave band instead, from the acceleration less
// the calibrated offset: the spectral (Wiener) estimate once it is designed (WienerHeave, which
// with companions reads the other two level axes too), before that, on the vertical axis only,
// the fixed double integrator (HeaveFilter). The two estimates are blended by inverse variance:
//  - what the harmonic model misses is measured where bias wander is not: its residual
//    acceleration above min_frequency (two first-order high-passes, only against a locked
//    model; on the vertical axis four until the first spectral design, while the fixed filter
//    stands in: it carries everything below the band, and a bias drifting over a minute leaks
//    through two high-passes as centimetres said to be missed), integrated by a second
//    HeaveFilter, its variance less that of the white noise through both (on the vertical axis,
//    whose share may open from the first lock on: through two, the smaller of it and the variance
//    through two leaky integrators, 1 / (s + omega_h)^2, the same band without the drift removal,
//    which rings for a minute after the lock's first samples; less the noise by
//    kMissSignificance times the scatter of its mean square); once that opens the
//    share, the larger of it and what the difference of the two displacements says (its
//    variance less the broadband error: a model locked elsewhere fits the acceleration yet
//    gives the wrong displacement);
//  - the broadband error is its own (the noise through the fixed filter, or the Wiener design's
//    expected error) plus its output below the wave band (two first-order low-passes at half
//    min_frequency), as averaged or as it is now, whichever is larger (bias wander grows faster
//    than a mean follows);
//  - the broadband share V_missed / (V_missed + V_broadband), zero below kMinWeight, is followed
//    with kWeightTime: a narrow sea (the bench) or none (at rest) keeps the harmonic model
//    whatever the bias does; a broad one (JONSWAP) takes the broadband estimate;
//  - the whole of it when the lock lies more than kOffPeak from the peak of the spectral
//    estimate's displacement spectrum and there is a sea: the spectral design holds one (its wave
//    kSeaOverError times its expected error), or the share is open and the broadband output holds
//    one (its mean square kSeaOverError times its error): the lock follows the acceleration's
//    peak, which on a broad sea lies above the displacement's (the spectra are a factor omega^4
//    apart), so the harmonic model misses most of the displacement while both measures of its
//    miss read low (the residual's high-passes take the low frequencies, and the two
//    displacements' errors are not independent);
//  - without a lock (the harmonic model's output is then none), the whole of it once the spectral
//    design holds a sea, taken up with kBlockedFade; horizontally only once the broadband output's
//    mean square is also kSeaOverError times its error.
// While the ship turns, the spectrum is measured anew (WienerHeave::restartRecord); the vertical
// axis crosses over to the fixed filter with WienerHeave::kDesignFade and back once the new record
// gives a design (at once where the blend publishes less than kMinWeight of it). A horizontal
// axis takes the spectral estimate only, and none while the owner says it may not (a ship
// turning, no attitude): its share then fades out with kBlockedFade, and returns as fast.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "periodic_bias_compensation/core/heave_filter.h"
#include "periodic_bias_compensation/core/noise_floor.h"
#include "periodic_bias_compensation/core/wiener_heave.h"

namespace periodic_bias_compensation
{
/// One sample of one axis, as the owner has it.
struct BroadbandWaveInput
{
  double raw = 0.0;          ///< level acceleration, gravity removed [m/s^2]
  double offset_free = 0.0;  ///< raw less the calibrated constant offset (fixed once calibrated)
  /// The other two axes' offset_free, in the order x, y, z without this one (read by the spectral
  /// estimate of a BroadbandWave made with companions).
  WienerHeave::Companions companions{};
  double residual = 0.0;           ///< what the harmonic model leaves of the acceleration [m/s^2]
  double harmonic_position = 0.0;  ///< the harmonic model's wave displacement [m]
  bool locked = false;             ///< the harmonic model has a lock
  double frequency = 0.0;          ///< the lock's frequency [Hz] (with a lock)
  bool allowed = true;             ///< a horizontal axis may take a broadband share now
  /// The horizontal record takes a manoeuvre now (by default whenever the share is not allowed;
  /// the sea's yaw holds the share off but is none).
  bool manoeuvre = true;
  bool turning = false;  ///< the heading has moved: the sea as met changed, its spectrum is measured anew
  double dt = 0.0;       ///< [s] since the previous sample (0: the first)
  double rate = 0.0;     ///< sample rate [Hz] (0: not known yet)
  /// The rate rests on enough of the stream to size the spectral estimate's buffers by (the
  /// owner's time base has settled); until then the spectral estimate takes no sample.
  bool rate_settled = true;
};

struct BroadbandWaveOutput
{
  HeaveOutput estimate;            ///< broadband displacement, velocity, wave-band acceleration
  double weight = 0.0;             ///< its share of the wave output [-]
  double position_variance = 0.0;  ///< of the broadband estimate [m^2]
  double velocity_variance = 0.0;  ///< [m^2/s^2]
  /// What the harmonic model's displacement misses, as a variance [m^2]: with a lock the larger of
  /// the measured miss and the excess of its difference from the broadband estimate; without one
  /// (its output faded to zero) the whole wave, the broadband estimate's mean square.
  double harmonic_miss_variance = 0.0;
  double harmonic_miss_velocity_variance = 0.0;  ///< [m^2/s^2]
};

class BroadbandWave
{
public:
  /// Time constant of the variances that weigh the broadband estimate [s].
  static constexpr double kAveraging = 60.0;
  /// Time from the start during which a horizontal axis's miss is not measured from the residual
  /// [s]: the measure still holds the lock's first transients (about 1.4 cm said missed on a
  /// sinusoid), and a narrow sea would open the share on them. Its share opens then only when the
  /// spectral design holds a sea away from the lock (nor on a design without a lock: a short
  /// record of a hand's or a rig's motion reads as a sea).
  static constexpr double kResidualSettling = 60.0;
  /// Smallest share; below it, none [-]: a few percent gain little and add that share of
  /// everything below the wave band, which can be metres of bias wander.
  static constexpr double kMinWeight = 0.1;
  /// Scatters of the noise's mean square beyond which the harmonic model's residual is a miss [-].
  static constexpr double kMissSignificance = 2.0;
  /// Time constant with which the share follows its target [s]: never a step.
  static constexpr double kWeightTime = 2.0;
  /// Time constant with which a horizontal share fades out when it is no longer allowed, and
  /// back in once it is again [s]: the hold, not the target, moved it.
  static constexpr double kBlockedFade = 0.3;
  /// Distance from its target within which a returning share is back [-]; then kWeightTime again.
  static constexpr double kReturned = 0.05;
  /// Lowest wave frequency relative to min_frequency (the lowest peak searched): a wind sea or a
  /// swell holds almost no energy below 0.6 times its peak frequency [-].
  static constexpr double kBandEdge = 0.6;
  /// Relative distance of the lock from the displacement spectrum's peak beyond which an open
  /// share becomes the whole wave output [-].
  static constexpr double kOffPeak = 0.1;
  /// ... and only when the broadband displacement's mean square exceeds its error this many times
  /// (a sea, not the noise and bias wander it passes at rest) [-].
  static constexpr double kSeaOverError = 2.0;

  /// vertical: the fixed filter stands in until the spectral estimate is designed. companions:
  /// the spectral estimate reads the other axes' accelerations too (WienerHeave).
  explicit BroadbandWave(bool vertical = true, double corner_frequency = 0.015, double min_frequency = 0.05,
                         bool companions = false);

  /// Forgets everything (filters, variances, share).
  void reset();
  void configure(double corner_frequency, double min_frequency);
  /// WienerHeave::setBackgroundDesigns of the spectral estimate.
  void setBackgroundDesigns(bool background)
  {
    spectral_.setBackgroundDesigns(background);
  }

  BroadbandWaveOutput update(const BroadbandWaveInput& in);
  /// The last update's share of the wave output [-].
  double weight() const
  {
    return weight_;
  }

  /// White-noise density of the acceleration squared, one-sided [(m/s^2)^2/Hz] at `rate`: from
  /// first differences, or from the upper half of the spectrum (NoiseFloor) where that is lower
  /// (lines above the wave band, an engine's vibration, inflate the first differences).
  double noiseDensitySquared(double rate) const
  {
    return 2.0 * noiseVariance() * (rate > 0.0 ? 1.0 / rate : 0.0);
  }
  /// The same as a variance per sample [(m/s^2)^2].
  double noiseVariance() const
  {
    return noise_blocks_ > 0.0 ? std::min(noise_variance_, line_free_variance_) : noise_variance_;
  }

private:
  struct HighPass
  {
    double input = 0.0, output = 0.0;
  };
  bool vertical_;
  double min_frequency_;
  bool companions_;
  HeaveFilter fixed_;
  WienerHeave spectral_;
  /// The ways the harmonic model's residual is measured above the band edge.
  static constexpr std::size_t kTwoPasses = 0;
  static constexpr std::size_t kFourPasses = 1;      ///< the vertical axis until the first design only
  static constexpr std::size_t kTwoPassesLeaky = 2;  ///< two passes, integrated without drift removal
  /// The high-passes of the residual: [0], [1] for both ways, [2], [3] for four passes.
  std::array<HighPass, 4> residual_high_{};
  std::array<HeaveFilter, 2> residual_heave_;  ///< the residual's displacement, each way
  std::array<double, 2> residual_leaky_{};     ///< the leaky integrators' states (kTwoPassesLeaky)
  std::array<double, 3> residual_band_variance_{};
  double difference_variance_ = 0.0;  ///< of harmonic less broadband displacement, since the lock
  double residual_samples_ = 0.0;     ///< in residual_band_variance_ since the lock
  double samples_ = 0.0;              ///< in noise_variance_ and low_variance_
  double elapsed_ = 0.0;              ///< time since the start [s]
  double weight_ = 0.0;
  bool returning_ = false;       ///< a horizontal share held off has not yet returned to its target
  double spectral_share_ = 0.0;  ///< of the spectral estimate against the fixed filter
  std::array<double, 2> low_{};  ///< the broadband output below the wave band
  double low_variance_ = 0.0;
  double wave_variance_ = 0.0;           ///< mean square of the broadband displacement [m^2]
  double wave_velocity_variance_ = 0.0;  ///< and of its velocity [m^2/s^2]
  double previous_raw_ = NAN;
  double noise_variance_ = 0.0;  ///< white noise per sample from first differences [(m/s^2)^2]
  NoiseFloor noise_floor_;
  double line_free_variance_ = 0.0;  ///< white noise per sample from NoiseFloor's blocks, averaged
  double noise_blocks_ = 0.0;        ///< blocks in line_free_variance_
};

}  // namespace periodic_bias_compensation
