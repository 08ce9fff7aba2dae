// Turns told from the yaw a sea induces (estimation core, no ROS).
//
// The wave estimate asks three things of the heading:
// - Has the ship turned? Then every encounter frequency has moved and the vertical spectrum
//   record describes another sea: it begins anew. A turn is a change of the heading's moving mean
//   (kHeadingAveraging) by kRecordTurn; the yaw a sea induces (degrees to tens of degrees on a
//   buoy, at its wave periods) averages out there, a turn does not.
// - May the horizontal axes take a broadband wave share? A turn's centripetal acceleration lies
//   at the wave band's lower edge, so not while the ship turns. The 2 s mean yaw rate beyond
//   kTurnRate and beyond kYawSpreads times the spread the sea gives it (its deviation from the
//   kSustainedTurnAveraging mean, over kYawSpreadAveraging) holds the share off while it lasts
//   and kAfterYaw after; after a heading change (a turn, not a yaw of the sea) kAfterTurn (the
//   spectral FIR spans up to that: it would still read the sea before the turn). A vessel that
//   yaws by degrees in waves keeps its share; a steady turn raises the spread to about 0.2 of its
//   rate. Without a measured attitude (one level frame) the share stays off: the hull's roll and
//   pitch leak g sin(angle) into the level axes in the wave band.
// - Does the horizontal spectrum record hold a manoeuvre? A turn until kAfterTurn after it, and
//   a sample without a measured attitude; the sea's yaw (the rate beyond its threshold in a tail
//   of the sea's spread, or before that spread is measured) holds the share off but leaves the
//   record as it is.
//
// Threading: not thread-safe; the owner serialises calls.
#pragma once

#include <Eigen/Geometry>

namespace periodic_bias_compensation
{
/// Heading of an attitude (body -> level frame, z up): the yaw of its x axis about z [rad],
/// in (-pi, pi].
double headingOf(const Eigen::Quaterniond& orientation);
/// The same of an attitude given as its rotation matrix.
double headingOf(const Eigen::Matrix3d& rotation);

class TurnDetector
{
public:
  /// Averaging of the yaw rate a turn is told by [s], and the rate beyond which the ship turns
  /// [rad/s] (wave-induced yaw of a few degrees at 5-15 s averages to a few mrad/s).
  static constexpr double kTurnAveraging = 2.0;
  static constexpr double kTurnRate = 0.008;
  /// Time after a turn without a horizontal share [s].
  static constexpr double kAfterTurn = 120.0;
  /// The longer yaw rate mean a turn is told by on a vessel that yaws in waves [s], the time over
  /// which the sea's spread of the 2 s mean about it is measured [s], and how many such spreads
  /// make a turn [-].
  static constexpr double kSustainedTurnAveraging = 60.0;
  static constexpr double kYawSpreadAveraging = 300.0;
  static constexpr double kYawSpreads = 3.0;
  /// Time after a yaw that is no turn without a horizontal share [s].
  static constexpr double kAfterYaw = 2.0;
  /// Heading change of the moving mean that makes a turn [rad], and that mean's time constant [s].
  static constexpr double kRecordTurn = 0.35;
  static constexpr double kHeadingAveraging = 10.0;

  /// Forgets everything: the next sample is the first.
  void reset();
  /// One sample. heading: headingOf() the attitude [rad]; yaw_rate: the angular rate about the
  /// level frame's z [rad/s]; dt: since the previous sample [s] (0 for the first);
  /// attitude_measured: the sample came with an attitude (not one level frame).
  void update(double heading, double yaw_rate, double dt, bool attitude_measured);

  /// This sample's heading mean has moved kRecordTurn from where the last record began (which
  /// then begins anew here).
  bool turned() const
  {
    return turned_;
  }
  /// Time since the yaw rate last marked a turn or the heading mean moved by kRecordTurn [s]
  /// (with or without a measured attitude; large before any).
  double sinceYaw() const
  {
    return since_yaw_;
  }
  /// The horizontal axes may take a broadband wave share.
  bool horizontalShareAllowed() const
  {
    return !manoeuvring();
  }
  /// The horizontal records take a manoeuvre now: a turn (the heading mean moved) until
  /// kAfterTurn after it, or no measured attitude. A yaw the heading mean does not follow (the
  /// sea's, which exceeds the yaw rate's threshold before its spread is measured) holds the share
  /// off but is none.
  bool recordManoeuvre() const
  {
    return !attitude_measured_ || (turn_confirmed_ && since_turn_ < kAfterTurn);
  }

private:
  /// A turn, a yaw or a missing attitude holds the share off.
  bool manoeuvring() const
  {
    return since_turn_ < (turn_confirmed_ ? kAfterTurn : kAfterYaw);
  }
  void followHeading(double heading, double dt);
  void followYawRate(double yaw_rate, double dt);

  double turn_rate_ = 0.0;            ///< yaw rate averaged over kTurnAveraging [rad/s]
  double sustained_turn_rate_ = 0.0;  ///< averaged over kSustainedTurnAveraging [rad/s]
  double yaw_spread_ = 0.0;           ///< mean square of turn_rate_ less sustained_turn_rate_ [rad^2/s^2]
  double yaw_samples_ = 0.0;          ///< samples in yaw_spread_'s mean
  bool turn_confirmed_ = false;       ///< the heading turned since the share was last allowed
  double since_turn_ = 0.0;           ///< time since the last turn or yaw beyond the threshold [s]
  double since_yaw_ = 1e9;            ///< the same, whether the attitude is measured or not [s]
  long heading_samples_ = 0;          ///< samples in the heading mean
  double heading_ = 0.0;              ///< last heading, unwrapped [rad]
  double heading_mean_ = 0.0;         ///< its moving mean over kHeadingAveraging [rad]
  double record_heading_ = 0.0;       ///< heading_mean_ when the current record began [rad]
  bool turned_ = false;
  bool attitude_measured_ = true;  ///< the last sample came with an attitude
};
}  // namespace periodic_bias_compensation
