#!/usr/bin/python3
"""scripts/wave_hindsight.py's parts on streams of known answer: the lever arm's terms taken off a
sensor that only rotates leave no acceleration, the FIR fitted with hindsight recovers a narrow
sea's heave from its acceleration, a slow bias walk costs it (the effect the script measures), and
a multi-input FIR gains on an axis whose motion another, cleaner axis shares.

  test_wave_hindsight.py [--xunit RESULTS.xml]    (the catkin test writes JUnit XML)
"""
import os
import sys
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), 'scripts'))
import wave_hindsight  # noqa: E402
import pyunit_main  # noqa: E402

DT = 0.01


def quaternion_about_x(angle):
    return np.c_[np.cos(angle / 2), np.sin(angle / 2), np.zeros_like(angle), np.zeros_like(angle)]


def sea(seconds, seed, low=0.07, high=0.14, lead=0.0):
    """Heave of 30 components between low and high Hz, random phases, and its acceleration; each
    component's phase advanced by `lead` [rad] (a horizontal motion that follows the heave)."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, seconds, DT)
    heave = np.zeros_like(t)
    acceleration = np.zeros_like(t)
    for f in rng.uniform(low, high, 30):
        omega, phase, amplitude = 2 * np.pi * f, rng.uniform(0, 2 * np.pi) + lead, rng.uniform(0.05, 0.15)
        heave += amplitude * np.sin(omega * t + phase)
        acceleration -= amplitude * omega ** 2 * np.sin(omega * t + phase)
    return t, heave, acceleration


class HindsightTest(unittest.TestCase):
    def test_lever_arm_of_a_rolling_sensor_taken_off(self):
        # The sensor rolls about base_link's x axis 2.5 m to the side and 3 m above it; base_link
        # does not move, so at base_link nothing but gravity is left.
        t = np.arange(0.0, 120.0, DT)
        roll = 0.15 * np.sin(2 * np.pi * 0.1 * t)
        rate = 0.15 * 2 * np.pi * 0.1 * np.cos(2 * np.pi * 0.1 * t)
        arm = np.array([0.0, 2.5, 3.0])
        c, s = np.cos(roll), np.sin(roll)
        # The sensor's position in the world, R(roll) arm, and its acceleration.
        position = np.c_[np.zeros_like(t), c * arm[1] - s * arm[2], s * arm[1] + c * arm[2]]
        world = np.gradient(np.gradient(position, DT, axis=0), DT, axis=0) + [0.0, 0.0, wave_hindsight.GRAVITY]
        body = np.c_[world[:, 0], c * world[:, 1] + s * world[:, 2], -s * world[:, 1] + c * world[:, 2]]
        q = quaternion_about_x(roll)
        columns = {'t': t, 'ax': body[:, 0], 'ay': body[:, 1], 'az': body[:, 2], 'gx': rate,
                   'gy': np.zeros_like(t), 'gz': np.zeros_like(t), 'att_w': q[:, 0], 'att_x': q[:, 1],
                   'att_y': q[:, 2], 'att_z': q[:, 3]}
        corrected, dt = wave_hindsight.level_acceleration(columns, arm)
        raw, _ = wave_hindsight.level_acceleration(columns, np.zeros(3))
        inner = slice(1000, -1000)
        self.assertAlmostEqual(dt, DT)
        for axis in (1, 2):  # the roll moves the sensor in y and z
            self.assertGreater(np.std(raw[inner, axis]), 0.05)
            self.assertLess(np.std(corrected[inner, axis]), 0.05 * np.std(raw[inner, axis]))
        self.assertLess(np.max(np.abs(corrected[inner, 0])), 1e-9)

    def test_narrow_sea_recovered(self):
        t, heave, acceleration = sea(1200.0, seed=3)
        noisy = acceleration + np.random.default_rng(4).normal(0.0, 0.02, len(t))
        ratio, std = wave_hindsight.hindsight_error(noisy, heave, DT, settle=200.0, span=60.0)
        self.assertLess(np.sqrt(ratio), 0.05)
        self.assertAlmostEqual(std, np.std(heave[20000:]), delta=0.1 * std)
        # Scored in the first minutes, fitted after 200 s: the same sea, the same small error.
        early, _ = wave_hindsight.hindsight_error(noisy, heave, DT, settle=200.0, span=20.0, window=(20.0, 80.0))
        self.assertLess(np.sqrt(early), 0.1)

    def test_bias_walk_costs_the_fir(self):
        t, heave, acceleration = sea(1200.0, seed=5)
        walk = np.cumsum(np.random.default_rng(6).normal(0.0, 2e-3 * np.sqrt(DT), len(t)))
        clean, _ = wave_hindsight.hindsight_error(acceleration, heave, DT, settle=200.0, span=60.0)
        biased, _ = wave_hindsight.hindsight_error(acceleration + walk, heave, DT, settle=200.0, span=60.0)
        self.assertGreater(np.sqrt(biased), np.sqrt(clean) + 0.02)

    def test_shared_motion_read_from_the_cleaner_axis(self):
        # Sway a quarter period ahead of the heave, a third of it, its accelerometer ten times
        # noisier: the heave's acceleration carries the sway too.
        t, heave, heave_acceleration = sea(1200.0, seed=7)
        _, sway, sway_acceleration = sea(1200.0, seed=7, lead=np.pi / 2)
        sway, sway_acceleration = sway / 3, sway_acceleration / 3
        rng = np.random.default_rng(8)
        both = np.c_[sway_acceleration + rng.normal(0.0, 0.2, len(t)), heave_acceleration + rng.normal(0.0, 0.02, len(t))]
        own, _ = wave_hindsight.hindsight_error(both[:, 0], sway, DT, settle=200.0, span=60.0)
        shared, _ = wave_hindsight.hindsight_error(both, sway, DT, settle=200.0, span=60.0)
        self.assertLess(np.sqrt(shared), 0.5 * np.sqrt(own))


if __name__ == '__main__':
    pyunit_main.main(HindsightTest)
