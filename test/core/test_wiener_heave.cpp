// WienerHeave: displacement and velocity from the measured spectrum, on a broad sea written
// here (not the simulator's), with bias wander, at several rates; nothing when there is no sea.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <memory>
#include <random>
#include <vector>

#include "../../src/core/background.h"
#include "periodic_bias_compensation/core/heave_filter.h"
#include "periodic_bias_compensation/core/wiener_heave.h"

namespace periodic_bias_compensation
{
namespace
{
/// A long-crested sea of `count` components with a Pierson-Moskowitz-shaped spectrum peaked at
/// fp [Hz] (0.6 fp .. 4 fp), significant height hs [m], random phases.
struct Sea
{
  Sea(double fp, double hs, unsigned seed, int count = 120)
    : Sea(0.6 * fp, (4.0 * fp - 0.6 * fp) / count, count, hs, seed,
          [fp](double f) { return std::pow(f, -5.0) * std::exp(-1.25 * std::pow(fp / f, 4.0)); })
  {
  }
  /// Displacement, velocity and acceleration at t.
  void at(double t, double* x, double* v, double* a) const
  {
    *x = *v = *a = 0.0;
    for (size_t k = 0; k < frequency.size(); ++k)
    {
      const double w = 2.0 * M_PI * frequency[k], angle = w * t + phase[k];
      *x += amplitude[k] * std::sin(angle);
      *v += amplitude[k] * w * std::cos(angle);
      *a -= amplitude[k] * w * w * std::sin(angle);
    }
  }
  /// A narrow swell: `count` components of a Gaussian spectrum of relative width `width` about
  /// fp, significant height hs.
  static Sea swell(double fp, double hs, unsigned seed, double width, int count = 60)
  {
    return Sea((1.0 - 3.0 * width) * fp, 6.0 * width * fp / count, count, hs, seed,
               [fp, width](double f) { return std::exp(-0.5 * std::pow((f - fp) / (width * fp), 2.0)); });
  }
  /// This sea and `other` together.
  Sea operator+(const Sea& other) const
  {
    Sea sum = *this;
    sum.frequency.insert(sum.frequency.end(), other.frequency.begin(), other.frequency.end());
    sum.amplitude.insert(sum.amplitude.end(), other.amplitude.begin(), other.amplitude.end());
    sum.phase.insert(sum.phase.end(), other.phase.begin(), other.phase.end());
    return sum;
  }
  std::vector<double> frequency, amplitude, phase;

private:
  /// `count` components, one at random in each of the bins of width df from lo, their amplitudes
  /// from the spectrum's `shape` scaled to significant height hs, random phases.
  template <typename Shape>
  Sea(double lo, double df, int count, double hs, unsigned seed, Shape shape)
  {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double m0 = 0.0;
    for (int k = 0; k < count; ++k)
    {
      const double f = lo + (k + u(rng)) * df;
      const double s = shape(f);
      frequency.push_back(f);
      amplitude.push_back(s * df);
      phase.push_back(2.0 * M_PI * u(rng));
      m0 += s * df;
    }
    for (double& a : amplitude)
      a = std::sqrt(2.0 * a * hs * hs / 16.0 / m0);
  }
};

struct Errors
{
  double position = 0.0;  ///< RMS error after the settling time / RMS displacement
  double velocity = 0.0;
  double fixed = 0.0;    ///< the same for HeaveFilter's displacement
  double largest = 0.0;  ///< largest |displacement output| [m]
  long valid = 0;
};

/// Runs `duration` s at `rate` with white noise of density 0.004 m/s^2/sqrt(Hz), a constant bias,
/// a bias random walk and a periodic bias of `periodic` m/s^2 at a 240 s period; errors counted
/// from `settle` s on. `vertical`: WienerHeave's vertical axis; `manoeuvring`: a horizontal
/// axis whose record always holds a manoeuvre (Welch's estimate alone).
Errors run(const Sea* sea, double rate, double duration, double random_walk, double settle, unsigned seed,
           bool vertical = false, double periodic = 0.0, bool manoeuvring = false)
{
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double density = 0.004, sigma = density * std::sqrt(rate / 2.0);
  WienerHeave heave(0.03, vertical);
  HeaveFilter fixed;
  double walk = 0.0, e_x = 0.0, e_v = 0.0, e_f = 0.0, s_x = 0.0, s_v = 0.0;
  Errors errors;
  for (long i = 0; i < static_cast<long>(duration * rate); ++i)
  {
    const double t = i / rate;
    double x = 0.0, v = 0.0, a = 0.0;
    if (sea)
      sea->at(t, &x, &v, &a);
    walk += random_walk * std::sqrt(1.0 / rate) * normal(rng);
    const double measured = a + 0.05 + walk + periodic * std::sin(2.0 * M_PI * t / 240.0) + sigma * normal(rng);
    if (manoeuvring)
      heave.noteManoeuvre();
    const WienerHeaveOutput out = heave.update(measured, 1.0 / rate, density * density);
    const double fixed_position = fixed.update(measured, 1.0 / rate).position;
    if (!out.valid)
      continue;
    ++errors.valid;
    EXPECT_TRUE(std::isfinite(out.position) && std::isfinite(out.velocity) && out.error_variance >= 0.0);
    errors.largest = std::max(errors.largest, std::abs(out.position));
    if (t < settle)
      continue;
    e_x += std::pow(out.position - x, 2);
    e_v += std::pow(out.velocity - v, 2);
    e_f += std::pow(fixed_position - x, 2);
    s_x += x * x;
    s_v += v * v;
  }
  errors.position = s_x > 0.0 ? std::sqrt(e_x / s_x) : 0.0;
  errors.velocity = s_v > 0.0 ? std::sqrt(e_v / s_v) : 0.0;
  errors.fixed = s_x > 0.0 ? std::sqrt(e_f / s_x) : 0.0;
  return errors;
}
}  // namespace

// A wind sea (peak 8 s) and a swell (peak 15 s), with the bias random walk of a low-cost sensor,
// once the spectrum has been measured for five minutes: displacement within 15 % of its RMS on
// the wind sea and 25 % on the swell (whose lower flank reaches down to the band edge), in either
// case under half the fixed filter's error; velocity within 15 %.
TEST(WienerHeave, BroadSeasWithBiasWander)
{
  const Sea wind(1.0 / 8.0, 1.8, 3), swell(1.0 / 15.0, 3.5, 4);
  for (const Sea* sea : { &wind, &swell })
  {
    const Errors e = run(sea, 50.0, 900.0, 6e-4, 300.0, 7);
    std::printf("[%s] displacement error %.3f (fixed filter %.3f), velocity %.3f of the RMS\n",
                sea == &wind ? "wind sea" : "swell", e.position, e.fixed, e.velocity);
    EXPECT_LT(e.position, sea == &wind ? 0.15 : 0.25) << (sea == &wind ? "wind sea" : "swell");
    EXPECT_LT(e.position, 0.5 * e.fixed);
    EXPECT_LT(e.velocity, 0.15);
  }
}

// The vertical axis's long records take Burg's estimate: on the same seas with a slow periodic
// bias (0.04 m/s^2 at 240 s, below the band) besides the walk, its displacement error from 5 to
// 15 min is under Welch's (a horizontal record holding a manoeuvre) on the swell and within a
// tenth of it on the wind sea, and within the limits above. A horizontal record without a
// manoeuvre takes the same estimate: the same error, to the last bit.
TEST(WienerHeave, VerticalLongRecordsByBurg)
{
  const Sea wind(1.0 / 8.0, 1.8, 3), swell(1.0 / 15.0, 3.5, 4);
  for (const Sea* sea : { &wind, &swell })
  {
    const Errors burg = run(sea, 50.0, 900.0, 6e-4, 300.0, 7, true, 0.04);
    const Errors welch = run(sea, 50.0, 900.0, 6e-4, 300.0, 7, false, 0.04, true);
    const Errors quiet = run(sea, 50.0, 900.0, 6e-4, 300.0, 7, false, 0.04);
    EXPECT_EQ(quiet.position, burg.position) << "a horizontal record without a manoeuvre";
    std::printf("[%s] displacement error %.3f (Welch %.3f), velocity %.3f of the RMS\n",
                sea == &wind ? "wind sea" : "swell", burg.position, welch.position, burg.velocity);
    EXPECT_LT(burg.position, sea == &wind ? 0.15 : 0.25);
    EXPECT_LT(burg.velocity, 0.15);
    if (sea == &swell)
      EXPECT_LT(burg.position, welch.position);
    else
      EXPECT_LT(burg.position, 1.1 * welch.position);
  }
}

// A horizontal record takes Burg's estimate only while its design window holds no manoeuvre: one
// noted at 300 s gives the designs of the next kDesignWindow the outputs of a record that holds
// one throughout, exactly, and once the window has passed it the outputs differ again.
TEST(WienerHeave, HorizontalRecordsWithAManoeuvreKeepWelch)
{
  const Sea swell(1.0 / 15.0, 3.5, 4);
  const double rate = 20.0, sigma = 0.004 * std::sqrt(rate / 2.0);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  WienerHeave noted(0.03), manoeuvring(0.03);
  long compared = 0, equal = 0;
  bool differs_before = false, differs_after = false;
  const double at = 300.0, window = WienerHeave::kDesignWindow;
  for (long i = 0; i < static_cast<long>((at + window + 200.0) * rate); ++i)
  {
    const double t = i / rate;
    double x, v, a;
    swell.at(t, &x, &v, &a);
    a += 0.05 + sigma * normal(rng);
    if (i == static_cast<long>(at * rate))
      noted.noteManoeuvre();
    manoeuvring.noteManoeuvre();
    const WienerHeaveOutput p = noted.update(a, 1.0 / rate, 1e-5), q = manoeuvring.update(a, 1.0 / rate, 1e-5);
    if (t > 2.0 * WienerHeave::kSegment * WienerHeave::kDesignPeriod + 10.0 && t < at)
      differs_before |= p.position != q.position;
    if (t > at + 40.0 && t < at + window - 10.0)
    {
      ++compared;
      equal += p.position == q.position ? 1 : 0;
    }
    if (t > at + window + WienerHeave::kRedesignInterval + 10.0)
      differs_after |= p.position != q.position;
  }
  EXPECT_TRUE(differs_before) << "a long record without a manoeuvre";
  EXPECT_EQ(equal, compared);
  EXPECT_TRUE(differs_after) << "once the window has passed the manoeuvre";
}

// The first minutes: designs from records of 50 s to 4 min take each record as one segment
// (short Welch segments put a 15 s swell inside the main lobe of zero frequency). From 60 s to
// 240 s the displacement is within 29 % of its RMS on the swell, 12 % on the wind sea (with
// segments of 32 s and 64 s: 36 % and 14 %).
TEST(WienerHeave, ShortRecordsResolveASwell)
{
  const Sea wind(1.0 / 8.0, 1.8, 3), swell(1.0 / 15.0, 3.5, 4);
  for (const Sea* sea : { &wind, &swell })
  {
    const Errors e = run(sea, 50.0, 240.0, 6e-4, 60.0, 7);
    std::printf("[%s] displacement error from 60 to 240 s %.3f of the RMS\n", sea == &wind ? "wind sea" : "swell",
                e.position);
    EXPECT_LT(e.position, sea == &wind ? 0.12 : 0.29) << (sea == &wind ? "wind sea" : "swell");
  }
}

// The vertical axis's first minute: its short records take Burg's estimate while a window
// cannot resolve the displacement's peak from zero frequency. A 15 s swell (a narrow
// Gaussian spectrum) under a 5.5 s wind sea, with the walk and the slow periodic bias, on two
// seas whose swell is there from the start: from 20 to 60 s the displacement error is below the
// horizontal axis's (Welch alone, from 20 s, a record holding a manoeuvre) on each, and by more
// than a tenth over both.
TEST(WienerHeave, VerticalFirstMinuteByBurg)
{
  double burg2 = 0.0, welch2 = 0.0;
  for (const unsigned seed : { 25u, 27u })
  {
    const Sea sea = Sea::swell(1.0 / 15.0, 2.0, seed, 0.07) + Sea(1.0 / 5.5, 1.2, seed + 1);
    const Errors burg = run(&sea, 50.0, 60.0, 6e-4, 20.0, 7, true, 0.04);
    const Errors welch = run(&sea, 50.0, 60.0, 6e-4, 20.0, 7, false, 0.04, true);
    std::printf("[sea %u] displacement error from 20 to 60 s %.3f of the RMS (Welch %.3f)\n", seed, burg.position,
                welch.position);
    EXPECT_LT(burg.position, 0.7) << "sea " << seed;
    EXPECT_LT(burg.position, welch.position) << "sea " << seed;
    burg2 += burg.position * burg.position;
    welch2 += welch.position * welch.position;
  }
  EXPECT_LT(std::sqrt(burg2 / welch2), 0.9);
}

// A single line (a shaken bench) on a short vertical record: the window resolves it, so Burg's
// model of a short record, which splits a line and puts part of it at the band's edge, is not
// taken. Every design puts the peak within a tenth of the line (the owner counts a lock farther
// than that from the design's peak as off it), and the displacement stays within 15 % of its RMS
// from 15 s on.
TEST(WienerHeave, ShortRecordsKeepALineWhereItIs)
{
  std::mt19937_64 rng(3);
  const double rate = 100.0, sigma = 0.003 * std::sqrt(rate / 2.0), w = 2.0 * M_PI * 0.443;
  WienerHeave heave(0.03, true);
  double error2 = 0.0, truth2 = 0.0;
  std::normal_distribution<double> normal(0.0, 1.0);
  for (long i = 0; i < static_cast<long>(140 * rate); ++i)
  {
    const double t = i / rate, x = 0.01 * std::sin(w * t + 1.9);
    const WienerHeaveOutput out = heave.update(-w * w * x + 0.025 + sigma * normal(rng), 1.0 / rate, 0.003 * 0.003);
    if (heave.designed())
    {
      ASSERT_NEAR(heave.peakFrequency(), 0.443, 0.1 * 0.443) << "at " << t << " s";
    }
    if (out.valid && t >= 15.0)
    {
      error2 += (out.position - x) * (out.position - x);
      truth2 += x * x;
    }
  }
  EXPECT_LT(std::sqrt(error2 / truth2), 0.15);
}

// The design rate is about 2 Hz whatever the input's: the same sea at 10, 87.7 and 400 Hz.
TEST(WienerHeave, AnyInputRate)
{
  const Sea wind(1.0 / 8.0, 1.8, 5);
  for (double rate : { 10.0, 87.7, 400.0 })
  {
    const Errors e = run(&wind, rate, 600.0, 0.0, 200.0, 11);
    EXPECT_GT(e.valid, 0) << rate;
    EXPECT_LT(e.position, 0.15) << rate << " Hz";
  }
}

// Above kMaxPhases / kDesignPeriod (256 Hz) the filter keeps kMaxPhases phases of the design-rate
// period and extrapolates its last two outputs to the samples between. On a 2 kHz stream (a wind
// sea and a swell, noise, a constant bias and a bias random walk), against the full-rate filter
// that keeps every phase: the same outputs at the kept phases; every sample valid in both but the
// few before the second kept phase; and between kept phases a difference of at most a thousandth
// of the significant wave height (of four standard deviations of the velocity for the velocity),
// its RMS under a thousandth of the filter's own RMS error.
TEST(WienerHeave, KeptPhasesFollowTheFullRateFilter)
{
  const Sea wind(1.0 / 8.0, 1.8, 5), swell(1.0 / 15.0, 1.2, 6);
  const double rate = 2000.0, density = 0.004, sigma = density * std::sqrt(rate / 2.0);
  const int decimation = static_cast<int>(std::lround(WienerHeave::kDesignPeriod * rate));
  ASSERT_GT(decimation, WienerHeave::kMaxPhases);
  std::vector<bool> kept_phase(decimation, false);
  for (int ring = 0; ring < WienerHeave::kMaxPhases; ++ring)
    kept_phase[static_cast<long>(ring) * decimation / WienerHeave::kMaxPhases] = true;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  WienerHeave kept(0.03, true), full(0.03, true);
  full.setMaxPhases(decimation);
  double walk = 0.0, largest_x = 0.0, largest_v = 0.0, difference2 = 0.0, error2 = 0.0, truth_x2 = 0.0, truth_v2 = 0.0;
  long both = 0, only_full = 0, only_kept = 0, exact = 0, inexact = 0;
  for (long i = 0; i < static_cast<long>(400 * rate); ++i)
  {
    const double t = i / rate;
    double x = 0.0, v = 0.0, a = 0.0, xs = 0.0, vs = 0.0, as = 0.0;
    wind.at(t, &x, &v, &a);
    swell.at(t, &xs, &vs, &as);
    walk += 4e-4 * std::sqrt(1.0 / rate) * normal(rng);
    const double measured = a + as + 0.05 + walk + sigma * normal(rng);
    const WienerHeaveOutput k = kept.update(measured, 1.0 / rate, density * density);
    const WienerHeaveOutput f = full.update(measured, 1.0 / rate, density * density);
    truth_x2 += std::pow(x + xs, 2);
    truth_v2 += std::pow(v + vs, 2);
    only_full += f.valid && !k.valid;
    only_kept += k.valid && !f.valid;
    if (!(k.valid && f.valid))
      continue;
    ++both;
    if (kept_phase[i % decimation])
      (k.position == f.position && k.velocity == f.velocity ? exact : inexact) += 1;
    largest_x = std::max(largest_x, std::abs(k.position - f.position));
    largest_v = std::max(largest_v, std::abs(k.velocity - f.velocity));
    difference2 += std::pow(k.position - f.position, 2);
    error2 += std::pow(f.position - x - xs, 2);
  }
  const long samples = static_cast<long>(400 * rate);
  const double hs = 4.0 * std::sqrt(truth_x2 / samples), velocity_scale = 4.0 * std::sqrt(truth_v2 / samples);
  ASSERT_GT(both, static_cast<long>(300 * rate));
  EXPECT_GT(exact, both / (2 * decimation / WienerHeave::kMaxPhases));
  EXPECT_EQ(inexact, 0);
  EXPECT_LE(only_full, 2 * (decimation / WienerHeave::kMaxPhases + 1));
  EXPECT_EQ(only_kept, 0);
  EXPECT_LT(largest_x, 1e-3 * hs);
  EXPECT_LT(largest_v, 1e-3 * velocity_scale);
  EXPECT_LT(std::sqrt(difference2), 1e-3 * std::sqrt(error2));
  std::printf(
      "kept phases against the full-rate filter: at most %.2g m and %.2g m/s apart (Hs %.2f m); RMS %.2g m "
      "against the filter's error of %.2g m\n",
      largest_x, largest_v, hs, std::sqrt(difference2 / both), std::sqrt(error2 / both));
}

// A swell of 20 s: the FIR spans six peak periods (120 s at most), but never more than the input
// held since the start (the first design, from about 20 s, would read zeros beyond it).
TEST(WienerHeave, FirstDesignsReadOnlyTheInputHeld)
{
  const Sea swell(1.0 / 20.0, 2.5, 3);
  const double rate = 20.0;
  for (const bool vertical : { false, true })
  {
    WienerHeave heave(0.03, vertical);
    double first_span = 0.0, first_time = 0.0;
    for (long i = 0; i < static_cast<long>(400 * rate); ++i)
    {
      double x, v, a;
      swell.at(i / rate, &x, &v, &a);
      heave.update(a, 1.0 / rate, 1e-5);
      if (first_span == 0.0 && heave.span() > 0.0)
      {
        first_span = heave.span();
        first_time = i / rate;
      }
    }
    ASSERT_GT(first_span, 0.0);
    EXPECT_LE(first_span, first_time);
    EXPECT_GT(first_span, 0.8 * first_time);
    EXPECT_NEAR(heave.span(), std::min(WienerHeave::kMaxSpan, WienerHeave::kSpanPeriods / heave.peakFrequency()), 1.0);
  }
}

// The owner's period refined by a little (its time base's line fit) changes nothing; a new rate
// starts the record over, sized for it.
TEST(WienerHeave, ANewRateStartsOver)
{
  const Sea wind(1.0 / 8.0, 1.8, 5);
  WienerHeave heave(0.03);
  const auto decimation = [](double rate) { return static_cast<int>(std::lround(WienerHeave::kDesignPeriod * rate)); };
  double x, v, a;
  long i = 0;
  for (; i < 60 * 50; ++i)
  {
    wind.at(i / 50.0, &x, &v, &a);
    heave.update(a, (i % 2 ? 1.004 : 0.996) / 50.0, 1e-5);
  }
  EXPECT_EQ(heave.decimation(), decimation(50.0));
  ASSERT_TRUE(heave.designed());
  const double peak = heave.peakFrequency();
  wind.at(i / 50.0, &x, &v, &a);
  EXPECT_TRUE(heave.update(a, 1.05 / 50.0, 1e-5).valid);  // within kPeriodChange
  EXPECT_EQ(heave.decimation(), decimation(50.0));
  EXPECT_EQ(heave.peakFrequency(), peak);
  EXPECT_FALSE(heave.update(a, 1.0 / 100.0, 1e-5).valid);  // 100 Hz: a new record
  EXPECT_EQ(heave.decimation(), decimation(100.0));
  EXPECT_FALSE(heave.designed());
  // Unknown (0) or absurd periods are not taken and change nothing.
  EXPECT_FALSE(heave.update(a, 0.0, 1e-5).valid);
  EXPECT_EQ(heave.decimation(), decimation(100.0));
}

// No sea, a bias that wanders (random walk and a 60 s drift of 0.06 m/s^2): no heave, on either
// axis's spectrum estimate.
TEST(WienerHeave, NoSeaNoHeave)
{
  std::mt19937_64 rng(2);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double rate = 50.0, sigma = 0.004 * std::sqrt(rate / 2.0);
  for (const bool vertical : { false, true })
  {
    WienerHeave heave(0.03, vertical);
    double walk = 0.0, largest = 0.0;
    long valid = 0;
    for (long i = 0; i < static_cast<long>(900 * rate); ++i)
    {
      const double t = i / rate;
      walk += 6e-4 * std::sqrt(1.0 / rate) * normal(rng);
      const double a = 0.05 + walk + 0.06 * std::sin(2.0 * M_PI * t / 60.0) + sigma * normal(rng);
      const WienerHeaveOutput out = heave.update(a, 1.0 / rate, 0.004 * 0.004);
      if (out.valid)
      {
        ++valid;
        largest = std::max(largest, std::abs(out.position));
      }
    }
    EXPECT_GT(valid, 0);
    EXPECT_LT(largest, 0.02) << (vertical ? "vertical" : "horizontal");
  }
}

// Nothing before the first design, and reset() starts over; a copy runs on its own.
TEST(WienerHeave, FirstDesignResetAndCopy)
{
  const Sea wind(1.0 / 8.0, 1.8, 9);
  const double rate = 20.0;
  WienerHeave heave(0.03);
  double first_valid = -1.0;
  for (long i = 0; i < static_cast<long>(200 * rate); ++i)
  {
    double x, v, a;
    wind.at(i / rate, &x, &v, &a);
    if (heave.update(a, 1.0 / rate, 1e-5).valid && first_valid < 0.0)
      first_valid = i / rate;
  }
  // kFirstDesign of data after the low-pass's two averages have filled
  EXPECT_NEAR(first_valid, WienerHeave::kFirstDesign + 2 * WienerHeave::kDesignPeriod, 1.0);
  EXPECT_GT(heave.peakFrequency(), 0.6 / 8.0);
  EXPECT_LT(heave.peakFrequency(), 1.4 / 8.0);
  WienerHeave copy = heave;
  double x, v, a;
  wind.at(200.0, &x, &v, &a);
  const WienerHeaveOutput original = heave.update(a, 1.0 / rate, 1e-5);
  const WienerHeaveOutput copied = copy.update(a, 1.0 / rate, 1e-5);
  EXPECT_EQ(original.position, copied.position);
  heave.reset();
  EXPECT_FALSE(heave.update(a, 1.0 / rate, 1e-5).valid);
  EXPECT_EQ(heave.peakFrequency(), 0.0);
}

// reset() keeps the buffers (sized for the rate) but nothing of what they held: after a large swell
// and a reset, a small wind sea gives what a fresh instance gives, sample for sample, with its
// companions too.
TEST(WienerHeave, AResetLeavesNothingOfTheRecordBefore)
{
  const Sea swell(1.0 / 14.0, 12.0, 5), wind(1.0 / 6.0, 1.0, 6), other(1.0 / 9.0, 0.8, 7);
  const double rate = 40.0;
  for (const bool vertical : { false, true })
  {
    WienerHeave reused(0.03, vertical, true), fresh(0.03, vertical, true);
    double x, v, a, xo, vo, ao;
    for (long i = 0; i < static_cast<long>(300 * rate); ++i)
    {
      swell.at(i / rate, &x, &v, &a);
      other.at(i / rate, &xo, &vo, &ao);
      reused.update(a, 1.0 / rate, 1e-5, { 2.0 * a, ao });
    }
    reused.reset();
    long valid = 0;
    for (long i = 0; i < static_cast<long>(200 * rate); ++i)
    {
      wind.at(i / rate, &x, &v, &a);
      other.at(i / rate, &xo, &vo, &ao);
      const WienerHeaveOutput r = reused.update(a, 1.0 / rate, 1e-5, { ao, 0.5 * a });
      const WienerHeaveOutput f = fresh.update(a, 1.0 / rate, 1e-5, { ao, 0.5 * a });
      ASSERT_EQ(r.valid, f.valid) << i / rate << " s";
      ASSERT_EQ(r.position, f.position) << i / rate << " s";
      ASSERT_EQ(r.velocity, f.velocity) << i / rate << " s";
      valid += r.valid;
    }
    EXPECT_GT(valid, 100 * rate) << (vertical ? "vertical" : "horizontal");
  }
}

// After restartRecord() (a turn) the last design stays applied but is stale until one from the
// new record, kRestartDesign of it; that design describes the sea met since, not the one before.
TEST(WienerHeave, RestartRecordDesignsFromTheSeaMetSince)
{
  const Sea before(1.0 / 8.0, 1.8, 11), after(1.0 / 4.0, 1.0, 12);
  const double rate = 20.0, dt = 1.0 / rate;
  WienerHeave heave(0.03);
  double x, v, a;
  for (long i = 0; i < static_cast<long>(300 * rate); ++i)
  {
    before.at(i * dt, &x, &v, &a);
    heave.update(a, dt, 1e-5);
  }
  ASSERT_NEAR(heave.peakFrequency(), 1.0 / 8.0, 0.4 / 8.0);
  heave.restartRecord();
  double first_valid = -1.0, stale_output = 0.0;
  for (long i = 0; i < static_cast<long>(90 * rate); ++i)
  {
    after.at(300.0 + i * dt, &x, &v, &a);
    const WienerHeaveOutput out = heave.update(a, dt, 1e-5);
    if (out.valid && first_valid < 0.0)
      first_valid = i * dt;
    if (!out.valid)
      stale_output = std::max(stale_output, std::abs(out.position));
  }
  EXPECT_NEAR(first_valid, WienerHeave::kRestartDesign, 1.0);
  EXPECT_GT(stale_output, 0.0) << "the stale design is still applied (for the owner's fade)";
  EXPECT_NEAR(heave.peakFrequency(), 1.0 / 4.0, 0.4 / 4.0);
}

// Designs made on the core's design thread and taken up kDesignDelay later change nothing against
// designs made in the sample's own call: the same outputs, sample for sample, through the first
// designs, the later ones, a turn (restartRecord) and a gap in the companions. The first design is
// taken up kDesignDelay after the data it was made from.
TEST(WienerHeave, BackgroundDesignsChangeNoOutput)
{
  const Sea sea = Sea(1.0 / 8.0, 2.0, 31) + Sea::swell(1.0 / 14.0, 1.0, 32, 0.05);
  const double rate = 20.0, dt = 1.0 / rate;
  WienerHeave background(0.03, false, true), calling(0.03, false, true);
  calling.setBackgroundDesigns(false);
  std::mt19937_64 rng(33);
  std::normal_distribution<double> normal(0.0, 0.01);
  long differing = 0, valid = 0, first_valid = -1, reads = 0;
  for (long i = 0; i < static_cast<long>(700 * rate); ++i)
  {
    double x, v, a;
    sea.at(i * dt, &x, &v, &a);
    WienerHeave::Companions companions{ a + normal(rng), normal(rng) };
    if (i == static_cast<long>(500 * rate))
      companions[0] = NAN;
    if (i == static_cast<long>(300 * rate))
    {
      background.restartRecord();
      calling.restartRecord();
    }
    const double measured = 0.5 * a + normal(rng);
    const WienerHeaveOutput b = background.update(measured, dt, 1e-4, companions);
    const WienerHeaveOutput c = calling.update(measured, dt, 1e-4, companions);
    if (b.valid != c.valid || b.position != c.position || b.velocity != c.velocity ||
        b.error_variance != c.error_variance || background.peakFrequency() != calling.peakFrequency())
      ++differing;
    valid += b.valid;
    reads += background.readsCompanions();
    if (b.valid && first_valid < 0)
      first_valid = i;
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(valid, static_cast<long>(600 * rate));
  EXPECT_GT(reads, 0) << "a design read the companions";
  // The low-pass's two averages fill (2 D samples), the record reaches kFirstDesign (its first
  // value is the 2 D-th sample's), then kDesignDelay.
  const long decimation = background.decimation();
  const long made = 2 * decimation + std::lround(WienerHeave::kFirstDesign * rate) - decimation;
  EXPECT_EQ(first_valid + 1, made + std::lround(WienerHeave::kDesignDelay * rate));
}

// A sample that must take up a design the design thread has not started makes it itself (offline,
// where samples come faster than designs, the caller and the thread then design side by side):
// with the thread held by another task, the first design is still taken up when due, with the
// outputs of designs made in the call.
TEST(WienerHeave, AWaitingSampleMakesAQueuedDesign)
{
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  // Held once it has started: a task still queued (other tests' designs ahead of it) would be
  // the oldest one a waiting sample takes.
  auto started = std::make_shared<std::promise<void>>();
  std::future<void> running = started->get_future();
  designInBackground([released, started] {
    started->set_value();
    released.wait();
  });
  running.wait();
  const Sea sea(1.0 / 8.0, 2.0, 34);
  const double rate = 20.0, dt = 1.0 / rate;
  auto run = std::async(std::launch::async, [&] {
    WienerHeave background(0.03), calling(0.03);
    calling.setBackgroundDesigns(false);
    long differing = 0, valid = 0;
    for (long i = 0; i < static_cast<long>(60 * rate); ++i)
    {
      double x, v, a;
      sea.at(i * dt, &x, &v, &a);
      const WienerHeaveOutput b = background.update(a, dt, 1e-4);
      const WienerHeaveOutput c = calling.update(a, dt, 1e-4);
      differing += b.valid != c.valid || b.position != c.position || b.velocity != c.velocity;
      valid += b.valid;
    }
    return std::make_pair(differing, valid);
  });
  const bool finished = run.wait_for(std::chrono::seconds(60)) == std::future_status::ready;
  release.set_value();
  ASSERT_TRUE(finished) << "the sample waited for the held design thread";
  const auto [differing, valid] = run.get();
  EXPECT_EQ(differing, 0);
  EXPECT_GT(valid, static_cast<long>(30 * rate));
}

// A sample period no IMU has (a glitch, a fuzzed stream) sizes nothing: no output, no throw.
TEST(WienerHeave, AbsurdPeriodsAreIgnored)
{
  for (double dt : { 1e-300, 1e-9, 20.0, 1e300, -1.0 })
  {
    WienerHeave heave;
    for (int k = 0; k < 10; ++k)
      EXPECT_FALSE(heave.update(0.1, dt, 1e-5).valid) << dt;
    EXPECT_EQ(heave.decimation(), 0) << dt;
  }
}

namespace
{
/// One horizontal axis of a long-crested sea read with and without companions: its wave moves
/// `sway` times the heave's displacement, a quarter period ahead; the axis's accelerometer has
/// `noise` times the heave's white noise and a bias random walk. Companion 0: the vertical
/// axis (the same sea, or `unrelated` a sea of its own); companion 1 white noise alone. Errors
/// from `settle` s on, relative to the sway's RMS; `with` and `without` companions.
struct CompanionErrors
{
  double with = 0.0, without = 0.0;
  bool reads = false;  ///< the last design read the companions
};
CompanionErrors runWithCompanions(const Sea& sea, double duration, double settle, bool unrelated, unsigned seed,
                                  bool finite = true, double gap_at = -1.0)
{
  const double rate = 20.0, dt = 1.0 / rate, density = 0.004, sigma = density * std::sqrt(rate / 2.0);
  const double sway = 0.5, noise = 10.0;
  const Sea other = Sea(1.0 / 6.0, 2.0, seed + 2);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  WienerHeave alone(0.03, false), joint(0.03, false, true);
  double walk = 0.0, e_with = 0.0, e_without = 0.0, s = 0.0;
  for (long i = 0; i < static_cast<long>(duration * rate); ++i)
  {
    const double t = i * dt;
    // A quarter period ahead: the displacement of a component sin(w t + p) becomes cos(w t + p),
    // its acceleration -w^2 cos: the velocity's shape over w.
    double x = 0.0, v = 0.0, a = 0.0, ox = 0.0, ov = 0.0, oa = 0.0;
    sea.at(t, &x, &v, &a);
    double y = 0.0, ay = 0.0;
    for (size_t k = 0; k < sea.frequency.size(); ++k)
    {
      const double w = 2.0 * M_PI * sea.frequency[k], angle = w * t + sea.phase[k];
      y += sway * sea.amplitude[k] * std::cos(angle);
      ay -= sway * sea.amplitude[k] * w * w * std::cos(angle);
    }
    if (unrelated)
      other.at(t, &ox, &ov, &oa);
    walk += 2e-4 * std::sqrt(dt) * normal(rng);
    const double measured = ay + 0.02 + walk + noise * sigma * normal(rng);
    WienerHeave::Companions companions{ (unrelated ? oa : a) + sigma * normal(rng), sigma * normal(rng) };
    if ((!finite && i % 2000 == 0) || (gap_at >= 0.0 && i == static_cast<long>(gap_at * rate)))
      companions[1] = NAN;
    const WienerHeaveOutput without = alone.update(measured, dt, noise * noise * density * density);
    const WienerHeaveOutput with = joint.update(measured, dt, noise * noise * density * density, companions);
    if (t < settle)
      continue;
    EXPECT_TRUE(with.valid && std::isfinite(with.position) && std::isfinite(with.velocity));
    e_with += std::pow(with.position - y, 2);
    e_without += std::pow(without.position - y, 2);
    s += y * y;
  }
  return { std::sqrt(e_with / s), std::sqrt(e_without / s), joint.readsCompanions() };
}
/// A wind sea and a swell.
CompanionErrors runWithCompanions(double duration, double settle, bool unrelated, unsigned seed, bool finite = true,
                                  double gap_at = -1.0)
{
  const Sea sea = Sea(1.0 / 8.0, 2.0, seed) + Sea::swell(1.0 / 14.0, 1.0, seed + 1, 0.05);
  return runWithCompanions(sea, duration, settle, unrelated, seed, finite, gap_at);
}
}  // namespace

// A sway ten times noisier than the heave of the same long-crested sea: the vertical axis says
// what the sway's noise and bias walk hide. Once the record holds kCrossSegments segments the
// design reads it: error less than half what the axis alone gives.
TEST(WienerHeave, CompanionsOfTheSameSea)
{
  const double settle = 4.0 * WienerHeave::kSegment * WienerHeave::kDesignPeriod;
  const CompanionErrors e = runWithCompanions(1800.0, settle, false, 21);
  std::printf("[companions] sway error %.1f %% with the vertical axis read, %.1f %% without\n", 100.0 * e.with,
              100.0 * e.without);
  EXPECT_TRUE(e.reads);
  EXPECT_LT(e.with, 0.5 * e.without);
}

// A narrow long swell alone, the sway a quarter period ahead of the heave: the sway's design reads
// the vertical axis from the record's second Welch segment on (before 448 s, when a design from
// the own density with Welch's cross-spectra beside it would start), and from Welch's matrix
// throughout, the own input's wave included: error two thirds of the axis's own or less over the
// first minutes, and over half an hour (where that mixed design gives three quarters).
TEST(WienerHeave, HorizontalCompanionsOfANarrowSwell)
{
  const Sea swell = Sea::swell(1.0 / 13.0, 2.0, 31, 0.06);
  for (double end : { 440.0, 1800.0 })
  {
    const CompanionErrors e = runWithCompanions(swell, end, 200.0, false, 31);
    std::printf(
        "[companions] narrow swell, 200 to %.0f s: sway error %.1f %% with the vertical axis read, %.1f %% "
        "without\n",
        end, 100.0 * e.with, 100.0 * e.without);
    EXPECT_TRUE(e.reads) << end;
    EXPECT_LT(e.with, 2.0 / 3.0 * e.without) << end;
  }
}

// Companions that hold another sea (and noise): nothing to gain, nothing lost.
TEST(WienerHeave, UnrelatedCompanionsCostNothing)
{
  const CompanionErrors e = runWithCompanions(1800.0, 200.0, true, 22);
  std::printf("[companions] sway error %.1f %% with an unrelated sea's axis read, %.1f %% without\n", 100.0 * e.with,
              100.0 * e.without);
  EXPECT_LT(e.with, 1.03 * e.without);
}

// A companion that is not finite is a gap in its record: no design reads the companions while
// their window holds it, and the output is the axis's own; a gap ends a design that reads them.
TEST(WienerHeave, CompanionGapsAreManoeuvres)
{
  const CompanionErrors e = runWithCompanions(1800.0, 200.0, false, 21, false);
  EXPECT_FALSE(e.reads);
  EXPECT_EQ(e.with, e.without);
  // One gap after the design reads them: the next sample designs from the own input.
  const CompanionErrors gap = runWithCompanions(1200.0 + 1.0 / 20.0, 1200.0, false, 21, true, 1200.0);
  EXPECT_FALSE(gap.reads);
  const CompanionErrors none = runWithCompanions(1200.0 + 1.0 / 20.0, 1200.0, false, 21, true);
  EXPECT_TRUE(none.reads);
}

}  // namespace periodic_bias_compensation
