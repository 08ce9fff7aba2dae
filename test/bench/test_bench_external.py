#!/usr/bin/python3
"""scripts/bench_external.py's comparison with the frequency-domain estimate on streams of known
answer: the standard deviation an estimator publishes is taken over its tracking outputs only,
wherever the held ones end between two points of the comparison's grid.

  test_bench_external.py [--xunit RESULTS.xml]    (the catkin test writes JUnit XML)
"""
import os
import sys
import unittest

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), 'scripts'))
import bench_external  # noqa: E402
import pyunit_main  # noqa: E402


class SpectralRowsTest(unittest.TestCase):
    def rows(self, held_until):
        """A 2 Hz heave on a 0.1 s grid; the estimator's outputs at 100 Hz, 0.5 ms off the grid's
        times, held (variance 1e6) until `held_until` [s] and then tracking with a variance of
        0.01 m^2."""
        name = 'xio_ngimu_heave_30cm'
        grid = np.arange(0.0, 60.0, 0.1)
        displacement = np.c_[0 * grid, 0 * grid, 0.1 * np.sin(2 * np.pi * 2.0 * grid)]
        t = np.arange(0.0005, 60.0, 0.01)
        track = np.c_[t, 0 * t, 0 * t, 0.1 * np.sin(2 * np.pi * 2.0 * t)]
        variance = np.where(t < held_until, 1e6, 0.01)
        variances = np.c_[t, variance, variance, variance]
        return bench_external.spectral_rows(name, (grid, displacement), track, variances)

    def test_held_outputs_are_left_out(self):
        # The compared part starts 5 s in; the hold ends inside it. At 8.1 s and 10.2 s a grid
        # point lies 95 % of the way from the last held output to the first tracking one.
        for held_until in (5.0, 8.043, 8.1, 10.2):
            for axis, correlation, ours, ref, difference, published in self.rows(held_until):
                self.assertAlmostEqual(published, 0.1, places=9, msg='%s held until %g s' % (axis, held_until))
            self.assertAlmostEqual(self.rows(held_until)[2][1], 1.0, places=6)


if __name__ == '__main__':
    pyunit_main.main(SpectralRowsTest)
