// Dominant-frequency estimation with FFTW3 over a sliding window (estimation core, no ROS).
#pragma once

#include <memory>
#include <vector>

namespace periodic_bias_compensation
{
/// Result of one spectral analysis of the window.
struct FrequencyEstimate
{
  bool locked = false;      ///< a peak stood out of the band (peak/median power >= threshold)
  double frequency = 0.0;   ///< dominant frequency with sub-bin interpolation [Hz]
  double peak_ratio = 0.0;  ///< peak power / median power in the band [-]
  double amplitude = 0.0;   ///< amplitude of the dominant sinusoid [signal units]
};

/// Sliding-window FFT of one signal. The FFTW plan is made once per window size and reused.
/// push() is O(1); analyse() costs one real FFT of the window (call it every hop, not every
/// sample).
class FrequencyTracker
{
public:
  /// @param window_samples FFT window length [samples], >= 16
  /// @param sample_rate    [Hz], > 0
  FrequencyTracker(int window_samples, double sample_rate);
  ~FrequencyTracker();
  FrequencyTracker(const FrequencyTracker&) = delete;
  FrequencyTracker& operator=(const FrequencyTracker&) = delete;

  /// Adds a sample taken at time t [s]. Frequencies are scaled by the window's measured mean
  /// sample rate, so a rate that differs a little from the planned one costs no accuracy.
  void push(double value, double t);
  /// Adds a sample at the nominal rate (one period after the previous).
  void push(double value);
  void clear();
  /// True once the window has been filled.
  bool full() const;
  /// Samples in the window so far (at most windowSamples()).
  int samples() const;
  int windowSamples() const { return n_; }
  double sampleRate() const { return rate_; }

  /// Dominant frequency in [f_min, f_max] [Hz] (DC excluded, Hann window, mean removed,
  /// Gaussian interpolation of the peak between bins). Not locked when the window is not
  /// full or no peak reaches min_peak_ratio.
  FrequencyEstimate analyse(double f_min, double f_max, double min_peak_ratio);

private:
  struct Plan;
  int n_;          ///< window [samples]
  int fft_size_;   ///< transform size, >= n_ (zero-padded)
  double rate_;
  std::vector<double> ring_;
  std::vector<double> times_;
  int head_ = 0;
  long count_ = 0;
  std::unique_ptr<Plan> plan_;
};

}  // namespace periodic_bias_compensation
