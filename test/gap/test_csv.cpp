// gap::readCsv: delimiters, column mistakes named with the file's columns, units checked against
// gravity and the stamps.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <string>

#include "periodic_bias_compensation/gap/csv.h"

namespace gap = periodic_bias_compensation::gap;

namespace
{
/// A sensor at rest, 100 Hz, 300 rows: t, ax, ay, az, gx, gy, gz with a small oscillation.
std::string writeCsv(const std::string& name, const std::string& separator, double accel_unit = 1.0,
                     double time_unit = 1.0)
{
  const std::string path = ::testing::TempDir() + name;
  std::ofstream out(path);
  out.precision(17);
  out << "time" << separator << "acc x" << separator << "acc_y" << separator << "acc_z" << separator << "gyro_x"
      << separator << "gyro_y" << separator << "gyro_z\n";
  for (int k = 0; k < 300; ++k)
  {
    const double t = 5.0 + 0.01 * k;
    const double wobble = 0.05 * std::sin(2.0 * M_PI * 0.5 * t);
    out << t / time_unit << separator << wobble / accel_unit << separator << -wobble / accel_unit << separator
        << (9.81 + wobble) / accel_unit << separator << 0.01 * wobble << separator << 0.0 << separator << -0.002
        << "\n";
  }
  return path;
}

gap::CsvOptions options(const std::string& path, const std::string& columns = "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=6")
{
  gap::CsvOptions o;
  o.path = path;
  o.columns = columns;
  return o;
}

/// The message of the exception `read` throws as E ("" when it throws nothing or another type).
template <class E>
std::string messageOf(const std::function<void()>& read)
{
  try
  {
    read();
  }
  catch (const E& e)
  {
    return e.what();
  }
  catch (...)
  {
    return "";
  }
  return "";
}
}  // namespace

TEST(GapCsv, DelimiterFromTheHeader)
{
  EXPECT_EQ(gap::detectDelimiter("t,ax,ay"), ',');
  EXPECT_EQ(gap::detectDelimiter("t;ax;ay"), ';');
  EXPECT_EQ(gap::detectDelimiter("t\tax\tay"), '\t');
  EXPECT_EQ(gap::detectDelimiter("t  ax ay"), ' ');
  EXPECT_EQ(gap::detectDelimiter("\"a,b\";c;d"), ';');  // a quoted comma is a name, not a delimiter
}

TEST(GapCsv, EveryDelimiterGivesTheSameRecording)
{
  const gap::Recording comma = gap::readCsv(options(writeCsv("comma.csv", ",")));
  ASSERT_EQ(comma.size(), 300u);
  EXPECT_NEAR(comma.data(0, 2), 9.81, 1e-9);
  EXPECT_NEAR(comma.stamp[1] - comma.stamp[0], 0.01, 1e-9);
  for (const std::string separator : { ";", "\t", "   " })
  {
    const gap::Recording r = gap::readCsv(options(writeCsv("other.csv", separator)));
    ASSERT_EQ(r.size(), comma.size()) << "'" << separator << "'";
    EXPECT_EQ(r.stamp, comma.stamp);
    EXPECT_TRUE(r.data == comma.data) << "'" << separator << "'";
  }
  // Column names of a ';' file ("acc x" holds a blank), negated.
  const gap::Recording named = gap::readCsv(
      options(writeCsv("named.csv", ";"), "t=time,ax=-acc x,ay=acc_y,az=acc_z,gx=gyro_x,gy=gyro_y,gz=gyro_z"));
  EXPECT_EQ(named.data.col(0), -comma.data.col(0));
}

TEST(GapCsv, ColumnMistakesNameTheFilesColumns)
{
  const std::string path = writeCsv("columns.csv", ";");
  const std::string missing =
      messageOf<gap::CsvOptionError>([&] { gap::readCsv(options(path, "t=0,ax=accx,ay=2,az=3,gx=4,gy=5,gz=6")); });
  EXPECT_NE(missing.find("no column 'accx'"), std::string::npos) << missing;
  EXPECT_NE(missing.find("time, acc x, acc_y, acc_z, gyro_x, gyro_y, gyro_z"), std::string::npos) << missing;
  const std::string beyond =
      messageOf<gap::CsvOptionError>([&] { gap::readCsv(options(path, "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=12")); });
  EXPECT_NE(beyond.find("has 7 columns"), std::string::npos) << beyond;
  const std::string unknown =
      messageOf<gap::CsvOptionError>([&] { gap::readCsv(options(path, "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=6,wz=6")); });
  EXPECT_NE(unknown.find("unknown key 'wz'"), std::string::npos) << unknown;
  EXPECT_NE(messageOf<gap::CsvOptionError>([&] {
              gap::readCsv(options(path, "t=0,ax=1,ay=2,az=3,gx=4,gy=5"));
            }).find("needs gz"),
            std::string::npos);
}

TEST(GapCsv, UnitsAreCheckedAgainstGravityAndTheStamps)
{
  const std::string in_g =
      messageOf<std::runtime_error>([] { gap::readCsv(options(writeCsv("g.csv", ",", 9.80665))); });
  EXPECT_NE(in_g.find("--accel-scale 9.80665"), std::string::npos) << in_g;
  gap::CsvOptions scaled = options(writeCsv("g.csv", ",", 9.80665));
  scaled.accel_scale = 9.80665;
  EXPECT_NEAR(gap::readCsv(scaled).data(0, 2), 9.81, 1e-9);

  const std::string in_ms =
      messageOf<std::runtime_error>([] { gap::readCsv(options(writeCsv("ms.csv", ",", 1.0, 1e-3))); });
  EXPECT_NE(in_ms.find("--time-scale"), std::string::npos) << in_ms;
  gap::CsvOptions ms = options(writeCsv("ms.csv", ",", 1.0, 1e-3));
  ms.time_scale = 1e-3;
  EXPECT_NEAR(gap::estimateRate(gap::readCsv(ms)), 100.0, 1e-6);
}

/// A sensor at rest, tilted and turned, written as NED/FRD files commonly are: specific force and
/// rate on x forward, y right, z down, and roll, pitch, yaw against north-east-down.
TEST(GapCsv, NedFilesAreReadIntoEnuWithTheirOrientation)
{
  const double roll = 0.1, pitch = -0.05, yaw = 2.0, g = 9.81;
  // The force at rest points up: (0, 0, -g) in NED. Its FRD components, rotating the world
  // vector back through yaw, pitch, roll in turn.
  const double cr = std::cos(roll), sr = std::sin(roll), cp = std::cos(pitch), sp = std::sin(pitch);
  const double fx = g * sp, fy = -g * sr * cp, fz = -g * cr * cp;
  const std::string path = ::testing::TempDir() + "ned.csv";
  {
    std::ofstream out(path);
    out.precision(17);
    out << "t,fx,fy,fz,wx,wy,wz,r,p,y\n";
    for (int k = 0; k < 300; ++k)
      out << 0.01 * k << "," << fx << "," << fy << "," << fz << ",0.01,0.02,0.03," << roll << "," << pitch << "," << yaw
          << "\n";
  }
  gap::CsvOptions o = options(path, "t=t,ax=fx,ay=fy,az=fz,gx=wx,gy=wy,gz=wz,roll=r,pitch=p,yaw=y");
  o.ned = true;
  const gap::Recording r = gap::readCsv(o);
  ASSERT_TRUE(r.has_orientation);
  ASSERT_EQ(r.orientation.size(), r.size());
  // The gyro in x forward, y left, z up.
  EXPECT_NEAR(r.data(0, 3), 0.01, 1e-12);
  EXPECT_NEAR(r.data(0, 4), -0.02, 1e-12);
  EXPECT_NEAR(r.data(0, 5), -0.03, 1e-12);
  // The reported orientation takes the force to ENU's up, and the bow to its heading: yaw from
  // north clockwise, pitch positive bow up.
  const Eigen::Vector3d up = r.orientation[0] * r.data.row(0).head<3>().transpose();
  EXPECT_NEAR(up.x(), 0.0, 1e-9);
  EXPECT_NEAR(up.y(), 0.0, 1e-9);
  EXPECT_NEAR(up.z(), g, 1e-9);
  const Eigen::Vector3d bow = r.orientation[0] * Eigen::Vector3d::UnitX();
  EXPECT_NEAR(bow.x(), std::sin(yaw) * cp, 1e-9);
  EXPECT_NEAR(bow.y(), std::cos(yaw) * cp, 1e-9);
  EXPECT_NEAR(bow.z(), std::sin(pitch), 1e-9);

  // Without ned the angles are ENU z-y-x of a z-up sensor.
  gap::CsvOptions enu = options(writeCsv("angles.csv", ","), "t=0,ax=1,ay=2,az=3,gx=4,gy=5,gz=6,roll=5,pitch=5,yaw=4");
  const gap::Recording e = gap::readCsv(enu);
  ASSERT_TRUE(e.has_orientation);
  EXPECT_NEAR(e.orientation[0].w(), 1.0, 1e-9);  // every angle 0 in the first row
  // All three angles or none.
  const std::string partial = messageOf<gap::CsvOptionError>(
      [&] { gap::readCsv(options(path, "t=t,ax=fx,ay=fy,az=fz,gx=wx,gy=wy,gz=wz,roll=r,pitch=p")); });
  EXPECT_NE(partial.find("roll,pitch,yaw"), std::string::npos) << partial;
}
