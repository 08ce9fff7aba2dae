// The time base of an IMU stream: which stamps continue it, the step to integrate, the sample
// rate (estimation core, no ROS).
//
// Real drivers stamp samples on arrival: the stamps jitter by a good part of a period, a sample
// now and then comes out of order, twice, stamped 0 or a few seconds off, and a serial buffer can
// deliver two samples a millisecond apart. None of that is a restart of the IMU. TimeBase
// therefore
//
//  - takes the sample period from a least-squares line of stamps against sample count (ticks)
//    over the last kRateWindow seconds, its outliers (residual beyond 4 robust standard
//    deviations) left out, never from a mean of 1 / dt; the line is refitted each time a
//    sixteenth of its stamps is new;
//  - gives each accepted sample the step ticks x period, ticks >= 1 the periods since the
//    previous sample read off that line, so a jittered stamp does not jitter the integration and
//    a dropped sample is stepped over;
//  - drops a stamp equal to the previous one (duplicate) or less than a quarter period after it
//    (early), and counts it;
//  - holds a stamp that does not continue the stream (before the previous one, or more than
//    max_gap after it; for an IMU slower than max_gap, more than kSlowStreamSteps periods): when the next sample continues the stream the held one was a lone glitch
//    and is dropped; when kConfirmSamples samples in a row continue the held one instead, the
//    jump is confirmed: a restart (backwards, e.g. a bag replayed again) or a gap (forwards);
//  - follows a genuine rate change: when the median of the last kRecentSteps stamp differences
//    departs from the period by more than kRateChange, the period restarts from that median.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

namespace periodic_bias_compensation
{
/// Samples in a row that confirm a jump in the stamps (the held one included).
constexpr int kConfirmSamples = 5;
/// Span of the line fit that measures the period [s].
constexpr double kRateWindow = 10.0;
/// Stamp differences whose median detects a change of the sample rate.
constexpr int kRecentSteps = 16;
/// Relative difference between that median and the period that is a change of rate [-] (jitter
/// of a quarter period moves the median of 16 differences by about 6 %).
constexpr double kRateChange = 0.3;
/// Longest sample period of a stream [s]: a longer step is a gap whatever the rate.
constexpr double kMaxPeriod = 10.0;
/// Periods a step of a stream slower than max_gap may last and still continue it [-].
constexpr double kSlowStreamSteps = 1.5;
/// A stamp less than this fraction of a period after the previous one is early [-].
constexpr double kEarlyFraction = 0.25;

/// What TimeBase made of a stamp.
enum class StampVerdict
{
  kAccept,     ///< continues the stream: step() is the time since the previous accepted sample
  kDuplicate,  ///< the previous stamp again: drop the sample
  kEarly,      ///< less than kEarlyFraction of a period after the previous stamp: drop it
  kHeld,       ///< does not continue the stream: keep the sample until confirmed or discarded
  kRestart,    ///< confirmed jump backwards: a new record starts with the held samples
  kGap,        ///< confirmed jump forwards, beyond max_gap: a new record starts with them
};

class TimeBase
{
public:
  /// max_gap [s]: the longest step integrated across.
  explicit TimeBase(double max_gap = 0.5);

  void setMaxGap(double max_gap);
  /// Forgets everything, the rate included.
  void reset();

  /// Classifies the next stamp t [s] (finite). After kRestart or kGap, the samples held since the
  /// jump (heldCount() of them, this one last) start the new record: step() is 0 for the first of
  /// them and the period for the others.
  StampVerdict update(double t);

  /// Step of the sample just accepted [s]; 0 for the first sample of a record.
  double step() const
  {
    return step_;
  }
  /// Sample period [s], 0 until two stamps have been seen.
  double period() const
  {
    return period_;
  }
  /// True once the period rests on kRecentSteps steps or more (until then it is the median of
  /// the few there are, and a quarter-period jitter moves it by up to half).
  bool settled() const
  {
    return settled_;
  }
  /// 1 / period() [Hz], 0 until known.
  double rate() const
  {
    return period_ > 0.0 ? 1.0 / period_ : 0.0;
  }
  /// Samples held for the jump being confirmed (after kRestart / kGap: those that start the new
  /// record, the current one included).
  int heldCount() const
  {
    return held_count_;
  }
  /// After kRestart / kGap: the step of held sample i (0 for the first) [s].
  double heldStep(int i) const;
  /// Stamps dropped as lone glitches: held and then discarded, or early.
  std::uint64_t glitches() const
  {
    return glitches_;
  }
  /// Genuine changes of the sample rate followed.
  std::uint64_t rateChanges() const
  {
    return rate_changes_;
  }

private:
  /// A step that continues the stream: forwards, and no longer than max_gap or, for an IMU slower
  /// than that, than kSlowStreamSteps periods (the second stamp of a record sets the period) and
  /// kMaxPeriod.
  bool continues(double dt) const
  {
    return dt > 0.0 && (dt <= max_gap_ || (dt <= kMaxPeriod && (period_ <= 0.0 || dt <= kSlowStreamSteps * period_)));
  }
  void accept(double t, double dt);
  void startRecord();
  void noteStep(double dt);
  void addToFit(double t);
  std::size_t fitWindow() const;  ///< stamps the next line fit takes
  void fitPeriod();

  double max_gap_;
  bool has_last_ = false;
  double last_t_ = 0.0;       ///< newest stamp of the stream [s]
  double last_seen_t_ = 0.0;  ///< newest stamp continuing the stream, early ones included [s]
  double step_ = 0.0;
  double period_ = 0.0;

  // Line fit of stamps against ticks over the last kRateWindow seconds (a ring).
  std::vector<double> ticks_;
  std::vector<double> stamps_;
  std::size_t fit_next_ = 0;  ///< where the next entry goes
  std::size_t fit_count_ = 0;
  double tick_ = 0.0;
  double last_ticks_ = 1.0;  ///< periods the newest accepted sample was counted after its predecessor
  double skipped_ = 0.0;     ///< stamps dropped since the newest accepted one
  std::size_t since_fit_ = 0;
  std::vector<double> scratch_;
  bool has_line_ = false;    ///< the fit's line is known: ticks come from it
  double line_tick_ = 0.0;   ///< a tick on the line
  double line_stamp_ = 0.0;  ///< the line's stamp at line_tick_ [s]

  std::array<double, kRecentSteps> recent_{};
  int recent_count_ = 0;
  bool settled_ = false;
  int recent_head_ = 0;

  // The jump being confirmed.
  int pending_count_ = 0;  ///< samples held for a jump not yet confirmed
  int held_count_ = 0;     ///< what heldCount() reports
  std::array<double, kConfirmSamples> held_{};

  std::uint64_t glitches_ = 0;
  std::uint64_t rate_changes_ = 0;
};

}  // namespace periodic_bias_compensation
