"""The interpretation of docs/benchmarks.md ("Where the baselines win or lose"), computed from the
tables in docs/bench/results.json: every figure is read from them and every comparison (better,
worse, on par) is decided here, so that no sentence outlives the run it describes. A point whose
tables are absent is left out.
"""
import math

from bench_tables import Accuracy

EKF = 'robot_localization EKF'
MADGWICK = 'Madgwick + default'
HARMONIC = 'default, harmonic heave'
ONE_FRAME = 'default, no orientation: one level frame'
GYRO = 'default, no orientation: gyro attitude'
GYRO_BIAS = 'default, no orientation: gyro attitude, gyro bias estimated'
HOLDS = 1.0  # [m]: "default holds the position" where its slow-motion error at the end is below
SAME = 0.10  # relative difference under which two errors are "on par"


def m(v):
    """A length in metres, as the tables round it for prose."""
    a = abs(v)
    return '%.0f' % v if a >= 100 else '%.1f' % v if a >= 1 else '%.2f' % v if a >= 0.01 else '%.3f' % v


def pct(v):
    return '%.0f' % v if abs(v) >= 10 else '%.1f' % v


def factor(v):
    if v >= 1000:
        return '10^%d' % round(math.log10(v))
    return '%.0f' % v if v >= 10 else '%.1f' % v


def span(values, fmt):
    lo, hi = min(values), max(values)
    if fmt(lo) == fmt(hi):
        return fmt(lo)
    signed = lo < 0 or fmt(lo).startswith('+')
    return '%s to %s' % (fmt(lo), fmt(hi)) if signed else '%s-%s' % (fmt(lo), fmt(hi))


def verdict(a, b, lower_is_better=True):
    """a against b: 'on par', 'better' or 'worse' (errors: lower is better)."""
    if abs(a - b) <= SAME * max(abs(a), abs(b)) or a == b:
        return 'on par'
    return 'better' if (a < b) == lower_is_better else 'worse'


def is_bench(scenario):
    return scenario.startswith('paper_bench')


def real_rows(blocks):
    """{recording: {method: error}} of bench_external.py real's table."""
    found = {}
    for b in blocks or []:
        if 'table' in b and b['table']['header'][:2] == ['recording', 'error against its reference']:
            for rec, _, method, value in b['table']['rows']:
                try:
                    found.setdefault(rec, {})[method] = float(value)
                except ValueError:
                    pass
    return found


def ekf_point(ext, real):
    scen = [s for s in ext.scenarios() if EKF in ext.methods(s)]
    if not scen:
        return None
    to_raw, to_default = [], []
    for s in scen:
        for a in 'xyz':
            e, r, d = (ext.get(s, k, a, 'slow_end') for k in (EKF, 'raw', 'default'))
            if e is not None and r:
                to_raw.append(e / r)
            if e is not None and d is not None and 0 < d < HOLDS:
                to_default.append((e / d, '`%s` %s' % (s, a)))
    real_raw = [v[EKF] / v['raw'] for v in real.values() if EKF in v and v.get('raw')]
    for rec, v in real.items():
        if EKF in v and 0 < v.get('default', HOLDS) < HOLDS:
            to_default.append((v[EKF] / v['default'], rec))
    if not to_raw:
        return None
    order = 'of the order of `raw`' if all(0.1 <= r <= 10 for r in to_raw + real_raw) else 'not always of the order of `raw`'
    text = ('- **robot_localization\'s EKF, IMU alone**: %s: its slow-motion error at the end is %s times `raw`\'s '
            'on the simulated scenarios (per axis)' % (order, span(to_raw, lambda v: '%.2f' % v)))
    if real_raw:
        text += ' and %s times on the real recordings' % span(real_raw, lambda v: '%.2f' % v)
    text += ('. Fed the IMU alone it double-integrates the acceleration: nothing it is given bounds the velocity. '
             'It is made to fuse wheel odometry or GNSS with the IMU')
    if to_default:
        lo, hi = min(to_default), max(to_default)
        text += ('; as a stand-alone position source, where `default` holds the position (its error at the end '
                 'below %g m), the EKF\'s error is %s (%s) to %s (%s) times `default`\'s'
                 % (HOLDS, factor(lo[0]), lo[1], factor(hi[0]), hi[1]))
    return text + '.'


def madgwick_point(ext):
    scen = [s for s in ext.scenarios() if MADGWICK in ext.methods(s)]
    if not scen:
        return None
    vertical = []
    for s in scen:
        a, b = ext.get(s, MADGWICK, 'z', 'hs'), ext.get(s, 'default', 'z', 'hs')
        if a is not None and b is not None:
            vertical.append('`%s` %s against %s (%s)' % (s, pct(a), pct(b), verdict(a, b)))
    mw = [v for s in scen for a in 'xy' for v in [ext.get(s, MADGWICK, a, 'wave')] if v is not None]
    dw = [v for s in scen for a in 'xy' for v in [ext.get(s, 'default', a, 'wave')] if v is not None]
    worse = [1 for s in scen for a in 'xy'
             if None not in (ext.get(s, MADGWICK, a, 'total_rms'), ext.get(s, 'default', a, 'total_rms'))
             and verdict(ext.get(s, MADGWICK, a, 'total_rms'), ext.get(s, 'default', a, 'total_rms')) == 'worse']
    text = '- **Madgwick + default** against `default` (the simulator\'s orientation), wave error in % of Hs on z: '
    text += '; '.join(vertical) + '.'
    if mw and dw:
        text += (' Horizontally its wave error is %s %% of the true wave RMS against %s %% for `default`, and its '
                 'total position RMS is worse on %d of %d scenario axes'
                 % (span(mw, pct), span(dw, pct), len(worse), 2 * len(scen)))
        if min(mw) >= 90:
            text += (' (Madgwick\'s attitude leans with the wave accelerations: it takes the accelerometer for '
                     'gravity, gain 0.1, which removes most of the horizontal acceleration before the '
                     'compensator sees it)')
        text += '.'
    return text


def underway_point(main, ext):
    scen = [s for s in main.scenarios() if main.travelled.get(s, 0) > 100]
    if not scen:
        return None
    parts = []
    for s in scen:
        methods = [k for k in ('highpass', 'paper', 'default') if k in main.methods(s)]
        per_axis = []
        for a in 'xy':
            values = {k: main.get(s, k, a, 'slow_end') for k in methods}
            values = {k: v for k, v in values.items() if v is not None}
            if values:
                per_axis.append((a, values))
        if not per_axis:
            continue
        spread = max(100 * (max(v.values()) / min(v.values()) - 1) if min(v.values()) > 0 else float('inf')
                     for _, v in per_axis)
        text = ('`%s` (the ship goes %s m from its start): horizontal slow-motion error at the end %s for %s'
                % (s, m(main.travelled[s]), ', '.join('%s %s m' % (a, span(list(v.values()), m)) for a, v in per_axis),
                   ', '.join('`%s`' % k for k in methods)))
        if spread < 5:
            text += ', equal within %.1f %%: `default` does not beat them there' % spread
        else:
            best = {a: min(v, key=v.get) for a, v in per_axis}
            text += ', best: %s' % ', '.join('%s `%s`' % (a, k) for a, k in best.items())
        if EKF in ext.methods(s):
            e = [ext.get(s, EKF, a, 'slow_rms') for a in 'xy']
            d = [ext.get(s, 'default', a, 'slow_rms') for a in 'xy']
            if None not in e + d:
                text += ('; the EKF\'s slow-motion RMS error (x, y) %s, %s m against %s, %s m for `default`'
                         % (m(e[0]), m(e[1]), m(d[0]), m(d[1])))
        parts.append(text)
    if not parts:
        return None
    return ('- **Underway** (the scenarios whose ship travels; a steady speed cannot be seen in acceleration '
            'at all): ' + '; '.join(parts) + '.')


def real_point(real):
    if not real:
        return None
    pairs = []
    for rec, v in real.items():
        if MADGWICK in v and 'default' in v:
            pairs.append('%s %s against %s m (%s)' % (rec, m(v[MADGWICK]), m(v['default']),
                                                      verdict(v[MADGWICK], v['default'])))
    paper = []
    for rec, v in real.items():
        if 'paper' in v and 'default' in v:
            paper.append('%s %s against %s m (%s)' % (rec, m(v['paper']), m(v['default']),
                                                      verdict(v['paper'], v['default'])))
    text = '- **Real recordings**:'
    if pairs:
        text += (' Madgwick\'s attitude, computed from the sensor itself, under the same `default` compensator '
                 'against the recording\'s own attitude: %s.' % '; '.join(pairs))
    if paper:
        text += ' `paper` against `default`: %s.' % '; '.join(paper)
    return text if pairs or paper else None


def highpass_point(main):
    scen = [s for s in main.scenarios() if 'highpass' in main.methods(s)]
    if not scen:
        return None
    still = []
    for s in scen:
        if s in main.travelled:
            continue
        h = max(main.get(s, 'highpass', a, 'slow_end') or 0 for a in 'xyz')
        d = max(main.get(s, 'default', a, 'slow_end') or 0 for a in 'xyz')
        still.append('`%s` %s m (`default` %s m)' % (s, m(h), m(d)))
    text = ('- **`highpass`** reports no slow motion at all (its one output is taken as the wave motion); its '
            'slow-motion error at the end where the ship holds station, largest axis: %s' % '; '.join(still))
    seas = [s for s in scen if not is_bench(s)]
    hw = [v for s in seas for a in 'xyz' for v in [main.get(s, 'highpass', a, 'wave')] if v is not None]
    dh = [v for s in seas for a in 'xy' for v in [main.get(s, 'default', a, 'wave')] if v is not None]
    dz = [v for s in seas for v in [main.get(s, 'default', 'z', 'wave')] if v is not None]
    if hw and dh and dz:
        side = 'above' if min(hw) > 100 else 'below' if max(hw) < 100 else 'around'
        text += ('. Its wave error on the seas is %s %% of the true wave RMS (%s 100 %%), against %s %% '
                 'horizontally and %s %% vertically for `default`' % (span(hw, pct), side, span(dh, pct), span(dz, pct)))
    return text + '.'


def heave_point(main):
    scen = [s for s in main.scenarios() if HARMONIC in main.methods(s)]
    if not scen:
        return None
    parts, unchanged = [], True
    for s in scen:
        h, d = main.get(s, HARMONIC, 'z', 'hs'), main.get(s, 'default', 'z', 'hs')
        hr, dr = main.get(s, HARMONIC, 'z', 'slow_rms'), main.get(s, 'default', 'z', 'slow_rms')
        if None in (h, d):
            continue
        text = '`%s` %s -> %s %% of Hs' % (s, pct(h), pct(d))
        if h:
            text += ' (x %.2f)' % (d / h)
        if None not in (hr, dr):
            text += ', slow-motion RMS %s -> %s m' % (m(hr), m(dr))
        parts.append(text)
        for a in 'xy':
            for c in ('slow_end', 'slow_rms', 'total_rms', 'wave'):
                if main.cell(s, HARMONIC, a, c) != main.cell(s, 'default', a, c):
                    unchanged = False
    if not parts:
        return None
    return ('- **Heave** (`default, harmonic heave`, the default mode with `heave_filter: false`, against '
            '`default`, docs/algorithm.md), z: %s. The horizontal axes are %s.'
            % ('; '.join(parts), 'unchanged' if unchanged else 'changed too'))


def orientation_point(main, real):
    scen = [s for s in main.scenarios() if ONE_FRAME in main.methods(s)]
    if not scen:
        return None
    seas = [s for s in scen if not is_bench(s)]
    one = [v for s in seas for a in 'xy' for v in [main.get(s, ONE_FRAME, a, 'wave')] if v is not None]
    text = '- **Without the IMU\'s orientation** (`default, no orientation: ...`):'
    if one:
        text += (' one level frame leaks the hull\'s roll and pitch into the horizontal axes: horizontal wave '
                 'error %s %% of the true wave RMS on the simulated seas' % span(one, pct))
    gaps = []
    for s in seas:
        diffs = [(main.get(s, GYRO_BIAS, a, 'wave'), main.get(s, 'default', a, 'wave')) for a in 'xy']
        diffs = [g - d for g, d in diffs if None not in (g, d)]
        if diffs:
            gaps.append('`%s` %s points' % (s, span(diffs, lambda v: '%+.0f' % v if round(v) else '0')))
    if gaps:
        text += ('; the gyro attitude (gyro bias estimated, the default) against the true orientation, '
                 'horizontal wave error: %s' % ', '.join(gaps))
    bias = [main.get(s, GYRO_BIAS, a, 'wave') - main.get(s, GYRO, a, 'wave') for s in seas for a in 'xyz'
            if None not in (main.get(s, GYRO_BIAS, a, 'wave'), main.get(s, GYRO, a, 'wave'))]
    if bias:
        text += '; estimating the gyro bias moves the seas\' wave error by %s points' % span(bias, lambda v: '%+.1f' % v)
    for s in scen:
        if is_bench(s):
            o = max(main.get(s, ONE_FRAME, a, 'slow_end') or 0 for a in 'xyz')
            g = max(main.get(s, GYRO_BIAS, a, 'slow_end') or 0 for a in 'xyz')
            text += ('; on `%s`, where nothing rotates, slow-motion error at the end (largest axis) %s m with one '
                     'frame, %s m with the gyro attitude' % (s, m(o), m(g)))
    recs = []
    for rec, v in real.items():
        if ONE_FRAME in v and 'default' in v and GYRO in v and GYRO_BIAS in v:
            recs.append('%s %s m with one frame, %s / %s m with the gyro attitude (bias not estimated / '
                        'estimated), %s m with the recording\'s attitude'
                        % (rec, m(v[ONE_FRAME]), m(v[GYRO]), m(v[GYRO_BIAS]), m(v['default'])))
    if recs:
        text += '. Real recordings: ' + '; '.join(recs)
    return text + '.'


def points(accuracy, external, real_blocks):
    """The bullets, as markdown, from the accuracy sections' JSON (None where absent)."""
    main = Accuracy({s['name']: s['blocks'] for s in (accuracy or {}).get('scenarios', [])})
    ext = Accuracy({s['name']: s['blocks'] for s in (external or {}).get('scenarios', [])})
    real = real_rows((real_blocks or {}).get('blocks'))
    found = [p(*args) for p, args in ((ekf_point, (ext, real)), (madgwick_point, (ext,)),
                                       (underway_point, (main, ext)), (real_point, (real,)),
                                       (highpass_point, (main,)), (heave_point, (main,)),
                                       (orientation_point, (main, real)))]
    found = [p for p in found if p]
    return '\n'.join(found) if found else 'No table to read from in this render.'
