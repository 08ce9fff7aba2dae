// Fuzz target: a stream of ImuSample into periodic_bias_compensation::Compensator.
// The bytes are a small program: a configuration (valid ranges, sometimes arbitrary values that
// validate() must refuse), then operations: single samples with arbitrary doubles (NaN, Inf,
// huge, subnormal) in every field and arbitrary stamps (jumps, repeats, going backwards), bursts
// of synthetic oscillation so the period search locks, run-time setConfig with arbitrary
// values, reset, recalibrate, setConstantBias.
// Asserts: no crash (ASan/UBSan), every output the core fills is finite, the counters add up.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>

#include "fuzz_input.h"
#include "periodic_bias_compensation/core/compensator.h"

namespace pbc = periodic_bias_compensation;

namespace
{
bool finiteOutput(const pbc::CompensatorOutput& o)
{
  bool ok = std::isfinite(o.t) && o.position_filtered.allFinite() && o.velocity_filtered.allFinite() &&
            o.position_wave.allFinite() && o.velocity_wave.allFinite() && o.acceleration_level.allFinite() &&
            o.position_variance.allFinite() && o.velocity_variance.allFinite() &&
            o.wave_position_variance.allFinite() && o.orientation.coeffs().allFinite();
  for (const auto& a : o.axes)
  {
    ok = ok && std::isfinite(a.constant_bias) && std::isfinite(a.periodic_bias) && std::isfinite(a.frequency) &&
         std::isfinite(a.period_samples) && std::isfinite(a.d_v) && std::isfinite(a.d_p);
  }
  return ok;
}

/// A configuration from the input: either plausible values in the documented ranges or, with
/// `wild`, arbitrary doubles in some fields.
pbc::CompensatorConfig makeConfig(pbc_fuzz::Input& in, bool wild)
{
  pbc::CompensatorConfig c;
  c.mode = in.flag() ? pbc::Mode::kPaper : pbc::Mode::kDefault;
  for (auto& g : c.gains)
  {
    g.alpha_v = wild ? in.value(0.5, 1.0) : in.range(0.0, 1.99);
    g.alpha_p = wild ? in.value(0.5, 1.0) : in.range(0.0, 1.99);
    g.beta_v = wild ? in.value(6.0, 7.0) : in.range(0.0, 12.0);
    g.beta_p = wild ? in.value(2.0, 7.0) : in.range(0.0, 12.0);
  }
  c.enable_constant = (in.byte() % 4) != 0;
  c.enable_periodic = (in.byte() % 4) != 0;
  c.assume_static_calibration = in.flag();
  // Short windows so that short inputs reach the locked state.
  c.calibration_duration = wild ? in.value(1.0, 1.0) : in.range(0.0, 2.0);
  c.fft_window = wild ? in.value(6.0, 4.0) : in.range(2.0, 8.0);
  c.fft_hop = wild ? in.value(0.5, 0.5) : in.range(0.05, 1.0);
  c.min_frequency = wild ? in.value(0.3, 0.3) : in.range(0.2, 0.6);
  c.max_frequency = wild ? in.value(2.0, 2.0) : in.range(0.7, 5.0);
  c.min_peak_ratio = wild ? in.value(30.0, 30.0) : in.range(1.0, 60.0);
  // One byte, as before the gyro attitude existed (the corpus keeps its meaning elsewhere): its
  // low bits the harmonics, the next the gyro attitude and its bias estimate, the rest its time
  // constant (2 .. 64 s).
  const int harmonics_byte = in.byte();
  c.harmonics = 1 + harmonics_byte % 4;
  c.gyro_attitude = (harmonics_byte / 4) % 2 == 1;
  c.estimate_gyro_bias = (harmonics_byte / 8) % 2 == 1;
  c.tilt_time_constant = 2.0 + 2.0 * ((harmonics_byte / 16) % 32);
  c.harmonic_memory = wild ? in.value(10.0, 10.0) : in.range(0.5, 20.0);
  c.drift_time_constant = wild ? in.value(2.0, 2.0) : in.range(0.5, 10.0);
  c.max_gap = wild ? in.value(0.5, 0.5) : in.range(0.01, 2.0);
  c.max_rate_change = wild ? in.value(0.2, 0.2) : in.range(0.01, 0.9);
  return c;
}

pbc::ImuSample plausible(double t, double f, double amplitude, double bias)
{
  pbc::ImuSample s;
  s.t = t;
  const double w = 2.0 * M_PI * f;
  s.specific_force = pbc::Vector3(amplitude * std::sin(w * t) + bias, 0.5 * amplitude * std::cos(w * t),
                                  pbc::kStandardGravity + 0.2 * amplitude * std::sin(2.0 * w * t));
  return s;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
  pbc_fuzz::Input in(data, size);
  const bool wild_start = (in.byte() % 8) == 0;
  const pbc::CompensatorConfig config = makeConfig(in, wild_start);
  std::unique_ptr<pbc::Compensator> c;
  try
  {
    c = std::make_unique<pbc::Compensator>(config);
  }
  catch (const std::invalid_argument&)
  {
    if (config.validate(nullptr))
    {
      pbc_fuzz::fail("Compensator refused a configuration that validates");
    }
    return 0;
  }
  if (!config.validate(nullptr))
  {
    pbc_fuzz::fail("Compensator accepted a configuration that does not validate");
  }
  static const bool verbose = std::getenv("PBC_FUZZ_VERBOSE") != nullptr;
  auto dump = [](const pbc::CompensatorConfig& k) {
    std::fprintf(stderr,
                 "config: mode %s constant %d periodic %d static %d calibration %.6g window %.6g hop %.6g band "
                 "%.6g-%.6g ratio %.6g harmonics %d memory %.6g drift %.6g max_gap %.6g rate_change %.6g gyro %d %d "
                 "%.6g gains",
                 pbc::toString(k.mode).c_str(), k.enable_constant, k.enable_periodic, k.assume_static_calibration,
                 k.calibration_duration, k.fft_window, k.fft_hop, k.min_frequency, k.max_frequency, k.min_peak_ratio,
                 k.harmonics, k.harmonic_memory, k.drift_time_constant, k.max_gap, k.max_rate_change, k.gyro_attitude,
                 k.estimate_gyro_bias, k.tilt_time_constant);
    for (const auto& g : k.gains)
    {
      std::fprintf(stderr, " [%.6g %.6g %.6g %.6g]", g.alpha_v, g.alpha_p, g.beta_v, g.beta_p);
    }
    std::fprintf(stderr, "\n");
  };
  if (verbose)
  {
    dump(config);
  }

  double t = in.flag() ? 1000.0 : 1.7e9;  // simulator default and Unix time
  double dt = 0.01;
  std::uint64_t handed = 0;
  pbc::CompensatorOutput out;
  // Every sample reaches the core, whatever its stamp step (F1) or values (F3: finite but
  // absurd ones must be refused by the core itself); every accepted sample's output must be
  // finite, in paper mode too (F5) and after any setConstantBias (F8, F8b).
  auto feed = [&](const pbc::ImuSample& s) {
    const bool absurd = s.specific_force.cwiseAbs().maxCoeff() > pbc::kMaxSpecificForce ||
                        s.angular_rate.cwiseAbs().maxCoeff() > pbc::kMaxAngularRate;
    ++handed;
    const pbc::SampleStatus status = c->addSample(s, &out);
    if (verbose)
    {
      std::fprintf(stderr, "sample t %.6f f %.6g %.6g %.6g q %s: %s, bias %.6g %.6g %.6g\n", s.t, s.specific_force.x(),
                   s.specific_force.y(), s.specific_force.z(), s.has_orientation ? "yes" : "no",
                   pbc::toString(status).c_str(), out.axes[0].constant_bias, out.axes[1].constant_bias,
                   out.axes[2].constant_bias);
    }
    const bool accepted = status == pbc::SampleStatus::kAccepted || status == pbc::SampleStatus::kGapReset ||
                          status == pbc::SampleStatus::kResetBackwards;
    if (accepted && absurd)
    {
      pbc_fuzz::fail("a sample beyond kMaxSpecificForce / kMaxAngularRate was accepted");
    }
    if (accepted)
    {
      if (!finiteOutput(out))
      {
        std::ostringstream m;
        m.precision(17);
        m << "non-finite output for an accepted sample (status " << pbc::toString(status) << "): t = " << s.t
          << ", f = " << s.specific_force.transpose() << ", w = " << s.angular_rate.transpose()
          << ", q = " << (s.has_orientation ? "" : "(none) ") << s.orientation.coeffs().transpose()
          << "; out: pf = " << out.position_filtered.transpose() << ", pw = " << out.position_wave.transpose()
          << ", a = " << out.acceleration_level.transpose() << ", q = " << out.orientation.coeffs().transpose()
          << ", var = " << out.position_variance.transpose() << ", bias = " << out.axes[0].constant_bias << " "
          << out.axes[1].constant_bias << " " << out.axes[2].constant_bias;
        pbc_fuzz::fail(m.str());
      }
    }
  };

  int operations = 0;
  while (!in.empty() && ++operations < 400)
  {
    const std::uint8_t op = in.byte() % 16;
    if (op < 6)
    {
      // One sample, each field plausible or arbitrary.
      switch (in.byte() % 8)
      {
        case 0:
          t = in.rawDouble();
          break;  // any stamp
        case 1:
          t -= in.range(0.0, 100.0);
          break;  // backwards
        case 2:
          t += in.range(0.0, 1e6);
          break;  // long gap / restart with a jump
        case 3:
          break;  // repeated stamp
        default:
          t += dt;
          break;
      }
      pbc::ImuSample s = plausible(t, 0.5, 0.3, 0.05);
      if (in.flag())
      {
        s.specific_force = pbc::Vector3(in.value(0.0, 2.0), in.value(0.0, 2.0), in.value(9.8, 2.0));
      }
      if (in.flag())
      {
        s.angular_rate = pbc::Vector3(in.value(0.0, 0.5), in.value(0.0, 0.5), in.value(0.0, 0.5));
      }
      if (in.flag())
      {
        s.has_orientation = true;
        s.orientation = pbc::Quaternion(in.value(1.0, 0.1), in.value(0.0, 0.1), in.value(0.0, 0.1), in.value(0.0, 0.1));
      }
      feed(s);
    }
    else if (op < 10)
    {
      // A burst of plausible oscillation, at a rate chosen by the input.
      const int n = 1 + in.u16() % 3000;
      const double f = in.range(0.05, 3.0);
      const double amplitude = in.range(0.0, 3.0);
      const double bias = in.range(-0.5, 0.5);
      dt = in.flag() ? 1.0 / in.range(5.0, 400.0) : dt;
      const bool orientation = in.flag();
      const bool noise = in.flag();
      if (verbose)
      {
        std::fprintf(stderr, "burst: t %.6f n %d f %.6g amplitude %.6g bias %.6g dt %.6g orientation %d noise %d\n", t,
                     n, f, amplitude, bias, dt, orientation, noise);
      }
      std::uint32_t state = in.u32() | 1u;
      for (int k = 0; k < n; ++k)
      {
        t += dt;
        pbc::ImuSample s = plausible(t, f, amplitude, bias);
        if (noise)
        {
          state ^= state << 13;
          state ^= state >> 17;
          state ^= state << 5;
          s.specific_force.x() += 0.5 * (state / 4294967295.0 - 0.5);
        }
        if (orientation)
        {
          s.has_orientation = true;
          s.orientation = pbc::Quaternion(Eigen::AngleAxisd(0.05 * std::sin(0.3 * t), pbc::Vector3::UnitX()));
        }
        feed(s);
      }
    }
    else if (op == 10)
    {
      const pbc::CompensatorConfig next = makeConfig(in, in.flag());
      const pbc::CompensatorConfig before = c->config();
      std::string why;
      const bool ok = c->setConfig(next, &why);
      if (verbose)
      {
        std::fprintf(stderr, "setConfig at t %.6f: %s %s\n", t, ok ? "accepted" : "refused", why.c_str());
        dump(next);
      }
      if (ok != next.validate(nullptr))
      {
        pbc_fuzz::fail("setConfig and validate disagree");
      }
      if (!ok && why.empty())
      {
        pbc_fuzz::fail("setConfig refused without a message");
      }
      if (!ok && c->config().fft_window != before.fft_window)
      {
        pbc_fuzz::fail("a refused setConfig changed the configuration");
      }
    }
    else if (op == 11)
    {
      if (verbose)
      {
        std::fprintf(stderr, "reset at t %.6f\n", t);
      }
      c->reset();
    }
    else if (op == 12)
    {
      if (verbose)
      {
        std::fprintf(stderr, "recalibrate at t %.6f\n", t);
      }
      c->recalibrate();
    }
    else if (op == 13)
    {
      const pbc::Vector3 bias(in.value(0.0, 0.1), in.value(0.0, 0.1), in.value(0.0, 0.1));
      const bool ok = c->setConstantBias(bias);
      if (verbose)
      {
        std::fprintf(stderr, "setConstantBias %.6g %.6g %.6g: %s\n", bias.x(), bias.y(), bias.z(),
                     ok ? "accepted" : "refused");
      }
      if (ok != (bias.allFinite() && bias.cwiseAbs().maxCoeff() <= pbc::kMaxConstantBias))
      {
        pbc_fuzz::fail("setConstantBias accepted a non-finite or absurd bias, or refused a plausible one");
      }
    }
    else
    {
      dt = in.flag() ? in.range(1e-3, 0.6) : 0.01;
    }
  }

  const pbc::CompensatorCounters& k = c->counters();
  // Resets and gap restarts are accepted samples too (counted in both); samples held for a jump
  // that was then confirmed are counted as accepted, those dropped as held.
  const std::uint64_t counted = k.accepted + k.rejected_non_finite + k.rejected_bad_quaternion + k.rejected_duplicate +
                                k.rejected_out_of_range + k.rejected_early + k.held;
  if (counted != handed)
  {
    pbc_fuzz::fail("counters do not add up: " + std::to_string(counted) + " counted, " + std::to_string(handed) +
                   " handed");
  }
  return 0;
}
