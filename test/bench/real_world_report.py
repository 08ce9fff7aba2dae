#!/usr/bin/python3
"""Renders the figures test_core's RealWorldStreams tests record (gtest XML, --gtest_output=xml)
as the table of docs/benchmarks.md's section "Real-world streams" (scripts/bench.py keeps them in
docs/bench/results.json and renders them with markdown()).

  real_world_report.py RESULTS.xml
"""
import sys
import xml.etree.ElementTree as ET


def properties(path):
    """{test name: {property: float}} of the RealWorldStreams tests."""
    found = {}
    for case in ET.parse(path).iter('testcase'):
        values = {}
        for prop in case.iter('property'):
            values[prop.get('name')] = float(prop.get('value'))
        for key, value in case.attrib.items():  # older gtest: properties as attributes
            if key not in ('name', 'status', 'result', 'time', 'timestamp', 'classname', 'file', 'line'):
                values[key] = float(value)
        found[case.get('name')] = values
    return found


def seeds(values, prefix):
    keys = [k for k in values if k.startswith(prefix) and k[len(prefix):].isdigit()]
    return [values[k] for k in sorted(keys, key=lambda k: int(k[len(prefix):]))]


def markdown(tests):
    """The table of {test name: {property: value}}, as a string."""
    out = []
    print = out.append
    rest = tests['SensorAtRestInventsNoMotion']
    bench = tests['SlowPeriodicBiasIsBiasNotMotion']
    jitter = tests['StampJitterChangesNothing']
    sea = tests['MooredBroadSeaHeave']
    real = tests.get('RealIMUsAtRestInventNoMotion', {})
    print('| stream | figure | target | measured (per seed) |')
    print('|---|---|---|---|')
    print('| at rest, 600 s, RW 2-6e-4 m/s^2/sqrt(s), bias to 0.08 m/s^2 | max \\|odometry/wave\\| [m] | <= 0.02 | %s |'
          % ' '.join('%.3f' % v for v in seeds(rest, 'max_wave_')))
    print('| | max odometry/filtered excursion [m] | <= 0.02 | %s |'
          % ' '.join('%.3f' % v for v in seeds(rest, 'max_filtered_')))
    print('| shaken bench, bias drift 0.02-0.06 m/s^2 over 60-240 s | wave RMS error after 20 s [%% of true] | <= 5 | %s |'
          % ' '.join('%.1f' % (100 * v) for v in seeds(bench, 'wave_error_')))
    print('| | slow error at 60 s [m] | <= 0.02 | %s |' % ' '.join('%.3f' % v for v in seeds(bench, 'slow_error_')))
    print('| | max odometry/filtered in the first 20 s [m] | <= 0.02 | %s |'
          % ' '.join('%.3f' % v for v in seeds(bench, 'filtered_first_20s_')))
    print('| bench stamps jittered by +-25 %% of the period | wave RMS error [%% of true] | within 10 %% of exact | %.2f (exact %.2f) |'
          % (100 * jitter['wave_error_jittered'], 100 * jitter['wave_error_clean']))
    print('| moored JONSWAP, 15 min, clean sensor | heave RMS error [%% of Hs] | - | %s |'
          % ' '.join('%.2f' % v for v in seeds(sea, 'heave_error_percent_hs_clean_')))
    print('| moored JONSWAP, 15 min, RW 6e-4 m/s^2/sqrt(s) | heave RMS error [%% of Hs] | median <= 4, worst <= 6 | %s |'
          % ' '.join('%.2f' % v for v in seeds(sea, 'heave_error_percent_hs_random_walk_')))
    slow = tests.get('MooredHeaveVarianceStaysHonestUnderSlowBias', {})
    slow_errors = seeds(slow, 'heave_error_percent_hs_')
    if slow_errors:
        print('| moored JONSWAP, 15 min, RW 6e-4 and a slow periodic bias of 0.04 m/s^2 (120-240 s) | heave RMS error '
              '[%% of Hs] (mean squared error over the mean published variance) | variance: 1/3 to 2.5 | %s |'
              % ' '.join('%.2f (%.2f)' % (v, w) for v, w in zip(slow_errors, seeds(slow, 'heave_error_to_variance_'))))
    horizontal = tests.get('MooredBroadSeaSurgeAndSway', {})
    for axis in ('surge', 'sway'):
        errors = seeds(horizontal, axis + '_error_')
        alone = seeds(horizontal, axis + '_error_harmonic_')
        bounds = seeds(horizontal, axis + '_bound_')
        if len(bounds) == len(errors):  # results from before the bound was measured have none
            cells = ['%.1f (%.1f; %.1f)' % (100 * v, 100 * w, 100 * b) for v, w, b in zip(errors, alone, bounds)]
            figure = '(harmonic model alone; causal bound)'
        else:
            cells = ['%.1f (%.1f)' % (100 * v, 100 * w) for v, w in zip(errors, alone)]
            figure = '(harmonic model alone)'
        print('| moored sea, horizontal motion not locked to heave, 30 min, RW 6e-4 | %s RMS error [%% of true] '
              '%s | < 35 and < half of it | %s |' % (axis, figure, ' '.join(cells)))
    hull = tests.get('MooredHullWithLeverArm', {})
    minutes = '%g min' % (hull.get('hull_duration_s', 1200) / 60)
    for axis, label, target in ((0, 'surge RMS error [% of true]', '<= 20 (MRU grade)'),
                                (1, 'sway RMS error [% of true]', '<= 20 (MRU grade)'),
                                (2, 'heave RMS error [% of Hs]', '<= 3 (MRU grade)')):
        print('| moored hull of its own, IMU 5 m aft, 1 m to port, 4 m up, lever arm configured, %s, '
              'RW 2e-4 | %s (lever arm not configured) | %s | %s |'
              % (minutes, label, target, ' '.join('%.1f (%.1f)' % (v, w) for v, w in
                                                zip(seeds(hull, 'lever_wave_error_%d_' % axis),
                                                    seeds(hull, 'no_lever_wave_error_%d_' % axis)))))
    yawing = tests.get('HullYawingInWavesKeepsSurgeAndSway', {})
    for axis, label in ((0, 'surge'), (1, 'sway')):
        print('| the same hull yawing 0.12 rad in the waves, IMU at the reference point | %s RMS error [%% of true] '
              '| < 40 | %s |' % (label, ' '.join('%.1f' % v for v in seeds(yawing, 'yawing_wave_error_%d_' % axis))))
    for name, label in (('adis16405', 'ADIS16405 at rest, 10 min'), ('mpu6050_100s', 'MPU-6050 at rest, 100 s'),
                        ('mpu6050_449s', 'MPU-6050 at rest, 449 s')):
        if name + '_gyro_attitude_max_wave' not in real:
            print('| %s | (../shared/data absent: skipped) | | |' % label)
            continue
        print('| %s, gyro attitude (default) | max \\|wave\\|, filtered excursion [m] | <= 0.02 | %.3f, %.3f |'
              % (label, real[name + '_gyro_attitude_max_wave'], real[name + '_gyro_attitude_max_filtered']))
        print('| %s, one level frame | max \\|wave\\|, filtered excursion [m] | <= 0.02 | %.3f, %.3f |'
              % (label, real[name + '_one_frame_max_wave'], real[name + '_one_frame_max_filtered']))
    return '\n'.join(out)


def main():
    print(markdown(properties(sys.argv[1])))


if __name__ == '__main__':
    main()
