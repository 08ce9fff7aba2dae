// Exact ship motion: slow part (fixed point, straight line or route) plus wave part
// (sinusoids or irregular sea), with analytic velocity, acceleration and angular rates.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "periodic_bias_compensation/sim/scenario.h"
#include "periodic_bias_compensation/sim/types.h"

namespace periodic_bias_compensation::sim
{
/// Slow (route) motion at one time.
struct SlowState
{
  Vector3 position = Vector3::Zero();      ///< ENU [m]
  Vector3 velocity = Vector3::Zero();      ///< ENU [m/s]
  Vector3 acceleration = Vector3::Zero();  ///< ENU [m/s^2]
  double heading = 0.0;                    ///< ENU yaw [rad]
  double yaw_rate = 0.0;                   ///< [rad/s]
};

/// Piecewise analytic slow motion: straight runs, constant-rate turns, constant accelerations.
class SlowMotion
{
public:
  /// @param motion motion description (route legs for MotionType::kRoute)
  explicit SlowMotion(const Motion& motion);

  /// State at a time.
  /// @param elapsed time since start [s]
  SlowState at(double elapsed) const;

  /// Index of the segment holding a time (segments are [start, end), the last one is open).
  /// @param elapsed time since start [s]
  std::size_t segmentAt(double elapsed) const;

  /// End time of a segment [s] (infinity for the last one).
  double segmentEnd(std::size_t segment) const;

  /// True if the segment has constant velocity and heading.
  bool segmentSteady(std::size_t segment) const;

private:
  struct Segment
  {
    double start;         ///< [s]
    double end;           ///< [s]
    Vector3 position;     ///< at start [m]
    double heading;       ///< at start [rad]
    double speed;         ///< at start [m/s]
    double turn_rate;     ///< [rad/s]
    double acceleration;  ///< along track [m/s^2]
    Vector3 direction;    ///< of the heading at start (ENU unit vector)
  };
  void push(Segment segment);
  std::vector<Segment> segments_;
};

/// One regular wave component of an irregular sea.
struct WaveComponent
{
  double amplitude = 0.0;   ///< [m]
  double omega = 0.0;       ///< absolute angular frequency [rad/s]
  double wavenumber = 0.0;  ///< deep water, omega^2 / g [rad/m]
  double direction = 0.0;   ///< propagation direction, ENU yaw [rad]
  double phase = 0.0;       ///< [rad]
  /// Extra phase of each Dof's response [rad] (Sea::response_coherence; heave's is 0).
  std::array<double, 6> lag{};
};

/// JONSWAP spectral density S(omega) [m^2 s / rad] (gamma = 1: Pierson-Moskowitz).
/// @param omega angular frequency [rad/s]
/// @param hs significant wave height [m]
/// @param tp peak period [s]
/// @param gamma peak enhancement [-]
double jonswap(double omega, double hs, double tp, double gamma);

/// Draws the wave components of a sea from a seed (components per system, frequencies in
/// random positions of equal bins over [0.6, 4] times the peak frequency).
/// @param sea sea description
/// @param gravity [m/s^2]
/// @param seed [-]
std::vector<WaveComponent> drawWaveComponents(const Sea& sea, double gravity, std::uint64_t seed);

/// Encounter angular frequency omega - omega^2 U cos(mu) / g.
/// @param omega absolute angular frequency [rad/s]
/// @param speed ship speed [m/s]
/// @param mu wave direction minus ship heading [rad]
/// @param gravity [m/s^2]
double encounterFrequency(double omega, double speed, double mu, double gravity);

/// Complete motion on the sample grid of a scenario.
class ShipMotion
{
public:
  /// What evaluate() fills.
  enum class Outputs
  {
    kAll,     ///< every field of the truth
    kSensor,  ///< what an IMU senses (Simulator::next(const Truth&, Sample*)): attitude, angular rate and
              ///< acceleration, acceleration; on a steady course the sea's part of position and velocity
              ///< is left zero (wave_position, wave_velocity)
  };

  /// @param scenario motion, rate and gravity are used
  /// @param seed seed of the sea's random components [-]
  /// @param outputs what evaluate() fills
  ShipMotion(const Scenario& scenario, std::uint64_t seed, Outputs outputs = Outputs::kAll);

  /// Truth at sample k (time k / rate). Fastest when called with k = 0, 1, 2, ...
  /// @param k sample index [-]
  Truth evaluate(std::int64_t k);

  /// The sea's components (empty without a sea).
  const std::vector<WaveComponent>& waveComponents() const
  {
    return components_;
  }

private:
  using Dofs = std::array<double, 18>;  ///< q, dq, ddq for each Dof: index 3 * dof + order

  Dofs sinusoidDofs(double elapsed) const;
  Dofs seaDofsDirect(double elapsed, const SlowState& slow) const;
  void fillSeaBlock(std::int64_t k0);
  void buildSeaCoefficients(const SlowState& slow);

  Motion motion_;
  double dt_;
  double gravity_;
  SlowMotion slow_;
  std::vector<WaveComponent> components_;
  Outputs outputs_;
  Eigen::MatrixXd block_;  ///< 18 x n sea DOFs of the cached block
  std::int64_t block_start_ = -1;
  // Steady-segment fast path, components in groups of four: each row's coefficients on the
  // phasors' sines (and, with response lags, cosines), the Dof slot of each row, and per group
  // the phasors and their steps.
  std::size_t coeff_segment_ = static_cast<std::size_t>(-1);
  bool lagged_ = false;
  std::vector<double> coeff_;
  std::vector<int> slot_;
  std::vector<double> phasor_;
};
}  // namespace periodic_bias_compensation::sim
