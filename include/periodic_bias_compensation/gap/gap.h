// Sim-to-real gap diagnosis (no ROS): features of an IMU recording (Welch PSD in log bands,
// overlapping Allan deviation per tau octave, value / stamp / cross-axis statistics per time
// segment), their distance from a simulated ensemble in units of its spread, effect
// candidates fitted on the first part of a recording and judged on the withheld rest.
// See docs/gap.md.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "periodic_bias_compensation/sim/scenario.h"

namespace periodic_bias_compensation::gap
{
constexpr int kChannels = 6;  ///< ax, ay, az [m/s^2], gx, gy, gz [rad/s]

/// "ax", "ay", "az", "gx", "gy", "gz".
const std::array<std::string, kChannels>& channelNames();

/// Ground truth of a recording (a nav_msgs/Odometry topic, or truth columns of a CSV), on its
/// own time base. World frame z up (ENU for a ship, the robot's base frame for an arm).
struct TruthTrack
{
  std::vector<double> stamp;                      ///< [s], the IMU's clock
  std::vector<Eigen::Vector3d> position;          ///< world [m]
  std::vector<Eigen::Quaterniond> orientation;    ///< body -> world
  bool has_twist = false;                         ///< velocities given (else differentiated)
  std::vector<Eigen::Vector3d> velocity;          ///< body frame [m/s] (odometry twist)
  std::vector<Eigen::Vector3d> angular_velocity;  ///< body frame [rad/s]

  std::size_t size() const
  {
    return stamp.size();
  }
};

/// An IMU recording in SI units (REP-145, sensor frame). Samples in stamp order as recorded.
struct Recording
{
  double rate = 0.0;          ///< nominal sample rate [Hz] (0: estimate from stamps)
  std::vector<double> stamp;  ///< reported time stamps [s]
  Eigen::MatrixXd data;       ///< N x 6: ax, ay, az [m/s^2], gx, gy, gz [rad/s]
  bool has_orientation = false;
  std::vector<Eigen::Quaterniond> orientation;  ///< reported sensor -> ENU
  bool has_temperature = false;
  std::vector<double> temperature;  ///< [degC]
  std::string source;               ///< file name or "sim seed N"
  TruthTrack truth;                 ///< empty when the recording has no truth

  std::size_t size() const
  {
    return stamp.size();
  }
};

/// The sample rate of the stamps [Hz]: the slope of fitStampLine started from the median
/// interval (0 with fewer than 2 samples).
double estimateRate(const Recording& recording);

/// Samples with stamp - stamp[0] in [from, to) * span (fractions of the recording's span).
Recording sliceFraction(const Recording& recording, double from, double to);

/// Runs the simulator and keeps what a real sensor would give (dropped samples removed), and with
/// keep_truth its truth (as ground_truth/odometry carries it) at every kept sample.
Recording simulateRecording(const sim::Scenario& scenario, std::uint64_t seed, bool keep_truth = false);

/// A scenario made to match a recording: same rate, duration and start time.
sim::Scenario matchScenario(const sim::Scenario& scenario, const Recording& real);

// ---------------------------------------------------------------------------------------------
// Signal processing

/// One-sided Welch PSD of a signal (Hann window, 50 % overlap, mean removed per segment).
struct Psd
{
  double df = 0.0;            ///< bin spacing [Hz]
  std::vector<double> power;  ///< [unit^2 / Hz], bins 0 .. nseg / 2
};

/// @param x samples
/// @param rate sample rate [Hz]
/// @param nseg segment length (clipped to x.size())
Psd welch(const Eigen::Ref<const Eigen::VectorXd>& x, double rate, int nseg);

/// Welch cross-spectral matrix of 3 signals (accel or gyro triple): real part, per bin, 3x3.
std::vector<Eigen::Matrix3d> welchCross3(const Eigen::Ref<const Eigen::MatrixXd>& x3, double rate, int nseg);

/// Segment length used for a recording of n samples: a power of two <= n / 4, at most 2^15.
int welchSegment(std::size_t n);

/// Overlapping Allan deviation at cluster sizes m (tau = m / rate) [unit].
std::vector<double> allanDeviation(const Eigen::Ref<const Eigen::VectorXd>& x, const std::vector<int>& m);

/// Allan variance of a first-order Gauss-Markov process of unit variance and correlation time
/// tc at averaging time tau.
double gaussMarkovAllanVariance(double tau, double tc);

/// Smallest lattice step the values lie on (0 if none): |v / q - round(v / q)| < 1e-3 for at
/// least 99 % of the values, with fewer distinct values than half the samples.
double latticeStep(const Eigen::Ref<const Eigen::VectorXd>& x);

/// Fraction of samples whose magnitude equals the largest magnitude (flat tops of clipping); 0
/// unless the largest magnitude is reached in two separate runs or more (one reading held over
/// several polls at the peak is not clipping).
double flatTopFraction(const Eigen::Ref<const Eigen::VectorXd>& x, double* limit = nullptr);

/// Fraction of rows equal to their predecessor in every channel (a driver polling faster than the
/// sensor updates repeats its last reading).
double repeatedFraction(const Eigen::MatrixXd& data);

/// The straight line the stamps follow, stamp = offset + period * index, with each sample's index
/// (0 for the first, increasing, a gap where samples were lost). The rate is refined from `rate`
/// by the drift of the stamps' phase from block to block (lost samples leave the phase as it
/// is, jitter only blurs it), the indices are the most likely increasing ones on that line
/// (Viterbi over the nearest index and one either side), and the line is then a least-squares
/// fit of the stamps on the indices without the outliers. A rate off by 0.01 % gives no lost
/// samples over an hour, as a fit on indices rounded from the nominal rate would.
struct StampLine
{
  double offset = 0.0;        ///< stamp of index 0 [s]
  double period = 0.0;        ///< [s]
  std::vector<double> index;  ///< per stamp [-]
};
StampLine fitStampLine(const std::vector<double>& stamp, double rate);

/// Stamp statistics: residual of the stamps about their line (fitStampLine), and the lost
/// samples its indices imply.
struct StampStats
{
  double rate = 0.0;           ///< fitted rate [Hz]
  double jitter = 0.0;         ///< robust standard deviation of the residual [s]
  double lost_fraction = 0.0;  ///< missing / expected samples [-]
  double bursts = 0.0;         ///< number of gaps [-]
  double mean_burst = 0.0;     ///< mean number of missing samples per gap [-]
  double backwards = 0.0;      ///< stamps earlier than their predecessor [-]
};
StampStats stampStats(const std::vector<double>& stamp, double rate);

// ---------------------------------------------------------------------------------------------
// Truth: sample-by-sample comparison

/// The ideal IMU a truth track drives, at the given stamps (N x 6, REP-145): specific force
/// R^T (a + g z) and angular rate in the body frame (sim::idealImu). The world acceleration is the
/// central difference of the world velocity (the twist rotated into the world, or position
/// differences), the angular rate the twist's (or from orientation differences); both are
/// smoothed by a centred moving average of `smooth` s, then interpolated to the stamps.
Eigen::MatrixXd idealFromTruth(const TruthTrack& truth, const std::vector<double>& stamps, double gravity,
                               double smooth);

/// Centred moving average of `smooth` s over the columns (stamps give the rate).
Eigen::MatrixXd movingAverage(const Eigen::MatrixXd& x, double rate, double smooth);

/// Real minus the ideal IMU driven by its truth, both smoothed alike (N x 6).
Eigen::MatrixXd truthResidual(const Recording& r, double gravity, double smooth);

/// Per channel and time segment: mean and standard deviation of a truth residual (layout: for
/// each channel, `segments` means then `segments` standard deviations).
std::vector<double> truthFeatures(const Eigen::MatrixXd& residual, int segments);

struct FeatureLayout;
/// Layout of truthFeatures() (stage "truth", range = the segment's time span since the start).
FeatureLayout truthLayout(double duration, int segments);

/// The compensator's own pipeline stages (core Compensator, default mode) on a recording, per
/// level axis and time segment: constant-bias estimate, dominant frequency while locked, rms of
/// the filtered velocity, of the filtered position (error growth) and of the wave position.
std::vector<double> stageFeatures(const Recording& r, int segments);

/// Layout of stageFeatures() (stage "compensator", channel "level x/y/z").
FeatureLayout stageLayout(double duration, int segments);

// ---------------------------------------------------------------------------------------------
// Features

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
  std::vector<double> spread;  ///< max(1.4826 MAD, floor)
};
EnsembleStats ensembleStats(const std::vector<std::vector<double>>& members, const FeatureLayout& layout);

/// z-scores of a feature vector against an ensemble.
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

// ---------------------------------------------------------------------------------------------
// Diagnosis

struct DiagnoseOptions
{
  int ensemble = 8;           ///< simulated runs per model
  double fit_fraction = 0.6;  ///< the fit sees [0, fit_fraction), the gap is measured after
  int threads = 2;
  double min_shrink = 0.3;            ///< below: "no candidate explains the gap"
  double pair_gain = 0.15;            ///< a pair is reported if it shrinks this much more
  std::uint64_t seed_base = 1000003;  ///< ensemble seeds seed_base + i (never the real's)
  double truth_smooth = 0.2;          ///< moving average of the truth comparison [s]
  int truth_segments = 8;             ///< time segments of the truth comparison
  bool verbose = false;
};

/// One candidate effect with fitted parameters and its gap on the withheld part.
struct Candidate
{
  std::string effect;                                                ///< vocabulary name, or "a+b" for a pair
  std::vector<sim::EffectSpec> specs;                                ///< what is added / changed in the scenario
  nlohmann::ordered_json params = nlohmann::ordered_json::object();  ///< fitted parameters
  std::string note;                                                  ///< how it was fitted
  double gap_before = 0.0;
  double gap_after = 0.0;
  double shrink = 0.0;          ///< (before - after) / (before - typical null gap), at most 1
  std::vector<double> z_after;  ///< withheld z-scores with the effect
  OwnShrink own;                ///< on the withheld features it moves
  /// Fitted parameters that the fitter's search range stopped, each "name = value, ...": the
  /// effect may be larger than the fit says, or another one. A verdict on such a fit is never
  /// confident (confidence below 0.5).
  std::vector<std::string> at_limit;
};

// ---------------------------------------------------------------------------------------------
// Motion stage: the recording's motion against the scenario's, before any sensor effect

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
  std::vector<double> heave_frequency;  ///< bins of the heave spectrum in that band [Hz]
  std::vector<double> heave_density;    ///< the heave spectrum there [m^2/Hz]
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

/// The heave spectra of the motion stage as CSV, "f,real,given,fitted" [Hz, m^2/Hz]: the
/// recording's, the mean of the scenario's runs as given, and the mean of `fitted_runs` (the
/// summaries of the adopted fit's runs).
std::string motionCsv(const MotionFit& fit, const std::vector<MotionSummary>& fitted_runs);

/// Directly visible effect (stamps, lattice, clipping, gaps).
struct DirectDetection
{
  std::string effect;
  bool detected = false;
  std::string evidence;
};

struct Report
{
  std::string real_source;
  std::string scenario_name;
  MotionFit motion;  ///< the motion stage; sensor effects are judged against motion.fitted
  double rate = 0.0;
  double duration = 0.0;
  std::size_t samples = 0;
  FeatureLayout layout_all;  ///< layout of the whole recording ("where")
  std::vector<double> real_all;
  EnsembleStats ens_all;
  std::vector<Departure> where;
  double gap_all = 0.0;
  double null_gap = 0.0;      ///< largest gap of one ensemble member vs the rest
  FeatureLayout layout_held;  ///< layout of the withheld part
  std::vector<double> real_held;
  EnsembleStats ens_held;
  double gap_before = 0.0;  ///< withheld part, scenario as given
  double null_gap_held = 0.0;
  double null_gap_typical = 0.0;                 ///< median gap of one member vs the rest (shrink reference)
  double max_z_held = 0.0;                       ///< largest |z| of the real withheld part
  double null_max_z_held = 0.0;                  ///< largest |z| of one member vs the rest
  std::vector<std::vector<double>> null_z_held;  ///< each member's leaveOneOutZ on the withheld part
  std::vector<Candidate> ranking;                ///< best first
  std::vector<DirectDetection> direct;
  // verdict
  std::string verdict_effect;  ///< effect name, "a+b", "none" (no candidate explains) or "no_gap"
  nlohmann::ordered_json verdict_params = nlohmann::ordered_json::object();  ///< the verdict's fitted parameters
  double confidence = 0.0;
  double shrink_withheld = 0.0;
  std::string verdict_text;
  int best = -1;  ///< index of the verdict in ranking, -1 for none
  // localised places: top departures of the withheld part, before and after the verdict
  std::vector<Departure> where_held;
  std::vector<double> where_held_after;
  double seconds = 0.0;  ///< wall time
  // Curves for plots (CSV text): withheld part, real vs ensemble median vs ensemble with the verdict.
  std::string psd_csv;       ///< channel,f,real,sim,sim_effect
  std::string allan_csv;     ///< channel,tau,real,sim,sim_effect
  std::string drift_csv;     ///< channel,t,real,sim_lo,sim_med,sim_hi,sim_effect_med (block means, whole recording)
  std::string features_csv;  ///< index,channel,quantity,range,segment,real,sim,spread,z_before,z_after
  std::vector<std::vector<double>> ens_held_members;  ///< for plots
  // Truth (when the recording has one): real minus the ideal IMU of its truth, against the same
  // residual of every ensemble member (its own truth); departures also go into `where`.
  bool has_truth = false;
  std::vector<Departure> truth_where;  ///< stage "truth", quantity truth_mean / truth_std
  std::vector<Departure> stage_where;  ///< stage "compensator" (its pipeline on real vs ensemble)
  std::string truth_csv;               ///< channel,t,real,sim_lo,sim_med,sim_hi (block means of the residual)
  std::string motion_csv;  ///< f,real,given,fitted: heave spectra (motionCsv; empty when the motion does not differ)
};

/// Full diagnosis of a real recording against a scenario.
Report diagnose(const Recording& real, const sim::Scenario& scenario, const DiagnoseOptions& options);

/// The scenario with a candidate's effects in place of those of the same name.
sim::Scenario applyCandidate(const sim::Scenario& scenario, const Candidate& candidate);

/// v to 6 significant digits, the precision of the numbers in report.json; non-finite values pass
/// through (nlohmann::json writes them as null).
double sixDigits(double v);

/// report.json: its keys in the order written.
nlohmann::ordered_json reportJson(const Report& report);

/// One-screen summary.
std::string reportSummary(const Report& report);

/// Fitted effect candidates for a real recording against a base ensemble (fit part only).
/// Exposed for tests.
std::vector<Candidate> fitCandidates(const Recording& real_fit, const std::vector<Recording>& sims_fit,
                                     const sim::Scenario& scenario);

/// Runs fn(i) for i in [0, n) on `threads` threads.
void parallelFor(int n, int threads, const std::function<void(int)>& fn);
}  // namespace periodic_bias_compensation::gap
