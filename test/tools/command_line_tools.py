#!/usr/bin/python3
"""The ROS command-line tools a user reaches for first work against the running compensator:
rosservice calls its calibrate service (std_srvs/Trigger, Python side: python3-std-srvs) and
rostopic echoes the odometry transform on /tf (tf2_msgs, Python side: python3-tf2-msgs)."""
import subprocess
import time
import unittest

import rostest


def run(args, timeout=60):
    return subprocess.run(args, capture_output=True, text=True, timeout=timeout)


class CommandLineTools(unittest.TestCase):
    def test_rosservice_calls_calibrate(self):
        deadline = time.time() + 60
        while '/compensator/calibrate' not in run(['rosservice', 'list']).stdout:
            self.assertLess(time.time(), deadline, 'the compensator never advertised calibrate')
            time.sleep(0.5)
        result = run(['rosservice', 'call', '/compensator/calibrate'])
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn('success: True', result.stdout)

    def test_rostopic_echoes_tf(self):
        result = run(['rostopic', 'echo', '-n', '1', '/tf'], timeout=90)
        self.assertEqual(result.returncode, 0, result.stdout + result.stderr)
        self.assertIn('child_frame_id', result.stdout)


if __name__ == '__main__':
    rostest.rosrun('periodic_bias_compensation', 'command_line_tools', CommandLineTools)
