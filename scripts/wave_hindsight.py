#!/usr/bin/env python3
"""Wave motion from a causal FIR fitted with hindsight: a reference for the wave estimate's error.

For each scenario and seed, simulate_imu writes the sensor and the truth; the level-frame
acceleration at base_link is formed as well as the sensor allows (the true attitude, the lever arm
taken off with the measured gyro) and, as the estimator does, low-passed by two moving averages of
--step seconds (0.25 s, WienerHeave::kDesignPeriod) and taken every such step. For each axis
asked for, a causal FIR of --span seconds (and a constant) is fitted by least squares to the axis's true wave motion on one half of the record
(after --settle) and scored on the other, both ways round; with --window T0 T1 it is fitted on the
whole record after --settle and scored from T0 to T1 s (the first minutes: what a FIR of a short
span does once the spectrum is known). The FIR reads the axis's own acceleration (`own`) or all
three (`all`: a multi-input filter, which gains where the axes move together, as a ship's or a
buoy's do in a long-crested sea; it has three times the coefficients, and a half of the record
shorter than a few times their number overfits: a warning says so). No causal linear filter of that span and those inputs designed
from the sensor alone does better on average; scenarios that share a sea (the same seed, a
different sensor) show what the sensor's effects cost such a filter. Prints per scenario, axis and
inputs the error in % of the true wave RMS and of Hs (4 x its standard deviation), to be set
beside `evaluate_compensator --settle S` (same seeds).

usage: wave_hindsight.py --devel DEVEL_LIB_DIR --scenario A.yaml [--scenario B.yaml ...]
                         [--axes z] [--inputs own] [--seeds 3] [--duration 1200] [--settle 200]
                         [--span 60] [--step 0.25] [--window T0 T1]
"""
import argparse
import os
import subprocess
import sys
import tempfile

import numpy as np
import yaml
from scipy import signal

from bench_external import G as GRAVITY, quat_rotate

AXES = 'xyz'


def lever_arm(simulate, scenario):
    """The scenario's lever arm [m] (zero without one), from simulate_imu's filled-in scenario."""
    text = subprocess.run([simulate, '--scenario', scenario, '--print-scenario'], check=True,
                          capture_output=True, text=True).stdout
    for effect in yaml.safe_load(text).get('effects', []) or []:
        if effect.get('name') == 'lever_arm' and effect.get('enabled', True):
            return np.array(effect['offset'], dtype=float)
    return np.zeros(3)


def level_acceleration(columns, arm):
    """Level-frame specific force less gravity at base_link (n x 3): the lever arm's terms taken
    off with the measured gyro (low-passed at 5 Hz, causally), turned by the true attitude."""
    t = columns['t']
    dt = np.median(np.diff(t))
    accel = np.c_[columns['ax'], columns['ay'], columns['az']]
    gyro = np.c_[columns['gx'], columns['gy'], columns['gz']]
    gyro = signal.sosfilt(signal.butter(2, min(5.0, 0.2 / dt), fs=1.0 / dt, output='sos'), gyro, axis=0)
    angular_acceleration = np.gradient(gyro, dt, axis=0)
    accel = accel - np.cross(angular_acceleration, arm) - np.cross(gyro, np.cross(gyro, arm))
    attitude = np.c_[columns['att_w'], columns['att_x'], columns['att_y'], columns['att_z']]
    level = quat_rotate(attitude, accel)
    level[:, 2] -= GRAVITY
    return level, dt


def hindsight_error(inputs, truth, dt, settle, span, window=None, step_s=0.25):
    """Mean squared error over true variance of the FIR from `inputs` (n x k, or n) to `truth`
    (n), fitted on one half and scored on the other (window None), or fitted after settle and
    scored within window = (T0, T1) [s]. Also returns the true motion's standard deviation there."""
    inputs = np.asarray(inputs, dtype=float).reshape(len(truth), -1)
    step = max(1, int(round(step_s / dt)))
    box = np.ones(step) / step
    values = [np.convolve(np.convolve(column, box)[:len(column)], box)[:len(column)][step - 1::step]
              for column in inputs.T]
    target = np.asarray(truth)[step - 1::step]
    taps = int(round(span / (step * dt)))

    def rows(begin, end):
        return np.array([np.concatenate([v[n - taps + 1:n + 1][::-1] for v in values] + [[1.0]])
                         for n in range(max(taps, begin), end)])

    def index(seconds):
        return int(np.ceil(seconds / (step * dt)))

    if window is not None:
        later, early = rows(index(settle), len(target)), rows(index(window[0]), index(window[1]))
        h = np.linalg.lstsq(later, target[max(taps, index(settle)):], rcond=None)[0]
        scored = target[max(taps, index(window[0])):index(window[1])]
        error = scored - early @ h
        return float(np.mean(error ** 2) / np.mean(scored ** 2)), float(np.std(scored))
    first = max(taps, index(settle))
    design = rows(first, len(target))
    scored = target[first:]
    half = len(scored) // 2
    if half < 4 * design.shape[1]:
        print('wave_hindsight: %d values per half against %d coefficients: the fit overfits, the error reads '
              'high; a longer --duration or a shorter --span' % (half, design.shape[1]), file=sys.stderr)
    ratios = []
    for fit, score in ((slice(0, half), slice(half, None)), (slice(half, None), slice(0, half))):
        h = np.linalg.lstsq(design[fit], scored[fit], rcond=None)[0]
        error = scored[score] - design[score] @ h
        ratios.append(np.mean(error ** 2) / np.mean(scored[score] ** 2))
    return float(np.mean(ratios)), float(np.std(scored))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--devel', required=True, help='devel/lib/periodic_bias_compensation of a build')
    parser.add_argument('--scenario', action='append', required=True)
    parser.add_argument('--axes', default='z', help='of x, y, z (default z)')
    parser.add_argument('--inputs', default='own', help='own, all or both (own,all)')
    parser.add_argument('--seeds', type=int, default=3)
    parser.add_argument('--duration', type=float, default=1200.0)
    parser.add_argument('--settle', type=float, default=200.0)
    parser.add_argument('--span', type=float, default=60.0, help='FIR span [s]')
    parser.add_argument('--step', type=float, default=0.25,
                        help='moving averages and spacing of the FIR input [s] (the estimator: 0.25)')
    parser.add_argument('--window', type=float, nargs=2, metavar=('T0', 'T1'),
                        help='score from T0 to T1 s of the record, the FIR fitted after --settle')
    args = parser.parse_args()
    simulate = os.path.join(args.devel, 'simulate_imu')
    if not os.access(simulate, os.X_OK):
        sys.exit('wave_hindsight: no simulate_imu in %s' % args.devel)
    axes = args.axes.replace(',', '')
    inputs = args.inputs.split(',')
    if not axes or set(axes) - set(AXES) or not set(inputs) <= {'own', 'all'}:
        sys.exit('wave_hindsight: --axes takes x, y, z (e.g. xyz); --inputs own, all (e.g. own,all)')
    axes = [AXES.index(a) for a in axes]
    scored = ('%g-%g' % tuple(args.window)) if args.window else 'after %g' % args.settle
    print('| scenario | axis | inputs | seeds | FIR span [s] | scored [s] | error [% of true wave RMS] | [% of Hs] |')
    print('|---|---|---|---|---|---|---|---|')
    with tempfile.TemporaryDirectory() as scratch:
        for scenario in args.scenario:
            arm = lever_arm(simulate, scenario)
            ratios = {}
            for seed in range(1, args.seeds + 1):
                csv = os.path.join(scratch, 'seed%d.csv' % seed)
                subprocess.run([simulate, '--scenario', scenario, '--csv', csv, '--seed', str(seed),
                                '--duration', str(args.duration)], check=True, stdout=subprocess.DEVNULL)
                data = np.genfromtxt(csv, delimiter=',', names=True)
                columns = {name: data[name] for name in data.dtype.names}
                level, dt = level_acceleration(columns, arm)
                for axis in axes:
                    for which in inputs:
                        source = level[:, axis] if which == 'own' else level
                        ratio, _ = hindsight_error(source, columns['wave_p' + AXES[axis]], dt, args.settle,
                                                   args.span, args.window, args.step)
                        ratios.setdefault((axis, which), []).append(ratio)
                print('%s seed %d done' % (os.path.basename(scenario), seed), file=sys.stderr)
            for (axis, which), values in sorted(ratios.items()):
                rms = 100 * np.sqrt(np.mean(values))
                # % of Hs = error RMS / (4 std); the wave's mean is near zero, so its RMS ~ std.
                print('| %s | %s | %s | %d | %.0f | %s | %.1f | %.2f |' % (
                    os.path.splitext(os.path.basename(scenario))[0], AXES[axis], which, args.seeds, args.span,
                    scored, rms, rms / 4))


if __name__ == '__main__':
    main()
