#include "periodic_bias_compensation/core/time_base.h"

#include <algorithm>
#include <cmath>

#include "periodic_bias_compensation/common/numeric.h"

namespace periodic_bias_compensation
{
namespace
{
/// Largest number of stamps in the line fit (kRateWindow at 400 Hz; faster IMUs fit a shorter
/// span, still thousands of samples).
constexpr std::size_t kMaxFitSamples = 4096;
/// Fewest stamps for the line fit; below it the period is the median of the recent steps.
constexpr std::size_t kMinFitSamples = 32;
/// Accepted samples between two line fits: at least this many, and at least the fit's window
/// over kFitsPerWindow (a fit costs a few passes over its window: a constant share per sample).
constexpr std::size_t kFitInterval = 16;
constexpr std::size_t kFitsPerWindow = 16;
/// A step shorter than this many periods is one period: jitter, not a dropped sample [-].
constexpr double kDropoutSteps = 1.75;

}  // namespace

TimeBase::TimeBase(double max_gap) : max_gap_(max_gap), ticks_(kMaxFitSamples), stamps_(kMaxFitSamples)
{
  scratch_.reserve(kMaxFitSamples);
}

void TimeBase::setMaxGap(double max_gap)
{
  max_gap_ = max_gap;
}

void TimeBase::reset()
{
  has_last_ = false;
  has_line_ = false;
  step_ = 0.0;
  period_ = 0.0;
  fit_next_ = fit_count_ = 0;
  tick_ = 0.0;
  since_fit_ = 0;
  recent_count_ = recent_head_ = 0;
  held_count_ = pending_count_ = 0;
  settled_ = false;
}

StampVerdict TimeBase::update(double t)
{
  if (!has_last_)
  {
    held_count_ = 1;
    held_[0] = t;
    startRecord();
    return StampVerdict::kAccept;
  }
  if (pending_count_ == 0)
    held_count_ = 0;  // the previous call's record start is done with
  const double dt = t - last_t_;
  if (dt == 0.0)
    return StampVerdict::kDuplicate;
  if (continues(dt))
  {
    glitches_ += pending_count_;  // the stream went on: what was held was a glitch
    skipped_ += pending_count_;
    pending_count_ = held_count_ = 0;
    const double seen = t - last_seen_t_;
    last_seen_t_ = t;
    noteStep(seen);  // may follow a rate change, after which this stamp is no longer early
    if (period_ > 0.0 && dt < kEarlyFraction * period_)
    {
      ++glitches_;
      ++skipped_;
      return StampVerdict::kEarly;
    }
    accept(t, dt);
    return StampVerdict::kAccept;
  }
  // Not the stream's continuation: the start of a jump, or its next sample.
  if (pending_count_ > 0 && continues(t - held_[pending_count_ - 1]))
  {
    held_[pending_count_++] = t;
    held_count_ = pending_count_;
    if (pending_count_ < kConfirmSamples)
      return StampVerdict::kHeld;
    const bool backwards = held_[0] < last_t_;
    pending_count_ = 0;
    startRecord();
    return backwards ? StampVerdict::kRestart : StampVerdict::kGap;
  }
  glitches_ += pending_count_;
  pending_count_ = held_count_ = 1;
  held_[0] = t;
  return StampVerdict::kHeld;
}

double TimeBase::heldStep(int i) const
{
  if (i <= 0 || i >= held_count_)
    return 0.0;
  const double dt = held_[i] - held_[i - 1];
  if (period_ <= 0.0)
    return dt;
  const double ticks = std::max(1.0, std::round(dt / period_));
  return std::abs(dt - ticks * period_) <= period_ ? ticks * period_ : dt;
}

void TimeBase::startRecord()
{
  // A new record keeps the period (the same IMU) but not the line fit's stamps.
  has_last_ = true;
  has_line_ = false;
  skipped_ = 0;
  fit_next_ = fit_count_ = 0;
  tick_ = 0.0;
  since_fit_ = 0;
  recent_count_ = recent_head_ = 0;
  last_t_ = last_seen_t_ = held_[0];
  addToFit(held_[0]);
  step_ = 0.0;
  for (int i = 1; i < held_count_; ++i)
  {
    last_seen_t_ = held_[i];
    noteStep(held_[i] - held_[i - 1]);
    accept(held_[i], held_[i] - held_[i - 1]);
  }
  step_ = held_count_ > 1 ? heldStep(held_count_ - 1) : 0.0;
}

void TimeBase::noteStep(double dt)
{
  recent_[recent_head_] = dt;
  recent_head_ = (recent_head_ + 1) % kRecentSteps;
  recent_count_ = std::min(recent_count_ + 1, kRecentSteps);
  settled_ = settled_ || recent_count_ == kRecentSteps;
  scratch_.assign(recent_.begin(), recent_.begin() + recent_count_);
  const double typical = upperMedian(scratch_.begin(), scratch_.end());
  if (period_ <= 0.0 || recent_count_ < kRecentSteps)
  {
    // Until the line fit has enough stamps, the median step is the period.
    if (fit_count_ < kMinFitSamples)
      period_ = typical;
    return;
  }
  // A new rate once three quarters of the recent steps agree on it (not while the steps of two
  // rates are mixed: their median lies between them).
  const int agreeing =
      static_cast<int>(std::count_if(recent_.begin(), recent_.begin() + recent_count_,
                                     [&](double step) { return std::abs(step - typical) <= kRateChange * typical; }));
  if (std::abs(typical - period_) > kRateChange * period_ && 4 * agreeing >= 3 * recent_count_)
  {
    ++rate_changes_;
    period_ = typical;
    fit_next_ = fit_count_ = 0;
    since_fit_ = 0;
    has_line_ = false;
  }
}

void TimeBase::accept(double t, double dt)
{
  // Periods since the previous sample: from the fitted line once there is one (a stamp's jitter
  // then counts once, not twice as in a difference of two jittered stamps).
  double ticks = 1.0;
  if (period_ > 0.0 && dt >= kDropoutSteps * period_)
  {
    ticks = std::round(dt / period_);
    if (has_line_)
    {
      const double expected = std::round(line_tick_ + (t - line_stamp_) / period_);
      ticks = std::max(1.0, std::min(ticks, expected - tick_));
    }
  }
  else if (has_line_ && last_ticks_ > 1.0 && fit_count_ > 0 &&
           std::round(line_tick_ + (t - line_stamp_) / period_) <= tick_)
  {
    // This stamp is where the previous one should have been: that one was late, not the end
    // of a dropout. It moves back one period (a late stamp counted as a dropout would add a
    // period to every later tick and shorten the fitted period).
    tick_ -= 1.0;
    ticks_[(fit_next_ + kMaxFitSamples - 1) % kMaxFitSamples] = tick_;
  }
  // A stamp dropped since the previous sample (early, or out of order) took a period of its own.
  ticks = std::max(ticks, 1.0 + skipped_);
  skipped_ = 0;
  last_ticks_ = ticks;
  step_ = period_ > 0.0 && std::abs(dt - ticks * period_) <= period_ ? ticks * period_ : dt;
  tick_ += ticks;
  last_t_ = last_seen_t_ = t;
  addToFit(t);
  if (++since_fit_ >= std::max(kFitInterval, fitWindow() / kFitsPerWindow) && fit_count_ >= kMinFitSamples)
  {
    since_fit_ = 0;
    fitPeriod();
  }
}

void TimeBase::addToFit(double t)
{
  ticks_[fit_next_] = tick_;
  stamps_[fit_next_] = t;
  fit_next_ = (fit_next_ + 1) % kMaxFitSamples;
  fit_count_ = std::min(fit_count_ + 1, kMaxFitSamples);
}

std::size_t TimeBase::fitWindow() const
{
  // The newest stamps spanning kRateWindow (at the current period), at most the ring. Compared
  // as doubles first: a period of 1e-77 s would overflow the count.
  const std::size_t most = std::max(kMinFitSamples, fit_count_);
  const double wanted = period_ > 0.0 ? kRateWindow / period_ : static_cast<double>(fit_count_);
  return wanted >= static_cast<double>(most) ? most : std::max(kMinFitSamples, static_cast<std::size_t>(wanted));
}

void TimeBase::fitPeriod()
{
  const std::size_t n = fitWindow();
  auto at = [&](std::size_t k) {  // k = 0 the oldest of the n used
    return (fit_next_ + kMaxFitSamples - n + k) % kMaxFitSamples;
  };
  // Relative to the oldest entry: stamps since the epoch would lose the period's digits.
  const double tick0 = ticks_[at(0)], stamp0 = stamps_[at(0)];
  auto line = [&](double threshold, double slope, double offset, double* new_slope, double* new_offset) {
    double sx = 0, sy = 0, sxx = 0, sxy = 0, count = 0;
    for (std::size_t k = 0; k < n; ++k)
    {
      const double x = ticks_[at(k)] - tick0, y = stamps_[at(k)] - stamp0;
      if (std::abs(y - offset - slope * x) > threshold)
        continue;
      sx += x;
      sy += y;
      sxx += x * x;
      sxy += x * y;
      ++count;
    }
    const double denominator = count * sxx - sx * sx;
    if (count < 2 || denominator <= 0.0)
      return false;
    *new_slope = (count * sxy - sx * sy) / denominator;
    *new_offset = (sy - *new_slope * sx) / count;
    return true;
  };
  double slope = 0.0, offset = 0.0;
  if (!line(INFINITY, 0.0, 0.0, &slope, &offset))
    return;
  scratch_.clear();
  for (std::size_t k = 0; k < n; ++k)
    scratch_.push_back(std::abs(stamps_[at(k)] - stamp0 - offset - slope * (ticks_[at(k)] - tick0)));
  const double sigma = 1.4826 * upperMedian(scratch_.begin(), scratch_.end());
  const double threshold = std::max(4.0 * sigma, 1e-3 * period_);
  double refined = slope;
  if (line(threshold, slope, offset, &refined, &offset) && refined > 0.0 &&
      std::abs(refined - period_) < kRateChange * period_)
  {
    period_ = refined;
    has_line_ = true;
    line_tick_ = tick_;
    line_stamp_ = stamp0 + offset + refined * (tick_ - tick0);
  }
}

}  // namespace periodic_bias_compensation
