"""Tables and plots of scripts/bench.py's ROS-side measurements, from the data it keeps in
docs/bench/results.json (markdown returned as a string, plots written as png files).

  nodelet_markdown(runs), nodelet_plot(runs, png)   runs: [{'label': ..., 'fields': {key: value}}]
                                                      of nodelet_benchmark's result lines
  bag_markdown(runs, core)                          bag_read_floor / compensate_bag runs (as above),
                                                      core medians [{'name', 'real_time', 'items'}]
  memory_markdown(rows, bag_rss), memory_plot(...)  the nodelet's RSS rows (its --rss-csv), and
                                                      compensate_bag's [[wall s, RSS kB]]
"""
import statistics


def fields(line):
    """nodelet_benchmark's and bag_read_floor's "key=value ..." result line as a dict."""
    return dict(kv.split('=', 1) for kv in line.split())


def core_latency_markdown(runs):
    """The core_latency runs as a table (the rate is 100 Hz in runs that do not say), then per
    rate whether every run's outputs were the same, and at 100 Hz the calls over 1 ms per kind of
    design."""
    out = []
    print = lambda *a: out.append(a[0] if a else '')
    print('| rate [Hz] | designs | run | mean [us] | p50 [us] | p99 [us] | p99.9 [us] | max [us] | calls > 200 us '
          '| calls > 1 ms | slowest calls (data time [s]: us) |')
    print('|---|---|---|---|---|---|---|---|---|---|---|')
    rate = lambda f: float(f.get('rate', 100))
    done = {}
    for f in runs:
        key = (rate(f), f['designs'])
        done[key] = done.get(key, 0) + 1
        slowest = ', '.join('%s: %s' % tuple(c.split(':')) for c in f['slowest'].split(','))
        print('| %g | %s | %d | %.1f | %.1f | %.0f | %.0f | %.0f | %s | %s | %s |' % (
            rate(f), f['designs'], done[key], float(f['mean_us']), float(f['p50_us']), float(f['p99_us']),
            float(f['p999_us']), float(f['max_us']), f['over_200us'], f['over_1ms'], slowest))
    print()
    rates = sorted({rate(f) for f in runs})
    same = all(len({f['checksum'] for f in runs if rate(f) == r}) == 1 for r in rates)
    print('Outputs of every run at one rate the same (sum of the positions over the run): **%s**.'
          % ('yes' if same else 'no'))
    slow = [f for f in runs if rate(f) == 100]
    kinds = sorted({f['designs'] for f in slow}, key=lambda k: k != 'background')
    print('Calls over 1 ms at 100 Hz, %s: **%s**; calls over 200 us: **%s**.' % (
        ' / '.join(kinds),
        ' / '.join(str(sum(int(f['over_1ms']) for f in slow if f['designs'] == k)) for k in kinds),
        ' / '.join(str(sum(int(f['over_200us']) for f in slow if f['designs'] == k)) for k in kinds)))
    return '\n'.join(out) + '\n'


def _nodelet_rows(runs):
    rows = [(r['label'], r['fields']) for r in runs if 'group' not in r]
    by = {(f['transport'], label): f for label, f in rows}
    sustained_rows = {}  # by transport: the fastest paced run below the closed loop without a drop
    for (t, label), f in by.items():
        if '% of closed loop' in label and str(f['dropped']) == '0' and \
                float(f['rate']) > float(sustained_rows.get(t, {'rate': 0})['rate']):
            sustained_rows[t] = f
    return rows, by, sustained_rows


def nodelet_markdown(runs):
    rows, by, sustained_rows = _nodelet_rows(runs)
    out = []
    print = lambda *a: out.append(a[0] if a else '')
    print('| transport | input | sent | dropped | input rate [msg/s] | latency p50 [us] | p99 [us] | max [us] |')
    print('|---|---|---|---|---|---|---|---|')
    for label, f in rows:
        print('| %s | %s | %s | %s | %.0f | %.0f | %.0f | %.0f |' % (
            f['transport'], label, f['sent'], f['dropped'], float(f['input_rate']),
            float(f['p50_us']), float(f['p99_us']), float(f['max_us'])))
    print()
    closed = {t: float(f['input_rate']) for (t, label), f in by.items() if label == 'closed loop'}
    sustained = {t: float(f['rate']) for t, f in sustained_rows.items()}
    for t in ('intra', 'tcp'):
        print('%s: closed loop %.0f msg/s; maximum sustained without drops: %s.' % (
            {'intra': 'Intra-process', 'tcp': 'Separate process'}[t], closed.get(t, float('nan')),
            '%.0f msg/s' % sustained[t] if t in sustained else 'none of the paced rates tried'))
    print()
    if len(closed) == 2:
        print('Closed-loop rate, intra-process / separate process: **%.2f**.' % (closed['intra'] / closed['tcp']))
    if len(sustained) == 2:
        print('Maximum sustained rate, intra-process / separate process: **%.2f**.'
              % (sustained['intra'] / sustained['tcp']))
    for label in sorted({label for _, label in by if label.endswith('Hz')}):
        if ('intra', label) in by and ('tcp', label) in by:
            a, b = by[('intra', label)], by[('tcp', label)]
            print('Latency p50 at %s, separate process / intra-process: %.0f / %.0f us = **%.1f**.'
                  % (label, float(b['p50_us']), float(a['p50_us']), float(b['p50_us']) / float(a['p50_us'])))
    print()
    side = [(r['label'], r['fields']) for r in runs if r.get('group') == 'side-by-side']
    if side:
        print('Side by side in the same harness, in-process, paced: the compensator (imu/data on a '
              'thread of its own, its default; `manager\'s queues`: `imu_thread: false`), the harness\'s '
              '`relay` (a nodelet that subscribes and publishes as the compensator\'s does, on a thread '
              'of its own, and answers each input with an empty odometry carrying its stamp: the '
              'threads and queues alone, the floor of any nodelet measured here) and imu_tools\' Madgwick '
              'filter nodelet (imu_filter_madgwick/ImuFilterNodelet on the manager\'s queues, accelerometer '
              'and gyro, its imu/data the answer). The harness receives every answer on a thread of its '
              'own. CPU time per message, over the messages sent: `process`, every thread of the process; '
              '`nodelet`, the same without the harness\'s two threads (its publisher and its receiver): the '
              'nodelet measured, the manager\'s threads and roscpp\'s. `SCHED_FIFO P, CPU N`: the threads a '
              'sample passes through (the harness\'s publisher and receiver, the nodelet\'s own thread: the '
              'compensator\'s `imu_thread_priority`) real-time at priority P and every thread of the process '
              'on CPU N (`nodelet_benchmark --realtime-priority P --cpu N`), as on an autopilot computer '
              'that keeps a core for the IMU. `idle CPUs polling`: the process holds a request that no CPU '
              'take longer than 0 us to come out of idle (`--cpu-wakeup-latency 0`, the compensator\'s '
              '`cpu_wakeup_latency`; Linux PM QoS): idle CPUs poll instead of halting, and a thread woken '
              'by another starts at once.' + _side_length(side))
        print()
        print('| nodelet | input | sent | dropped | latency p50 [us] | p99 [us] | max [us] '
              '| CPU per message, process [us] | nodelet [us] |')
        print('|---|---|---|---|---|---|---|---|---|')
        for label, f in side:
            print('| %s | %s | %s | %s | %.0f | %.0f | %.0f | %.1f | %.1f |' % (
                _side_name(f), label, f['sent'], f['dropped'], float(f['p50_us']),
                float(f['p99_us']), float(f['max_us']), float(f.get('cpu_us_per_msg', 'nan')),
                float(f.get('nodelet_cpu_us_per_msg', 'nan'))))
        if not any(f.get('nodelet') == 'madgwick' for _, f in side):
            print()
            print('Madgwick not measured in this run (no built imu_tools given: `--imu-tools DEVEL`).')
        print()
    floor = [(r['label'], r['fields']) for r in runs if r.get('group') == 'floor']
    if floor:
        print('The machine\'s own floor in the same run (`wakeup_floor`: no ROS, no estimator, paced as the '
              'rows above): `handoff`, a thread that sleeps to each sample time wakes a second one waiting on a '
              'condition variable, from the notify to the second running (one hop of a sample: a nodelet\'s '
              'answer takes two; notifies that come before the second has run count once, from the first, '
              'hence fewer samples); `timer`, how late the first wakes from its sleep; `spin`, a thread that never '
              'sleeps (ordinary priority, the real-time rows\' CPU, as long as the 1 kHz runs): the times '
              'between two of its clock reads over 10 us, when its CPU was taken from it. No nodelet measured '
              'here can have a maximum below the longest of these.')
        print()
        print('| measurement | input | threads | samples | p50 [us] | p99 [us] | max [us] | over 1 ms |')
        print('|---|---|---|---|---|---|---|---|')
        for label, f in floor:
            threads = ('SCHED_FIFO %s, CPU %s' % (f['realtime_priority'], f['cpu'])
                       if int(f['realtime_priority']) > 0 and f['floor'] != 'spin' else
                       'ordinary' + (', CPU %s' % f['cpu'] if int(f['cpu']) >= 0 else ''))
            threads += _wakeup_request(f)
            print('| %s | %s | %s | %s | %.0f | %.0f | %.0f | %s |' % (
                f['floor'], '-' if f['floor'] == 'spin' else label, threads, f['samples'], float(f['p50_us']),
                float(f['p99_us']), float(f['max_us']), f['over_1ms']))
        print()
    return '\n'.join(out)


def _side_name(f):
    """A side-by-side row's nodelet, and where its input is served or how its threads are scheduled
    when that is not the default."""
    name = f.get('nodelet', 'compensator')
    if f.get('queues') == 'manager':
        name += ", manager's queues"
    if int(f.get('realtime_priority', '0')) > 0:
        name += ', SCHED_FIFO %s, CPU %s' % (f['realtime_priority'], f.get('cpu', 'any'))
    return name + _wakeup_request(f)


def _wakeup_request(f):
    """', idle CPUs polling' (or the wake-up latency asked for) where the run held such a request."""
    latency = float(f.get('cpu_wakeup_latency', '-1'))
    if latency < 0:
        return ''
    return ', idle CPUs polling' if latency == 0 else ', CPU wake-up within %g us' % (latency * 1e6)


def _side_length(side):
    """What the side-by-side runs at the highest rate cover: the CPU per message there is the
    start-up's (calibration window, first spectral designs) unless they go on past it."""
    _, label, seconds = max((float(f['input_rate']), label, float(f['sent']) / float(f['input_rate']))
                            for label, f in side)
    if seconds >= 30.0:
        return (' The %s runs last %.0f s, past the calibration window (10 s) and the first spectral designs.'
                % (label, seconds))
    return ' The %s runs last %.0f s: the start-up (calibration window, first designs) alone.' % (label, seconds)


def nodelet_plot(runs, png):
    _, by, sustained_rows = _nodelet_rows(runs)
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 3.5))
    labels = ['100 Hz', '1 kHz', 'closed loop', 'maximum sustained']
    for i, transport in enumerate(('intra', 'tcp')):
        for j, label in enumerate(labels):
            f = sustained_rows.get(transport) if label == 'maximum sustained' else by.get((transport, label))
            if not f:
                continue
            x = j + (i - 0.5) * 0.35
            ax.bar(x, float(f['p99_us']), 0.33, color='C%d' % i, alpha=0.35)
            ax.bar(x, float(f['p50_us']), 0.33, color='C%d' % i,
                   label=('intra-process (p50 dark, p99 light)' if transport == 'intra'
                          else 'separate process, TCP') if j == 0 else None)
    ax.set_xticks(range(len(labels)))
    ax.set_xticklabels(labels, fontsize=8)
    ax.set_yscale('log')
    ax.set_ylabel('publish to output received [us]')
    ax.legend(fontsize=8)
    ax.grid(axis='y', alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def _bag_runs(bag):
    """The bag's runs by label, and their median messages per second and wall time."""
    runs = {'floor': [], 'whole_bag': [], 'compensate_bag': [], 'compensate_bag_lz4': [], 'compensate_bag_filtered': []}
    for r in bag['runs']:
        runs[r['label']].append(r['fields'])
    rate = {k: statistics.median(float(r['messages_per_s']) for r in v) for k, v in runs.items() if v}
    wall = {k: statistics.median(float(r['wall_s']) for r in v) for k, v in runs.items() if v}
    return int(runs['floor'][0]['messages']), rate, wall


def bag_list(bags):
    """'600 s (154M) and 3600 s (925M)': the bags' lengths and sizes."""
    items = ['%d s (%s)' % (b['seconds'], b['size']) for b in bags]
    return ' and '.join(items) if len(items) < 3 else ', '.join(items[:-1]) + ' and ' + items[-1]


def bag_markdown(bags, core_rows):
    out = []
    print = lambda *a: out.append(a[0] if a else '')
    for bag in bags:
        messages, rate, wall = _bag_runs(bag)
        print('%d s bag:' % bag['seconds'])
        print()
        print('| program | IMU messages | wall time [s] (median of %d) | IMU messages per second '
              '| ratio to the IMU-topic floor | ratio to the whole-bag floor |' % bag['reps'])
        print('|---|---|---|---|---|---|')
        rows = [('read-only floor, IMU topic (`bag_read_floor`)', 'floor'),
                ('read-only floor, whole bag (`bag_read_floor --whole-bag`)', 'whole_bag'),
                ('`compensate_bag`', 'compensate_bag'),
                ('`compensate_bag --compression lz4`', 'compensate_bag_lz4'),
                ('`compensate_bag --outputs filtered` (the navigation output alone)', 'compensate_bag_filtered')]
        for title, key in rows:
            if key not in rate:
                continue
            ratio = lambda floor: '%.1f' % (rate[floor] / rate[key]) if floor in rate else '-'
            print('| %s | %d | %.2f | %.3g | %s | %s |' % (
                title, messages, wall[key], rate[key], ratio('floor'),
                ('**%s**' if key.startswith('compensate_bag') else '%s') % ratio('whole_bag')))
        print()
    # The core against both floors of the longest bag: reading an in-memory array and reading the bag.
    _, rate, wall = _bag_runs(bags[-1])
    core = {r['name']: r['items'] for r in core_rows if r['items']}
    print('| core benchmark | samples per second | ns per sample | ratio to the in-memory floor | ratio to the bag floor |')
    print('|---|---|---|---|---|')
    for name, items in core.items():
        if not name.startswith('compensate/'):
            continue
        scenario = name.split('/')[1].rsplit('_', 1)[0]
        memory = core.get('readFloor/' + scenario)
        print('| %s | %.3g | %.0f | %s | %.2f |' % (name, items, 1e9 / items,
              '%.0f' % (memory / items) if memory else '-', rate['floor'] / items))
    print()
    if 'compensate_bag' in wall:
        print('Where `compensate_bag`\'s time goes on the %d s bag (%.2f s): the core runs on the main thread; '
              'beside it, in threads of their own, the bag is read (`BagReader`), the three output messages are '
              'built and six records per IMU sample (three outputs, three ground-truth messages copied as bytes) '
              'appended to in-memory chunks, which a thread of the writer (`BagWriter`) writes past the page cache '
              'in 4 MiB blocks (direct I/O, where the file system allows it; with `--compression lz4` it also '
              'compresses them), and the check of the bag\'s structure reads the file once more. rosbag alone '
              'reads the whole bag in %.2f s (the whole-bag floor). The core\'s share, measured: "Where '
              'compensate_bag\'s time goes" under "Reliability runs".' % (
                  bags[-1]['seconds'], wall['compensate_bag'], wall.get('whole_bag', float('nan'))))
        print()
    return '\n'.join(out)


def _memory_series(rows):
    hours = [float(r['data_hours']) for r in rows]
    rss = [float(r['rss_kb']) / 1024 for r in rows]
    wall = [float(r['wall_s']) for r in rows]
    outputs = [int(r['outputs']) for r in rows]
    cost = [1e6 * (wall[i] - wall[i - 1]) / (outputs[i] - outputs[i - 1]) for i in range(1, len(rows))]
    return hours, rss, cost


def memory_markdown(rows, bag_rss):
    out = []
    print = lambda *a: out.append(a[0] if a else '')
    hours, rss, cost = _memory_series(rows)
    print('| point | data time [h] | RSS [MB] | cost per message over the last block [us] |')
    print('|---|---|---|---|')
    for name, i in (('start', 1), ('middle', len(rows) // 2), ('end', len(rows) - 1)):
        print('| %s | %.2f | %.1f | %.1f |' % (name, hours[i], rss[i], cost[i - 1]))
    print()
    print('RSS from the first to the last sample: %.1f -> %.1f MB (%+.1f MB), max %.1f MB; '
          'cost per message: median of the first tenth %.1f us, of the last tenth %.1f us.'
          % (rss[0], rss[-1], rss[-1] - rss[0], max(rss), statistics.median(cost[:len(cost) // 10 or 1]),
             statistics.median(cost[-(len(cost) // 10 or 1):])))
    print()
    bag_t = [float(t) for t, _ in bag_rss]
    bag_rss_mb = [float(kb) / 1024 for _, kb in bag_rss]
    if bag_rss_mb:
        print('`compensate_bag` on the long bag: RSS %.1f MB after %.1f s, %.1f MB at the end (%.1f s).'
              % (bag_rss_mb[0], bag_t[0], bag_rss_mb[-1], bag_t[-1]))
        print()
    return '\n'.join(out)


def memory_plot(rows, bag_rss, png):
    hours, rss, cost = _memory_series(rows)
    bag_t = [float(t) for t, _ in bag_rss]
    bag_rss_mb = [float(kb) / 1024 for _, kb in bag_rss]
    import matplotlib
    matplotlib.use('Agg')
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 3, figsize=(12, 3.4))
    axes[0].plot(hours, rss)
    axes[0].set_xlabel('data time [h]')
    axes[0].set_ylabel('RSS [MB]')
    axes[0].set_ylim(0, max(rss) * 1.2)
    axes[0].set_title('nodelet in-process, fed at full speed', fontsize=9)
    axes[1].plot(hours[1:], cost, lw=0.6)
    axes[1].set_xlabel('data time [h]')
    axes[1].set_ylabel('wall time per message [us]')
    axes[1].set_ylim(0, statistics.median(cost) * 3)
    axes[1].set_title('cost per message (per minute of data)', fontsize=9)
    if bag_t:
        axes[2].plot(bag_t, bag_rss_mb)
        axes[2].set_ylim(0, max(bag_rss_mb) * 1.2)
    axes[2].set_xlabel('wall time [s]')
    axes[2].set_ylabel('RSS [MB]')
    axes[2].set_title('compensate_bag on the long bag', fontsize=9)
    for ax in axes:
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=110)
