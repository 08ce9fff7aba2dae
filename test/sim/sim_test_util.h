// Helpers of the simulator gtests: run scenarios, spectra, Allan deviation, autocorrelation.
#pragma once

#include <cmath>
#include <complex>
#include <vector>

#include "periodic_bias_compensation/sim/simulator.h"

namespace sim_test
{
namespace sim = periodic_bias_compensation::sim;

/// Sensor error (output minus ideal IMU of the truth) of every sample.
struct Errors
{
  std::vector<sim::Vector3> accel;
  std::vector<sim::Vector3> gyro;
  std::vector<sim::Sample> samples;  ///< only if keep_samples
};

/// A level static scenario without effects.
inline sim::Scenario staticScenario(double rate, double duration)
{
  sim::Scenario s;
  s.rate = rate;
  s.duration = duration;
  return s;
}

/// Runs a scenario and returns output minus ideal IMU per sample.
inline Errors run(const sim::Scenario& scenario, std::uint64_t seed = 1, bool keep_samples = false)
{
  Errors e;
  sim::Simulator simulator(scenario, seed);
  sim::Sample s;
  while (simulator.next(&s))
  {
    sim::Vector3 a;
    sim::Vector3 g;
    sim::idealImu(s.truth, scenario.gravity, &a, &g);
    e.accel.push_back(s.accel - a);
    e.gyro.push_back(s.gyro - g);
    if (keep_samples)
    {
      e.samples.push_back(s);
    }
  }
  return e;
}

/// One axis of a vector series.
inline std::vector<double> axis(const std::vector<sim::Vector3>& v, int i)
{
  std::vector<double> out;
  out.reserve(v.size());
  for (const sim::Vector3& x : v)
  {
    out.push_back(x[i]);
  }
  return out;
}

/// Amplitude of the sinusoid at frequency f in x (DFT at f, no window).
/// @param fs sample rate [Hz]
/// @param f frequency [Hz]
inline double lineAmplitude(const std::vector<double>& x, double fs, double f)
{
  std::complex<double> sum = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k)
  {
    sum += x[k] * std::polar(1.0, -2.0 * M_PI * f * k / fs);
  }
  return 2.0 * std::abs(sum) / x.size();
}

/// One-sided PSD of x at f [unit^2/Hz]: Welch average of Hann-windowed segments.
inline double psd(const std::vector<double>& x, double fs, double f, std::size_t segment)
{
  double sum = 0.0;
  int count = 0;
  std::vector<double> w(segment);
  double w2 = 0.0;
  for (std::size_t k = 0; k < segment; ++k)
  {
    w[k] = 0.5 - 0.5 * std::cos(2.0 * M_PI * k / segment);
    w2 += w[k] * w[k];
  }
  for (std::size_t start = 0; start + segment <= x.size(); start += segment / 2)
  {
    std::complex<double> acc = 0.0;
    for (std::size_t k = 0; k < segment; ++k)
    {
      acc += w[k] * x[start + k] * std::polar(1.0, -2.0 * M_PI * f * k / fs);
    }
    sum += 2.0 * std::norm(acc) / (fs * w2);
    ++count;
  }
  return sum / count;
}

/// Overlapping Allan deviation of x at averaging time m samples.
inline double allanDeviation(const std::vector<double>& x, std::size_t m)
{
  std::vector<double> c(x.size() + 1, 0.0);
  for (std::size_t k = 0; k < x.size(); ++k)
  {
    c[k + 1] = c[k] + x[k];
  }
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k + 2 * m <= x.size(); ++k)
  {
    const double a = (c[k + m] - c[k]) / m;
    const double b = (c[k + 2 * m] - c[k + m]) / m;
    sum += (b - a) * (b - a);
    ++n;
  }
  return std::sqrt(sum / (2.0 * n));
}

/// Autocovariance of x at a lag [samples] (mean removed).
inline double autocovariance(const std::vector<double>& x, std::size_t lag)
{
  double mean = 0.0;
  for (const double v : x)
  {
    mean += v;
  }
  mean /= x.size();
  double sum = 0.0;
  for (std::size_t k = 0; k + lag < x.size(); ++k)
  {
    sum += (x[k] - mean) * (x[k + lag] - mean);
  }
  return sum / (x.size() - lag);
}

/// Mean and standard deviation.
inline void meanStd(const std::vector<double>& x, double* mean, double* stddev)
{
  double m = 0.0;
  for (const double v : x)
  {
    m += v;
  }
  m /= x.size();
  double s = 0.0;
  for (const double v : x)
  {
    s += (v - m) * (v - m);
  }
  *mean = m;
  *stddev = std::sqrt(s / (x.size() - 1));
}
}  // namespace sim_test
