#include "periodic_bias_compensation/tools/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "periodic_bias_compensation/common/numeric.h"
#include "periodic_bias_compensation/core/raw_integrator.h"

namespace periodic_bias_compensation::metrics
{
Scorer::Scorer(const sim::Sample& first, double settle) : slow0_(first.truth.slow_position), settle_(settle)
{
}

void Scorer::add(const sim::Sample& s, const Vector3& slow, const Vector3& wave)
{
  for (std::size_t c = 0; c < kCheckpoints.size(); ++c)
    if (!checkpoint_done_[c] && s.elapsed >= kCheckpoints[c] - 0.1)
    {
      checkpoint_done_[c] = true;
      slow_at_[c] = (slow - (s.truth.slow_position - slow0_)).cwiseAbs();
    }
  if (s.elapsed < settle_)
    return;
  const Vector3 e = wave - s.truth.wave_position;
  error2_ += e.cwiseProduct(e);
  truth2_ += s.truth.wave_position.cwiseProduct(s.truth.wave_position);
  truth_sum_ += s.truth.wave_position;
  const Vector3 slow_error = slow - (s.truth.slow_position - slow0_);
  const Vector3 total_error = slow + wave - (s.truth.position - slow0_);
  slow2_ += slow_error.cwiseProduct(slow_error);
  total2_ += total_error.cwiseProduct(total_error);
  ++n_;
}

Errors Scorer::finish(const sim::Sample& last, const Vector3& slow, const Vector3& wave) const
{
  Errors errors;
  errors.slow_at = slow_at_;
  errors.slow_final = (slow - (last.truth.slow_position - slow0_)).cwiseAbs();
  errors.total_final = (slow + wave - (last.truth.position - slow0_)).cwiseAbs();
  for (int i = 0; i < 3; ++i)
    if (truth2_[i] > 0.0)
      errors.wave_rms_percent[i] = 100.0 * std::sqrt(error2_[i] / truth2_[i]);
  if (n_ > 0)
  {
    const Vector3 mean = truth_sum_ / n_;
    for (int i = 0; i < 3; ++i)
    {
      const double truth_std = std::sqrt(std::max(0.0, truth2_[i] / n_ - mean[i] * mean[i]));
      if (truth_std > 0.0)
        errors.wave_hs_percent[i] = 100.0 * std::sqrt(error2_[i] / n_) / (4.0 * truth_std);
    }
    errors.slow_rms = (slow2_ / n_).cwiseSqrt();
    errors.total_rms = (total2_ / n_).cwiseSqrt();
  }
  return errors;
}

PeriodScorer::PeriodScorer(const CompensatorConfig& config, double rate) : config_(config)
{
  const int window = std::max(16, static_cast<int>(std::lround(config.fft_window * rate)));
  for (auto& tracker : truth_)
    tracker = std::make_unique<FrequencyTracker>(window, rate);
  hop_ = std::max(1, static_cast<int>(std::lround(config.fft_hop * rate)));
  delay_ = std::clamp(static_cast<int>(std::lround(kSearchDelay * rate)), 1, hop_);
  rate_ = rate;
}

void PeriodScorer::add(const sim::Sample& s, const CompensatorOutput& out)
{
  for (int i = 0; i < 3; ++i)
  {
    truth_[i]->push(s.truth.wave_acceleration[i], s.t);
    if (out.axes[i].locked && std::isnan(errors_.lock_time[i]))
      errors_.lock_time[i] = s.elapsed;
  }
  ++since_hop_;
  if (since_hop_ == delay_ && due_)
  {
    due_ = false;
    for (int i = 0; i < 3; ++i)
    {
      if (std::isnan(errors_.lock_time[i]))
        continue;
      ++hops_[i];
      if (!out.axes[i].locked)
        continue;
      ++locked_[i];
      if (at_hop_[i] > 0.0)
        relative_[i].push_back(100.0 * std::abs(out.axes[i].frequency - at_hop_[i]) / at_hop_[i]);
    }
  }
  if (since_hop_ < hop_)
    return;
  since_hop_ = 0;
  due_ = true;
  for (int i = 0; i < 3; ++i)
  {
    // Over the same span the compensator's search uses (analyseFreshest, same rule).
    int span = 0;
    at_hop_[i] = truth_[i]
                     ->analyseFreshest(config_.min_frequency, config_.max_frequency, 1.0,
                                       static_cast<int>(kRecentFftWindow * rate_), &span)
                     .frequency;
  }
}

PeriodErrors PeriodScorer::finish() const
{
  PeriodErrors e = errors_;
  for (int i = 0; i < 3; ++i)
  {
    if (hops_[i] > 0)
      e.locked_percent[i] = 100.0 * locked_[i] / hops_[i];
    e.error_median[i] = percentile(relative_[i], 0.5);
    e.error_p95[i] = percentile(relative_[i], 0.95);
  }
  return e;
}

HighPass::HighPass(double cutoff, double rate)
{
  const double k = std::tan(M_PI * cutoff / rate);
  b_ = 1.0 / (1.0 + k);
  a_ = (1.0 - k) / (1.0 + k);
}

Vector3 HighPass::operator()(const Vector3& x)
{
  y_ = b_ * (x - x_) + a_ * y_;
  x_ = x;
  return y_;
}

Errors highPassBaseline(const std::vector<sim::Sample>& samples, double gravity, double settle)
{
  const double rate = (samples.size() - 1) / (samples.back().stamp - samples.front().stamp);
  HighPass hp_a(0.1, rate), hp_v(0.1, rate), hp_p(0.1, rate);
  Vector3 v = Vector3::Zero(), p = Vector3::Zero();
  Scorer scorer(samples.front(), settle);
  Vector3 position = Vector3::Zero();
  for (std::size_t k = 1; k < samples.size(); ++k)
  {
    const sim::Sample& s = samples[k];
    const double dt = s.stamp - samples[k - 1].stamp;
    v += hp_a(s.orientation * s.accel - Vector3(0, 0, gravity)) * dt;
    p += hp_v(v) * dt;
    position = hp_p(p);
    scorer.add(s, Vector3::Zero(), position);
  }
  return scorer.finish(samples.back(), Vector3::Zero(), position);
}

Errors causalBound(const std::vector<sim::Sample>& samples, double gravity, double settle, const Vector3& lever_arm)
{
  const long n = static_cast<long>(samples.size());
  const double rate = (n - 1) / (samples.back().stamp - samples.front().stamp);
  const int spacing = std::max(1, static_cast<int>(std::lround(kBoundStep * rate)));
  const long taps =
      std::max(1L, std::min(static_cast<long>(std::lround(kBoundSpan * rate / spacing)), n / (4 * spacing)));
  // Fit rows every 0.1 s: more rows than taps by far, fewer than samples.
  const int stride = std::max(1, static_cast<int>(std::lround(0.1 * rate)));
  std::array<std::vector<double>, 3> low;  // the acceleration through two moving averages
  std::array<std::vector<double>, 3> target;
  std::vector<Vector3> lever(n);
  for (auto& v : low)
    v.resize(n);
  for (auto& v : target)
    v.resize(n);
  std::array<std::vector<double>, 2> boxes{ std::vector<double>(spacing, 0.0), std::vector<double>(spacing, 0.0) };
  for (int i = 0; i < 3; ++i)
  {
    double first = 0.0, second = 0.0;
    std::fill(boxes[0].begin(), boxes[0].end(), 0.0);
    std::fill(boxes[1].begin(), boxes[1].end(), 0.0);
    for (long k = 0; k < n; ++k)
    {
      const sim::Sample& s = samples[k];
      const double a = (s.orientation * s.accel - Vector3(0, 0, gravity))[i];
      const int slot = static_cast<int>(k % spacing);
      first += a - boxes[0][slot];
      boxes[0][slot] = a;
      second += first / spacing - boxes[1][slot];
      boxes[1][slot] = first / spacing;
      low[i][k] = second / spacing;
      if (i == 0)
        lever[k] = s.truth.attitude * lever_arm - lever_arm;
      target[i][k] = s.truth.wave_position[i] + lever[k][i];
    }
  }
  // Row k: the low-passed values at k, k - spacing, ... (zero before the first sample) and 1.
  const auto row = [&](int i, long k, Eigen::VectorXd* x) {
    for (long j = 0; j < taps; ++j)
    {
      const long at = k - j * spacing;
      (*x)[j] = at >= 0 ? low[i][at] : 0.0;
    }
    (*x)[taps] = 1.0;
  };
  const long half = n / 2;
  std::vector<Vector3> estimate(n, Vector3::Zero());
  Eigen::VectorXd x(taps + 1);
  for (int i = 0; i < 3; ++i)
    for (int fold = 0; fold < 2; ++fold)
    {
      // Rows with the whole span of history only.
      const long full = (taps - 1) * spacing;
      const long begin = fold == 0 ? full : std::max(half, full), end = fold == 0 ? half : n;
      const long rows = (end - begin + stride - 1) / stride;
      Eigen::MatrixXd design(rows, taps + 1);
      Eigen::VectorXd truth(rows);
      for (long r = 0; r < rows; ++r)
      {
        row(i, begin + r * stride, &x);
        design.row(r) = x.transpose();
        truth[r] = target[i][begin + r * stride];
      }
      Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(taps + 1, taps + 1);
      normal.selfadjointView<Eigen::Lower>().rankUpdate(design.transpose());
      normal = normal.selfadjointView<Eigen::Lower>();
      // A ridge of 1e-9 of the mean diagonal: the solution, not a prior.
      normal.diagonal().array() += 1e-9 * normal.diagonal().mean();
      const Eigen::VectorXd weights = normal.ldlt().solve(design.transpose() * truth);
      // Applied to the other half.
      const long other_begin = fold == 0 ? half : 0, other_end = fold == 0 ? n : half;
      for (long k = other_begin; k < other_end; ++k)
      {
        row(i, k, &x);
        estimate[k][i] = x.dot(weights);
      }
    }
  Scorer scorer(samples.front(), settle + kBoundSpan);
  const Vector3 slow0 = samples.front().truth.slow_position;
  for (long k = 1; k < n; ++k)
    scorer.add(samples[k], samples[k].truth.slow_position - slow0, estimate[k] - lever[k]);
  return scorer.finish(samples.back(), samples.back().truth.slow_position - slow0, estimate[n - 1] - lever[n - 1]);
}

Errors integrateRaw(const std::vector<sim::Sample>& samples, double gravity)
{
  Scorer scorer(samples.front(), std::numeric_limits<double>::infinity());
  RawIntegrator raw;
  for (std::size_t k = 0; k < samples.size(); ++k)
  {
    raw.add(samples[k].stamp, samples[k].orientation * samples[k].accel - Vector3(0, 0, gravity), false);
    if (k > 0)
      scorer.add(samples[k], raw.position(), Vector3::Zero());
  }
  return scorer.finish(samples.back(), raw.position(), Vector3::Zero());
}

double percentile(std::vector<double> values, double share)
{
  if (values.empty())
    return NAN;
  const std::size_t k = std::min(values.size() - 1, static_cast<std::size_t>(share * values.size()));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[k];
}

double median(std::vector<double> values)
{
  values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }), values.end());
  return periodic_bias_compensation::median(std::move(values));
}
}  // namespace periodic_bias_compensation::metrics
