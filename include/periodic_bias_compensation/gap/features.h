// Sim-to-real gap diagnosis: the features of a recording (Welch PSD in log bands, overlapping
// Allan deviation per tau octave, value / stamp / cross-axis statistics per time segment) and the
// gap metric, their distance from a simulated ensemble in units of its spread. See docs/gap.md.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "periodic_bias_compensation/gap/recording.h"

namespace periodic_bias_compensation::gap
{
/// Where a feature lives.
struct FeatureInfo
{
  std::string channel;     ///< "ax".."gz", "accel", "gyro", "stamp", "orientation"
  std::string quantity;    ///< "psd", "allan", "mean", "std", "corr", "flat_top", "lattice", "jitter", ...
  std::string range;       ///< band "0.1-0.2 Hz", tau "1.28 s", "" for none
  double lo = 0.0;         ///< band low edge [Hz] or tau [s]
  double hi = 0.0;         ///< band high edge [Hz] or tau [s]
  std::string segment;     ///< "all" or "seg k/n"
  std::string stage;       ///< "sensor" (raw data), "stamps", "orientation"
  double floor = 0.0;      ///< smallest spread used for z-scores [feature unit]
  double rel_floor = 0.0;  ///< plus this fraction of |ensemble median|
  /// Left out of the gap (z-score 0): a departure of the motion that the motion stage reaches but
  /// could not fit, which no sensor effect is to be credited with.
  bool left_out = false;
};

/// A feature of time segment s of `segments` over `duration` s (range = its time span).
FeatureInfo segmentInfo(const std::string& channel, const std::string& quantity, const std::string& stage,
                        double duration, int s, int segments);

/// Fixed feature layout (bands, taus, segments) so that real and simulated runs compare.
struct FeatureLayout
{
  double rate = 0.0;
  int nseg = 0;                    ///< Welch segment length
  std::vector<double> band_edges;  ///< log bands [Hz], half-octave
  std::vector<int> allan_m;        ///< cluster sizes (octaves)
  int segments = 4;                ///< time segments for mean / std
  bool orientation = false;        ///< tilt features (the real recording has orientation)
  bool temperature = false;        ///< temperature-slope features
  std::vector<FeatureInfo> info;   ///< one per feature value
};

/// Layout for recordings at this rate with this many samples.
FeatureLayout makeLayout(double rate, std::size_t n, bool orientation, bool temperature, int segments = 4);

/// Feature values of a recording in the layout's order.
std::vector<double> computeFeatures(const Recording& recording, const FeatureLayout& layout);

// ---------------------------------------------------------------------------------------------
// Gap metric

/// Ensemble statistics of every feature.
struct EnsembleStats
{
  std::vector<double> median;
  std::vector<double> spread;  ///< max(1.4826 MAD, floor); 1 where the feature is left out
  std::vector<char> left_out;  ///< the layout's FeatureInfo::left_out
};
EnsembleStats ensembleStats(const std::vector<std::vector<double>>& members, const FeatureLayout& layout);

/// z-scores of a feature vector against an ensemble (0 where a feature is left out).
std::vector<double> zScores(const std::vector<double>& features, const EnsembleStats& stats);

/// z-scores of member i of an ensemble against the other members.
std::vector<double> leaveOneOutZ(const std::vector<std::vector<double>>& members, int i, const FeatureLayout& layout);

/// Gap = root mean square of log(1 + max(0, |z| - kZThreshold)) over features [-]: 0 when every
/// feature lies within the ensemble's spread; the logarithm keeps one huge departure (a mean
/// many spreads off) from hiding many moderate ones.
constexpr double kZThreshold = 3.0;
double gapOf(const std::vector<double>& z);

/// The vocabulary's boundary between a spectral line's two names: from here up a vibration (an
/// engine's or a propeller's), below a periodic bias. The vibration fitter searches from here up:
/// a sea whose motion the scenario matches only roughly leaves excess lines in its wave band
/// that are not the sensor's [Hz].
constexpr double kVibrationMinFrequency = 1.0;

/// Gap of a candidate model: as gapOf(), plus kSpreadPenalty * max(0, ln(spread / base spread))
/// per feature, so that a model cannot explain a departure merely by being vaguer (a log-score
/// idea: a wider predictive spread costs its logarithm).
constexpr double kSpreadPenalty = 0.3;
double gapOf(const std::vector<double>& z, const std::vector<double>& spread, const std::vector<double>& base_spread);

/// A candidate moves a feature when its ensemble's median lies more than this many of the base
/// ensemble's spreads from the base median [-].
constexpr double kMovedSpreads = 3.0;

/// What a candidate explains of the departures it touches, whatever else the gap holds (a motion
/// the scenario cannot reproduce, another effect): the gap over the features it moves, before and
/// after, against the null level over the same features.
struct OwnShrink
{
  int moved = 0;            ///< features the candidate moves
  double before = 0.0;      ///< gap over them, the base ensemble
  double after = 0.0;       ///< with the candidate (gapOf with its spread penalty)
  double null_level = 0.0;  ///< median over the base members of one member against the rest
  double shrink = 0.0;      ///< (before - after) / (before - null_level), at most 1; 0 without an excess
};

/// OwnShrink of a candidate whose ensemble is `candidate`, for the real features `real` against
/// the base ensemble `base`; `null_z`: each base member's leaveOneOutZ.
OwnShrink ownShrink(const std::vector<double>& real, const EnsembleStats& base, const EnsembleStats& candidate,
                    const std::vector<std::vector<double>>& null_z);

/// One departure of the real recording from the simulated ensemble.
struct Departure
{
  FeatureInfo where;
  double real = 0.0;
  double sim_median = 0.0;
  double z = 0.0;  ///< size, in ensemble spreads
};

/// Departures with |z| > threshold, largest first.
std::vector<Departure> rankDepartures(const std::vector<double>& real, const EnsembleStats& stats,
                                      const FeatureLayout& layout, double threshold = kZThreshold,
                                      std::size_t max_count = 40);
}  // namespace periodic_bias_compensation::gap
