// An IMU recording read from a delimited text file (diagnose_gap --real-csv).
#pragma once

#include <stdexcept>
#include <string>

#include "periodic_bias_compensation/gap/recording.h"

namespace periodic_bias_compensation::gap
{
/// How to read the file.
struct CsvOptions
{
  std::string path;
  /// key=COLUMN pairs, comma-separated. Keys: t; ax, ay, az; gx, gy, gz (required); temp; px, py,
  /// pz, qw, qx, qy, qz (truth: all or none); roll, pitch, yaw (the sensor's reported orientation
  /// as z-y-x angles against the world [rad]: all or none). COLUMN is a header name or a 0-based
  /// index, optionally prefixed with '-' to negate it.
  std::string columns;
  int skip_lines = 0;                 ///< lines before the header
  double accel_scale = 1.0;           ///< to m/s^2 (9.80665 for g)
  double gyro_scale = 1.0;            ///< to rad/s (0.0174532925 for deg/s)
  double time_scale = 1.0;            ///< to s (1e-3 for ms)
  double truth_position_scale = 1.0;  ///< to m
  double rate = 0.0;                  ///< [Hz]; without a t column the time is k / rate
  bool use_truth = true;              ///< read the truth columns when given
  /// The sensor's axes are x forward, y right, z down and its angles are against north-east-down
  /// (the usual marine convention): specific force and rate are turned into x forward, y left,
  /// z up (180 degrees about x), the orientation into sensor -> ENU (REP-103, REP-145).
  bool ned = false;
};

/// A mistake in CsvOptions::columns or rate (an unknown key, a column the file does not have):
/// the command line's fault, not the file's.
class CsvOptionError : public std::invalid_argument
{
public:
  using std::invalid_argument::invalid_argument;
};

/// The delimiter of a header line: the most frequent of ',' ';' and tab outside quotes, or ' '
/// (runs of spaces and tabs) when it has none of them.
char detectDelimiter(const std::string& header);

/// Reads the file. The delimiter comes from the header line (detectDelimiter); lines that do
/// not parse as numbers in every used column are skipped. The result is checked: at least 200
/// data lines, a rate from the stamps between 0.5 Hz and 20 kHz (else the time column is in
/// other units than s), and a median specific-force magnitude near gravity (else the
/// accelerations are in g, in mg or without gravity).
/// @throws CsvOptionError for a mistake in the options (the message lists the valid keys or the
///         file's columns)
/// @throws std::runtime_error naming the file when it cannot be read or fails a check above
Recording readCsv(const CsvOptions& options);

}  // namespace periodic_bias_compensation::gap
