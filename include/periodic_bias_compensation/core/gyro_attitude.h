// Attitude from the gyro for IMUs that report none (estimation core, no ROS).
//
// A complementary filter: the gyro rate, less its estimated bias, turns the attitude; the
// direction of the mean specific force (gravity, once the wave accelerations average out) pulls
// roll and pitch back over a time constant of tens of seconds. With gyro bias estimation the
// pull is a proportional-integral loop whose integral is the gyro bias on the level axes (the
// paper's second item of future work: compensate the gyros too); without it a constant gyro
// bias b leaves a standing tilt of b x tilt_time_constant. Yaw is the gyro's integral only
// (nothing observes it), so its bias is not estimated.
//
// At rest the attitude does not change, and integrating a gyro whose bias wanders (a few tenths
// of a milliradian per second over minutes) or whose noise is large only tilts the estimate,
// which reads as horizontal acceleration. While the sensor is quiet (kQuietBlocks one-second
// means of force and rate all within kQuietForceRange and kQuietRateRange of each other) the
// gyro is not integrated: its mean is the bias (all three axes, time constant kQuietBiasTime)
// and the force alone pulls the tilt. The gyro is back the moment its rate less the bias,
// averaged over kQuietExitTime, exceeds kQuietRateLimit, and quiet needs kQuietBlocks again.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <Eigen/Geometry>

#include <array>

namespace periodic_bias_compensation
{
/// Roll and pitch that turn a specific force (at rest: up) onto +z by the shortest rotation; yaw
/// zero. A force pointing straight down turns about x, nearly straight down about the horizontal
/// axis normal to it (as Eigen::Quaterniond::FromTwoVectors). A zero force gives the identity,
/// a non-finite one a NaN quaternion.
Eigen::Quaterniond levelFromSpecificForce(const Eigen::Vector3d& specific_force);

/// Data that starts the attitude [s]: at rest (gyro and force steady) its mean rate is the gyro
/// bias and its mean force the up direction; otherwise the attitude starts from the newest force.
constexpr double kStartWindow = 2.0;
/// One-second means that must agree before the sensor counts as quiet.
constexpr int kQuietBlocks = 10;
/// Largest spread (max - min) of those means per axis: force [m/s^2] (5 mrad of tilt; a bench
/// shaken by 2 cm at 0.3 Hz spreads them by 0.1) and rate [rad/s].
constexpr double kQuietForceRange = 0.05;
constexpr double kQuietRateRange = 0.005;
/// While quiet: time constant of the gyro bias [s]; averaging time and limit of the rate less the
/// bias that end quiet [s, rad/s].
constexpr double kQuietBiasTime = 10.0;
constexpr double kQuietExitTime = 0.1;
constexpr double kQuietRateLimit = 0.01;

struct GyroAttitudeConfig
{
  /// Time constant with which the tilt follows the mean specific force [s]. Long against the
  /// wave period, so the wave accelerations average out; short against how fast the gyro bias
  /// changes. Must be > 0 (CompensatorConfig::validate asks for 2 s or more).
  double tilt_time_constant = 30.0;
  /// Estimate the gyro bias on the level axes (proportional-integral loop, a double pole at
  /// -1 / tilt_time_constant) rather than only pulling the tilt (one pole there).
  bool estimate_bias = true;
};

class GyroAttitude
{
public:
  explicit GyroAttitude(const GyroAttitudeConfig& config = GyroAttitudeConfig());

  /// Starts over from the attitude `start` (sensor -> level) or, without one, from the next
  /// sample's specific force (roll and pitch, yaw zero).
  void reset();
  void reset(const Eigen::Quaterniond& start);

  /// Turns the attitude by the gyro over dt [s] and pulls the tilt towards the specific force
  /// [m/s^2, sensor frame]. Returns the attitude, sensor -> level ENU. Started without an
  /// attitude, the first kStartWindow of samples only start it (initialised() is false meanwhile).
  const Eigen::Quaterniond& update(const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& specific_force,
                                   double dt);

  const Eigen::Quaterniond& attitude() const
  {
    return attitude_;
  }
  /// Estimated gyro bias, sensor frame [rad/s] (zero without estimate_bias).
  const Eigen::Vector3d& gyroBias() const
  {
    return bias_;
  }
  /// False during the first kStartWindow of data (the attitude is the identity then).
  bool initialised() const
  {
    return initialised_;
  }
  /// The start window was at rest: the attitude and the gyro bias started from its means.
  bool startedAtRest() const
  {
    return started_at_rest_;
  }
  /// The last kQuietBlocks seconds were quiet: the gyro is not integrated.
  bool quiet() const
  {
    return quiet_;
  }

  void setConfig(const GyroAttitudeConfig& config)
  {
    config_ = config;
  }

private:
  /// Statistics of the start window (Welford).
  struct StartWindow
  {
    double count = 0.0, elapsed = 0.0;
    Eigen::Vector3d rate_mean = Eigen::Vector3d::Zero(), rate_m2 = Eigen::Vector3d::Zero();
    Eigen::Vector3d force_mean = Eigen::Vector3d::Zero();
    double magnitude_mean = 0.0, magnitude_m2 = 0.0;
  };
  void start(const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& specific_force, double dt, bool gravity_like);
  /// Adds a sample to the current one-second block and decides quiet_ when it closes.
  void watchQuiet(const Eigen::Vector3d& angular_rate, const Eigen::Vector3d& specific_force, double dt);

  /// One-second means of rate and force, the newest kQuietBlocks.
  struct Block
  {
    Eigen::Vector3d rate = Eigen::Vector3d::Zero(), force = Eigen::Vector3d::Zero();
  };
  Block block_sum_;
  double block_count_ = 0.0, block_elapsed_ = 0.0;
  std::array<Block, kQuietBlocks> blocks_{};
  int blocks_filled_ = 0, block_next_ = 0;
  bool quiet_ = false;
  Eigen::Vector3d rate_less_bias_ = Eigen::Vector3d::Zero();  ///< averaged over kQuietExitTime

  GyroAttitudeConfig config_;
  StartWindow start_;
  bool started_at_rest_ = false;
  Eigen::Quaterniond attitude_ = Eigen::Quaterniond::Identity();
  Eigen::Vector3d bias_ = Eigen::Vector3d::Zero();
  bool initialised_ = false;
  double elapsed_ = 0.0;  ///< time since initialisation from the specific force [s]
};

}  // namespace periodic_bias_compensation
