// Helpers of the run-time fault rostests (faults.cpp, manager_restart.cpp): a background IMU
// publisher on wall-time stamps whose signal, rate, orientation and stamps the test changes while
// it runs, and an observer of the outputs and of the compensator's /diagnostics status.
#pragma once

#include <atomic>
#include <cmath>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/Imu.h>

#include "periodic_bias_compensation/BiasState.h"

namespace pbc_test
{
/// Publishes imu/data in a thread until stopped; every setting may change while it runs.
class ImuStream
{
public:
  explicit ImuStream(ros::NodeHandle& nh) : pub_(nh.advertise<sensor_msgs::Imu>("imu/data", 1000))
  {
  }
  ~ImuStream()
  {
    stop();
  }

  void start()
  {
    if (thread_.joinable())
    {
      return;
    }
    running_ = true;
    thread_ = std::thread([this] { loop(); });
  }
  void stop()
  {
    running_ = false;
    if (thread_.joinable())
    {
      thread_.join();
    }
  }
  bool waitForSubscriber(double timeout)
  {
    const ros::WallTime start = ros::WallTime::now();
    while (pub_.getNumSubscribers() == 0 && (ros::WallTime::now() - start).toSec() < timeout)
    {
      ros::WallDuration(0.05).sleep();
    }
    return pub_.getNumSubscribers() > 0;
  }

  std::atomic<double> amplitude{ 0.0 };     ///< surge acceleration amplitude [m/s^2]
  std::atomic<double> frequency{ 0.5 };     ///< [Hz]
  std::atomic<double> rate{ 100.0 };        ///< [Hz]
  std::atomic<bool> orientation{ true };    ///< orientation present (else covariance[0] = -1)
  std::atomic<double> stamp_offset{ 0.0 };  ///< added to the wall-time stamp [s] (IMU restart)
  std::atomic<std::size_t> sent{ 0 };

private:
  void loop()
  {
    const double start = std::floor(ros::WallTime::now().toSec());
    while (running_ && ros::ok())
    {
      const double r = rate;
      const double now = ros::WallTime::now().toSec();
      // The signal follows the stamps (the publishing loop runs a little slower than `rate`).
      const double t_signal = now - start;
      sensor_msgs::Imu msg;
      msg.header.stamp = ros::Time(now + stamp_offset);
      msg.header.frame_id = "imu_link";
      msg.linear_acceleration.x = amplitude * std::sin(2.0 * M_PI * frequency * t_signal);
      msg.linear_acceleration.z = 9.80665;
      msg.orientation.w = 1.0;
      for (int i = 0; i < 3; ++i)
      {
        msg.orientation_covariance[4 * i] = 1e-4;
        msg.linear_acceleration_covariance[4 * i] = 1e-4;
        msg.angular_velocity_covariance[4 * i] = 1e-6;
      }
      if (!orientation)
      {
        msg.orientation_covariance[0] = -1.0;
        msg.orientation.w = 0.0;
      }
      pub_.publish(msg);
      ++sent;
      ros::WallDuration(1.0 / r).sleep();
    }
  }

  ros::Publisher pub_;
  std::atomic<bool> running_{ false };
  std::thread thread_;
};

/// One /diagnostics status of the compensator.
struct Status
{
  int level = -1;
  std::string message;
  std::map<std::string, std::string> values;
  ros::WallTime received;
};

/// Watches odometry/filtered, bias_state and the compensator's /diagnostics status.
class Observer
{
public:
  explicit Observer(ros::NodeHandle& nh)
  {
    odom_ = nh.subscribe("odometry/filtered", 1000, &Observer::odometry, this);
    wave_ = nh.subscribe("odometry/wave", 1000, &Observer::odometry, this);
    bias_ = nh.subscribe("bias_state", 1000, &Observer::bias, this);
    diag_ = nh.subscribe("/diagnostics", 100, &Observer::diagnostics, this);
  }

  void odometry(const nav_msgs::Odometry::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& p = msg->pose.pose.position;
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
    {
      ++nonfinite_;
    }
    max_position_ = std::max({ max_position_, std::abs(p.x), std::abs(p.y), std::abs(p.z) });
    ++odometry_;
    last_odometry_ = ros::WallTime::now();
  }
  void bias(const periodic_bias_compensation::BiasState::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    last_bias_ = *msg;
    ++bias_count_;
  }
  void diagnostics(const diagnostic_msgs::DiagnosticArray::ConstPtr& msg)
  {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& s : msg->status)
    {
      if (s.name.find("bias compensation") == std::string::npos)
      {
        continue;
      }
      Status status;
      status.level = s.level;
      status.message = s.message;
      status.received = ros::WallTime::now();
      for (const auto& kv : s.values)
      {
        status.values[kv.key] = kv.value;
      }
      history_.push_back(status);
    }
  }

  /// Waits until a status received from now on satisfies pred; returns it (level -1 on timeout).
  Status waitForStatus(const std::function<bool(const Status&)>& pred, double timeout)
  {
    const ros::WallTime start = ros::WallTime::now();
    std::size_t seen = 0;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      seen = history_.size();
    }
    while ((ros::WallTime::now() - start).toSec() < timeout)
    {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (; seen < history_.size(); ++seen)
        {
          if (pred(history_[seen]))
          {
            return history_[seen];
          }
        }
      }
      ros::WallDuration(0.05).sleep();
    }
    return Status();
  }
  /// Waits for a status whose message contains `text`.
  Status waitForMessage(const std::string& text, double timeout)
  {
    return waitForStatus([&](const Status& s) { return s.message.find(text) != std::string::npos; }, timeout);
  }

  /// The latest status (level -1 before any).
  Status last()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return history_.empty() ? Status() : history_.back();
  }

  std::size_t odometryCount()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return odometry_;
  }
  std::size_t nonfinite()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return nonfinite_;
  }
  double maxPosition()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return max_position_;
  }
  periodic_bias_compensation::BiasState lastBias()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return last_bias_;
  }
  std::size_t biasCount()
  {
    std::lock_guard<std::mutex> lock(mutex_);
    return bias_count_;
  }
  /// Waits until odometry has grown by `n` messages.
  bool waitForOdometry(std::size_t n, double timeout)
  {
    const std::size_t before = odometryCount();
    const ros::WallTime start = ros::WallTime::now();
    while ((ros::WallTime::now() - start).toSec() < timeout)
    {
      if (odometryCount() >= before + n)
      {
        return true;
      }
      ros::WallDuration(0.05).sleep();
    }
    return false;
  }

private:
  std::mutex mutex_;
  ros::Subscriber odom_, wave_, bias_, diag_;
  std::vector<Status> history_;
  std::size_t odometry_ = 0, nonfinite_ = 0, bias_count_ = 0;
  double max_position_ = 0.0;
  ros::WallTime last_odometry_;
  periodic_bias_compensation::BiasState last_bias_;
};
}  // namespace pbc_test
