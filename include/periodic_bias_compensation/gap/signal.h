// Sim-to-real gap diagnosis: signal processing of a recording (Welch spectra, Allan deviation,
// lattice, clipping and repeated samples, the line of the stamps). See docs/gap.md.
#pragma once

#include <cstddef>
#include <vector>

#include <Eigen/Core>

namespace periodic_bias_compensation::gap
{
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
}  // namespace periodic_bias_compensation::gap
