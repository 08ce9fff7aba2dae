#!/usr/bin/env python3
"""Heave from a causal FIR fitted with hindsight: a reference for the spectral heave's error.

For each scenario and seed, simulate_imu writes the sensor and the truth; the vertical acceleration
is formed as well as the sensor allows (the true attitude, the lever arm taken off with the
measured gyro) and, as the estimator does, low-passed by two moving averages of about 0.5 s and
taken every such step. A causal FIR of --span seconds (and a constant) is then fitted by least
squares to the true wave heave on one half of the record (after --settle) and scored on the other,
both ways round; with --window T0 T1 it is fitted on the whole record after --settle and scored
from T0 to T1 s (the first minutes: what a FIR of a short span does once the spectrum is known).
No causal linear filter of that span designed from the sensor alone does better on
average; scenarios that share a sea (the same seed, a different sensor) show what the sensor's
effects cost such a filter. Prints per scenario the error in % of the true wave RMS and of Hs
(4 x its standard deviation), to be set beside `evaluate_compensator --settle S` (same seeds).

usage: heave_hindsight.py --devel DEVEL_LIB_DIR --scenario A.yaml [--scenario B.yaml ...]
                          [--seeds 3] [--duration 1200] [--settle 200] [--span 60]
                          [--window T0 T1]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import yaml
from scipy import signal

GRAVITY = 9.80665


def lever_arm(simulate, scenario):
    """The scenario's lever arm [m] (zero without one), from simulate_imu's filled-in scenario."""
    text = subprocess.run([simulate, '--scenario', scenario, '--print-scenario'], check=True,
                          capture_output=True, text=True).stdout
    for effect in yaml.safe_load(text).get('effects', []) or []:
        if effect.get('name') == 'lever_arm' and effect.get('enabled', True):
            return np.array(effect['offset'], dtype=float)
    return np.zeros(3)


def vertical_acceleration(columns, arm):
    """World-z specific force less gravity at base_link: the lever arm's terms taken off with the
    measured gyro (low-passed at 5 Hz, causally), rotated by the true attitude."""
    t = columns['t']
    dt = np.median(np.diff(t))
    accel = np.c_[columns['ax'], columns['ay'], columns['az']]
    gyro = np.c_[columns['gx'], columns['gy'], columns['gz']]
    gyro = signal.sosfilt(signal.butter(2, min(5.0, 0.2 / dt), fs=1.0 / dt, output='sos'), gyro, axis=0)
    angular_acceleration = np.gradient(gyro, dt, axis=0)
    accel = accel - np.cross(angular_acceleration, arm) - np.cross(gyro, np.cross(gyro, arm))
    w, x, y, z = (columns[k] for k in ('att_w', 'att_x', 'att_y', 'att_z'))
    up = (2 * (x * z - w * y) * accel[:, 0] + 2 * (y * z + w * x) * accel[:, 1] +
          (1 - 2 * (x * x + y * y)) * accel[:, 2])
    return up - GRAVITY, dt


def hindsight_error(a, heave, dt, settle, span, window=None):
    """Mean squared error over true variance of the FIR fitted on one half, scored on the other
    (window None), or fitted after settle and scored within window = (T0, T1) [s]."""
    step = max(1, int(round(0.5 / dt)))
    box = np.ones(step) / step
    low = np.convolve(np.convolve(a, box)[:len(a)], box)[:len(a)]
    values, target = low[step - 1::step], heave[step - 1::step]
    taps = int(round(span / (step * dt)))
    def rows(begin, end):
        return np.array([np.r_[values[n - taps + 1:n + 1][::-1], 1.0] for n in range(max(taps, begin), end)])

    def index(seconds):
        return int(np.ceil(seconds / (step * dt)))

    if window is not None:
        fit, score = rows(index(settle), len(values)), rows(index(window[0]), index(window[1]))
        h = np.linalg.lstsq(fit, target[max(taps, index(settle)):], rcond=None)[0]
        truth = target[max(taps, index(window[0])):index(window[1])]
        error = truth - score @ h
        return float(np.mean(error ** 2) / np.mean(truth ** 2)), float(np.std(truth))
    first = max(taps, index(settle))
    design = rows(first, len(values))
    truth = target[first:]
    half = len(truth) // 2
    ratios = []
    for fit, score in ((slice(0, half), slice(half, None)), (slice(half, None), slice(0, half))):
        h = np.linalg.lstsq(design[fit], truth[fit], rcond=None)[0]
        error = truth[score] - design[score] @ h
        ratios.append(np.mean(error ** 2) / np.mean(truth[score] ** 2))
    return float(np.mean(ratios)), float(np.std(truth))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--devel', required=True, help='devel/lib/periodic_bias_compensation of a build')
    parser.add_argument('--scenario', action='append', required=True)
    parser.add_argument('--seeds', type=int, default=3)
    parser.add_argument('--duration', type=float, default=1200.0)
    parser.add_argument('--settle', type=float, default=200.0)
    parser.add_argument('--span', type=float, default=60.0, help='FIR span [s]')
    parser.add_argument('--window', type=float, nargs=2, metavar=('T0', 'T1'),
                        help='score from T0 to T1 s of the record, the FIR fitted after --settle')
    args = parser.parse_args()
    simulate = os.path.join(args.devel, 'simulate_imu')
    if not os.access(simulate, os.X_OK):
        sys.exit('heave_hindsight: no simulate_imu in %s' % args.devel)
    print('| scenario | seeds | FIR span [s] | scored [s] | error [% of true wave RMS] | [% of Hs] |')
    print('|---|---|---|---|---|---|')
    with tempfile.TemporaryDirectory() as scratch:
        for scenario in args.scenario:
            arm = lever_arm(simulate, scenario)
            ratios, hs = [], []
            for seed in range(1, args.seeds + 1):
                csv = os.path.join(scratch, 'seed%d.csv' % seed)
                subprocess.run([simulate, '--scenario', scenario, '--csv', csv, '--seed', str(seed),
                                '--duration', str(args.duration)], check=True, stdout=subprocess.DEVNULL)
                data = np.genfromtxt(csv, delimiter=',', names=True)
                columns = {name: data[name] for name in data.dtype.names}
                a, dt = vertical_acceleration(columns, arm)
                ratio, std = hindsight_error(a, columns['wave_pz'], dt, args.settle, args.span, args.window)
                ratios.append(ratio)
                hs.append(std)
                print('%s seed %d: %.1f %% of the true wave RMS' % (os.path.basename(scenario), seed,
                                                                    100 * np.sqrt(ratio)), file=sys.stderr)
            rms = 100 * np.sqrt(np.mean(ratios))
            # % of Hs = error RMS / (4 std); the wave's mean is near zero, so RMS ~ std.
            scored = ('%g-%g' % tuple(args.window)) if args.window else 'after %g' % args.settle
            print('| %s | %d | %.0f | %s | %.1f | %.2f |' % (os.path.splitext(os.path.basename(scenario))[0],
                                                         args.seeds, args.span, scored, rms, rms / 4))


if __name__ == '__main__':
    main()
