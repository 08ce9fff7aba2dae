# Ship IMU simulator (core library without ROS; see docs/simulator.md).
