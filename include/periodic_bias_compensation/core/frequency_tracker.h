// Dominant-frequency estimation with FFTW3 over a sliding window (estimation core, no ROS).
#pragma once

#include <functional>
#include <future>
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
  double amplitude = 0.0;   ///< amplitude of the dominant sinusoid after the decimation filter [signal units]
};

/// A search of the window as it stood when FrequencyTracker::searchTask() was called.
struct FrequencySearch
{
  FrequencyEstimate estimate;
  int span_samples = 0;  ///< input samples the estimate covers
  int samples = 0;       ///< FrequencyTracker::samples() when searched
  bool full = false;     ///< FrequencyTracker::full() when searched
};

/// Sliding-window FFT of one signal. The FFTW plan is made once per window size and reused. With
/// `background` it is made on the core's planning thread (FFTW plans a size it has not seen in
/// milliseconds, too long for the sample that first gives the rate), and waited for by the first
/// analysis if it is not ready by then; the destructor drops it there too (FFTW's planner lock,
/// which destroying a plan takes, may be held by a plan being made).
/// push() is O(1); analyse() costs one real FFT of the window (call it every hop, not every
/// sample).
///
/// With decimation M > 1 the window holds the input low-pass filtered and decimated by M: a
/// moving average of M samples taken again over each block of M (a triangular filter, response
/// sinc^2, nulls at multiples of rate/M), so the transform is M times shorter. Choose M so that
/// rate/M is several times the highest frequency searched (Compensator: 5 x max_frequency).
class FrequencyTracker
{
public:
  /// @param window_samples FFT window length [input samples], >= 16 x decimation
  /// @param sample_rate    input rate [Hz], > 0
  /// @param decimation     M >= 1 (1: every sample goes into the window)
  /// @param background     plan on the core's planning thread (see above)
  FrequencyTracker(int window_samples, double sample_rate, int decimation = 1, bool background = false);
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
  /// Input samples the window spans so far (at most windowSamples()).
  int samples() const;
  int windowSamples() const
  {
    return n_ * decimation_;
  }
  double sampleRate() const
  {
    return rate_ * decimation_;
  }
  int decimation() const
  {
    return decimation_;
  }

  /// Dominant frequency in [f_min, f_max] [Hz] (DC excluded, Hann window, mean removed,
  /// Gaussian interpolation of the peak between bins). Not locked when the window is not
  /// full or no peak reaches min_peak_ratio. With recent_samples > 0 only the newest
  /// recent_samples input samples are analysed (a fresher estimate of a period that fits in them).
  FrequencyEstimate analyse(double f_min, double f_max, double min_peak_ratio, int recent_samples = 0);
  /// analyse() of the whole window (long periods, a swell, need it); then, when the peak found
  /// also fits three times in the newest recent_samples and is found there too (within 20 %), the
  /// estimate from those instead: its span is centred less far back, so a drifting frequency is
  /// followed with less lag. *span_samples: the input samples the returned estimate covers.
  FrequencyEstimate analyseFreshest(double f_min, double f_max, double min_peak_ratio, int recent_samples,
                                    int* span_samples);
  /// analyseFreshest() (`freshest`) or analyse() of the newest recent_samples, of the window as it
  /// stands now, as a task to run on any thread while new samples come (the core's design thread):
  /// it reads the window in place, and the slots it reads are not written again until it has
  /// finished (the ring holds two windows; push() waits for it, should a window's worth of new
  /// samples come first; clear() keeps them). Its result is that of the same search made now. Run
  /// it once; the next searchTask(), analyse() and analyseFreshest() wait for it to finish.
  std::function<FrequencySearch()> searchTask(double f_min, double f_max, double min_peak_ratio, int recent_samples,
                                              bool freshest);

private:
  struct Plan;
  /// The ring of samples and their times (shared with a search task under way).
  struct Ring
  {
    std::vector<double> values;
    std::vector<double> times;
  };
  /// A window of the ring: its `window` newest of `count` samples pushed, the next write at `head`.
  struct Held
  {
    const double* values;
    const double* times;
    int length;  ///< of the ring
    int window;  ///< of the search [samples at the decimated rate]
    int head;
    long count;
  };
  /// What a search needs of the tracker besides its window (fixed at construction).
  struct Shape
  {
    int fft_size;
    double rate;  ///< decimated rate [Hz]
    int decimation;
  };
  static FrequencyEstimate analyseHeld(const Held& held, const Shape& shape, Plan& plan, double f_min, double f_max,
                                       double min_peak_ratio, int recent_samples);
  static FrequencySearch searchHeld(const Held& held, const Shape& shape, Plan& plan, double f_min, double f_max,
                                    double min_peak_ratio, int recent_samples, bool freshest);
  Held held() const
  {
    return { ring_->values.data(), ring_->times.data(), static_cast<int>(ring_->values.size()), n_, head_, count_ };
  }
  Shape shape() const
  {
    return { fft_size_, rate_, decimation_ };
  }
  void finishSearch();                    ///< waits for a search task under way
  Plan& plan();                           ///< plan_, once planned
  void store(double value, double t);     ///< into the window (decimated rate)
  void decimate(double value, double t);  ///< through the anti-alias filter

  int n_;         ///< window [samples at the decimated rate]
  int fft_size_;  ///< transform size, >= n_ (zero-padded)
  double rate_;   ///< decimated rate [Hz]
  int decimation_ = 1;
  bool background_ = false;  ///< planned on the core's planning thread
  // Anti-alias filter (decimation_ > 1): moving sum of the last M inputs, summed over a block.
  std::vector<double> moving_;  ///< last M inputs
  int moving_head_ = 0;
  double moving_sum_ = 0.0;
  double block_sum_ = 0.0;
  double block_time_ = 0.0;  ///< sum of the block's input times
  int block_count_ = 0;
  long inputs_ = 0;
  double last_time_ = 0.0;      ///< time of the newest input [s]
  std::shared_ptr<Ring> ring_;  ///< 2 n_ slots (searchTask)
  int head_ = 0;
  long count_ = 0;
  std::shared_ptr<Plan> plan_;                   ///< shared with a search task under way
  std::future<std::unique_ptr<Plan>> planning_;  ///< plan_ until it is taken
  std::shared_future<void> searching_;           ///< the last search task, until it has finished
  int stores_since_search_ = 0;                  ///< stored since the last search task was made
};

}  // namespace periodic_bias_compensation
