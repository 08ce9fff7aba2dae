#!/usr/bin/python3
"""Benchmarks: accuracy on the simulator's shipped scenarios (truth known) and speed of the core
and of the ROS side. Measurements go to docs/bench/results.json; docs/benchmarks.md is rendered
from it with the template docs/bench/benchmarks.md.in. Ratios are measured in the same run;
absolute times depend on the machine (recorded in the output).

  scripts/bench.py run [--quick] [--only SECTION,...] [--robot-localization DEVEL] [--imu-tools DEVEL]
                       [--json PATH] [--out PATH]
  scripts/bench.py render [--json PATH] [--out PATH]

run: builds the benchmark programs (scripts/setup), measures (progress on stderr), writes the JSON
  and renders. --only measures the given sections alone and keeps the JSON's other sections.
  --quick: 3 seeds instead of 10, short scenarios, short ROS runs.
  --robot-localization, --imu-tools (or $PBC_ROBOT_LOCALIZATION, $PBC_IMU_TOOLS): devel folders of
  built copies of those packages (not in this repository; skipped with a message without);
  $PBC_BENCH_EXTERNAL_SEEDS: seeds of the external accuracy runs (1).
render: the JSON to markdown only (plots beside the output, in bench/).
--out: the markdown (default docs/benchmarks.md; its plots go to bench/ beside it). The sections
  from "## Reliability runs" on are kept by hand and carried over from docs/benchmarks.md.
Sections: core-speed, core-latency, nodelet, bag, memory, accuracy, external-accuracy, real-recordings,
  real-world, simulator-speed.
"""
import argparse
import csv
import datetime
import glob
import io
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(REPO, 'test', 'bench'))
import bench_render  # noqa: E402
import real_world_report  # noqa: E402
from bench_report import fields  # noqa: E402
from bench_tables import parse_blocks  # noqa: E402

JSON = os.path.join(REPO, 'docs', 'bench', 'results.json')
OUT = os.path.join(REPO, 'docs', 'benchmarks.md')
TEMPLATE = os.path.join(REPO, 'docs', 'bench', 'benchmarks.md.in')
# The CPU the real-time side-by-side runs are pinned to (the machines measured have two).
REALTIME_CPU = 1
# Where Linux takes CPU wake-up latency requests (PM QoS): rows asking idle CPUs to poll need to
# write it.
WAKEUP_LATENCY_DEVICE = '/dev/cpu_dma_latency'
TARGETS = ('core_benchmark', 'core_latency', 'evaluate_compensator', 'nodelet_benchmark', 'bag_read_floor', 'simulate_imu',
           'compensate_bag', 'test_core', 'wakeup_floor')
PY = '/usr/bin/python3'  # Debian's ROS modules live there, not in another python on PATH


def log(message):
    print('[bench] ' + message, file=sys.stderr, flush=True)


def load(path):
    if os.path.exists(path):
        with open(path) as f:
            return json.load(f)
    return {'sections': {}}


def render(results, out):
    with open(TEMPLATE) as f:
        template = f.read()
    results = dict(results)
    with open(OUT) as f:  # the hand-kept sections, from the committed file
        results['kept'] = bench_render.kept_section(f.read())
    text = bench_render.render(results, template, os.path.join(os.path.dirname(os.path.abspath(out)), 'bench'))
    with open(out, 'w') as f:
        f.write(text)
    return text


class Bench:
    """One run: the workspace's programs, a temporary folder, the settings of --quick."""

    def __init__(self, args):
        self.args = args
        self.quick = args.quick
        self.tmp = tempfile.mkdtemp(prefix='pbc_bench_')
        self.master = None
        self.seeds = 3 if self.quick else 10
        self.scenarios = (['paper_bench', 'moored_sea_state_4'] if self.quick else
                          ['paper_bench', 'moored_sea_state_4', 'moored_sea_state_4_bias_wander', 'swell_and_wind_sea',
                           'swell_and_wind_sea_bias_wander', 'underway_course_changes'])
        self.sea_duration = 600 if self.quick else 1800  # [s]: slow-motion errors at 60 s, 10 min, 30 min
        # Rates and lengths of the ROS side.
        self.paced_s = [10, 5, 5] if self.quick else [30, 20, 10]
        # The side-by-side 2.8 kHz runs: past the calibration window (10 s) and the first spectral designs.
        self.side_fast_s = 5 if self.quick else 40
        self.max_data_s = 30 if self.quick else 600
        self.bag_lengths = [600] if self.quick else [600, 3600]  # [s]
        self.memory_s = 7200 if self.quick else 86400
        self.bag_reps = {600: 1} if self.quick else {600: 5, 3600: 3}
        self.ros_scenario = os.path.join(REPO, 'config/scenarios/swell_and_wind_sea.yaml')  # 100 Hz, two seas
        with open(self.ros_scenario) as f:  # the scenario's own seed
            self.ros_seed = int(re.search(r'^seed: *(\d+)', f.read(), re.M).group(1))
        self.env = self.setup()
        self.bin = os.path.join(self.ws, 'devel/lib/periodic_bias_compensation')
        self.bags = {}

    def setup(self):
        """scripts/setup (install, build), the benchmark targets, and devel/setup.bash's environment."""
        script = ('source "%s/scripts/setup" >&2 && cd "$PBC_WS" && '
                  '{ catkin_make -j2 %s > "$PBC_WS/bench_build.log" 2>&1 || '
                  '{ tail -n 40 "$PBC_WS/bench_build.log" >&2; exit 1; }; } && '
                  'set +u && source devel/setup.bash && env -0' % (REPO, ' '.join(TARGETS)))
        r = subprocess.run(['bash', '-c', script], stdout=subprocess.PIPE,
                           env=dict(os.environ, PATH='/usr/sbin:/usr/bin:/sbin:/bin'))
        if r.returncode:
            sys.exit(1)
        env = dict(kv.split('=', 1) for kv in r.stdout.decode().split('\0') if '=' in kv)
        self.ws = env['PBC_WS']
        return env

    def exe(self, name):
        return os.path.join(self.bin, name)

    def close(self):
        if self.master:
            self.master.send_signal(signal.SIGINT)
            try:
                self.master.wait(20)
            except subprocess.TimeoutExpired:
                self.master.kill()
        shutil.rmtree(self.tmp, ignore_errors=True)

    def start_master(self):
        if self.master:
            return
        port = 11500 + random.randrange(400)
        self.env.update(ROS_HOME=os.path.join(self.tmp, 'ros'), ROS_MASTER_URI='http://127.0.0.1:%d' % port)
        with open(os.path.join(self.tmp, 'master.log'), 'w') as f:
            self.master = subprocess.Popen(['rosmaster', '--core', '-p', str(port)], env=self.env, stdout=f,
                                           stderr=subprocess.STDOUT)
        time.sleep(2)

    def output(self, cmd, **kw):
        return subprocess.run(cmd, env=self.env, stdout=subprocess.PIPE, universal_newlines=True, **kw)

    # --- sections: each returns its JSON ---

    def core_speed(self):
        log('core speed (Google Benchmark, 5 repetitions, medians)')
        r = self.output([self.exe('core_benchmark'), '--benchmark_repetitions=5',
                         '--benchmark_report_aggregates_only=true', '--benchmark_format=csv'],
                        stderr=subprocess.DEVNULL)
        rows = []
        for cells in csv.reader(io.StringIO(r.stdout)):
            if cells and cells[0].endswith('_median'):
                rows.append({'name': cells[0].replace('_median', ''), 'real_time': float(cells[2]),
                             'items': float(cells[6]) if len(cells) > 6 and cells[6] else 0.0})
        return {'repetitions': 5, 'rows': rows}

    def core_latency(self):
        data_s, speed, repetitions = (60, 4, 1) if self.quick else (300, 4, 2)
        log('core latency: %d s of data at %g times its pace, designs in the background and in the call'
            % (data_s, speed))

        def latency(*args):
            """The figures of one core_latency run on the ROS scenario."""
            r = self.output([self.exe('core_latency'), '--scenario', self.ros_scenario] + [str(a) for a in args],
                            check=True)
            return fields([line for line in r.stdout.split('\n') if line.startswith('designs=')][-1])

        runs = []
        for _ in range(repetitions):
            for designs in ('background', 'calling'):
                runs.append(latency('--duration', data_s, '--speed', speed, '--designs', designs))
        # The nodelet's faster rates, at the IMU's own pace: what the first samples and the end of
        # the calibration window cost where the buffers sized for the rate are largest.
        fast_s = 15 if self.quick else 30
        for rate in (1000, 2800):
            log('core latency: %d s of data at %d Hz at its own pace' % (fast_s, rate))
            runs.append(latency('--duration', fast_s, '--rate', rate, '--speed', 1))
        return {'seed': self.ros_seed, 'duration': data_s, 'speed': speed, 'fast_duration': fast_s, 'runs': runs}

    def nodelet_run(self, label, transport, *extra, env=None, group=None):
        """One nodelet_benchmark run: {'label', 'fields'} (and 'group' when given); tcp starts
        compensator_node first. `env`: another environment (one that finds imu_tools' nodelet)."""
        node = None
        with open(os.path.join(self.tmp, 'node.log'), 'a') as node_log:
            if transport == 'tcp':
                node = subprocess.Popen([self.exe('compensator_node'), '__name:=compensator'], env=self.env,
                                        stdout=node_log, stderr=subprocess.STDOUT)
            r = subprocess.run([self.exe('nodelet_benchmark'), '--transport', transport, '--scenario',
                                self.ros_scenario] + [str(x) for x in extra], env=env or self.env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
            with open(os.path.join(self.tmp, 'nodelet.log'), 'a') as f:  # ROS's log lines, also on stdout
                f.write(r.stdout)
            lines = [line for line in r.stdout.split('\n') if line.startswith('transport=')]
            if node:
                node.send_signal(signal.SIGINT)
                node.wait()
        if r.returncode or not lines:
            sys.stderr.write('\n'.join(r.stdout.split('\n')[-20:]) + '\n')
            raise RuntimeError('nodelet_benchmark failed (%s, %s)' % (label, transport))
        run = {'label': label, 'fields': fields(lines[-1])}
        if group:
            run['group'] = group
        return run

    def nodelet(self):
        self.start_master()
        runs = []
        for transport in ('intra', 'tcp'):
            log('nodelet (%s): 100 Hz, 1 kHz, maximum' % transport)
            runs.append(self.nodelet_run('100 Hz', transport, '--rate', 100, '--duration', self.paced_s[0]))
            runs.append(self.nodelet_run('1 kHz', transport, '--rate', 1000, '--duration', self.paced_s[1]))
            closed = self.nodelet_run('closed loop', transport, '--rate', 1000, '--duration', self.max_data_s,
                                      '--closed-loop')
            runs.append(closed)
            # Paced at 75, 50, 25 % of the closed-loop rate: the first with no message dropped is the
            # sustained maximum (to 25 % of the closed-loop rate).
            for percent in (75, 50, 25):
                rate = int(float(closed['fields']['input_rate']) * percent / 100)
                run = self.nodelet_run('%d %% of closed loop, %d Hz' % (percent, rate), transport, '--rate', rate,
                                       '--duration', self.paced_s[2])
                runs.append(run)
                if run['fields']['dropped'] == '0':
                    break
        runs += self.nodelet_side_by_side()
        runs += self.wakeup_floor()
        return {'seed': self.ros_seed, 'paced_s': self.paced_s, 'max_data_s': self.max_data_s, 'runs': runs}

    def madgwick_env(self):
        """This run's environment extended by imu_tools' DEVEL/setup.bash, or None when no built copy
        of imu_filter_madgwick's nodelet was given (--imu-tools)."""
        devel = self.args.imu_tools
        if not devel or not glob.glob(os.path.join(devel, 'lib', 'libimu_filter_nodelet.so')):
            log('nodelet side by side: no built imu_tools given (--imu-tools DEVEL), Madgwick not measured')
            return None
        r = subprocess.run(['bash', '-c', 'set +u && source "%s/setup.bash" --extend && env -0' % devel],
                           env=self.env, stdout=subprocess.PIPE, check=True)
        return dict(kv.split('=', 1) for kv in r.stdout.decode().split('\0') if '=' in kv)

    def nodelet_side_by_side(self):
        """The compensator (imu/data on its own thread, then on the manager's queues), the harness's
        own relay (both also real-time on one CPU) and imu_tools' Madgwick nodelet in the same
        harness, in-process, paced at 100 Hz, 1 kHz and 2.8 kHz: latency and CPU time per message
        (the process's, and without the harness's threads); then the compensator, the relay and
        Madgwick again with idle CPUs polling (a wake-up latency request of 0), where this user may
        ask for it."""
        madgwick = self.madgwick_env()
        polling = self.polling_allowed()
        log('nodelet side by side: 100 Hz, 1 kHz, 2.8 kHz, with the relay' + (' and Madgwick' if madgwick else '')
            + (', also with idle CPUs polling' if polling else ''))
        # Each rate's runs: (nodelet_benchmark's options, environment). Real-time: the sample's threads
        # at SCHED_FIFO 50, the process on one CPU.
        realtime = ['--realtime-priority', 50, '--cpu', REALTIME_CPU]
        poll = ['--cpu-wakeup-latency', 0]
        variants = [([], None), (['--manager-queues'], None), (['--nodelet', 'relay'], None)]
        variants += [(['--nodelet', nodelet] + realtime, None) for nodelet in ('compensator', 'relay')]
        if madgwick:
            variants.append((['--nodelet', 'madgwick'], madgwick))
        if polling:
            variants += [(['--nodelet', nodelet] + poll, None) for nodelet in ('compensator', 'relay')]
            variants.append((poll + realtime, None))
            if madgwick:
                variants.append((['--nodelet', 'madgwick'] + poll, madgwick))
        runs = []
        for label, rate, seconds in (('100 Hz', 100, self.paced_s[0]), ('1 kHz', 1000, self.paced_s[1]),
                                     ('2.8 kHz', 2800, self.side_fast_s)):
            for extra, env in variants:
                runs.append(self.nodelet_run(label, 'intra', '--rate', rate, '--duration', seconds, *extra, env=env,
                                             group='side-by-side'))
        return runs

    def polling_allowed(self):
        """Whether this user may ask that idle CPUs poll (write the wake-up latency device); logs
        why not otherwise."""
        if os.access(WAKEUP_LATENCY_DEVICE, os.W_OK):
            return True
        log('no write access to %s: the rows with idle CPUs polling are not measured' % WAKEUP_LATENCY_DEVICE)
        return False

    def wakeup_floor(self):
        """The machine's own floor under the side-by-side latencies (wakeup_floor: a timed thread
        waking another, no ROS), paced as those, ordinary and real-time on the same CPU, then both
        with idle CPUs polling where allowed; after the real-time 1 kHz run, a thread that never
        sleeps on that CPU."""
        log('wakeup floor: 100 Hz, 1 kHz, ordinary and real-time; a spinning thread')
        runs = []
        poll = [['--cpu-wakeup-latency', 0]] if self.polling_allowed() else []
        for label, rate, seconds in (('100 Hz', 100, self.paced_s[0]), ('1 kHz', 1000, self.paced_s[1])):
            realtime = ['--realtime-priority', 50, '--cpu', REALTIME_CPU]
            spin = ['--spin'] if rate == 1000 else []
            for extra in [[], realtime + spin] + [p + q for p in poll for q in ([], realtime)]:
                r = self.output([self.exe('wakeup_floor'), '--rate', str(rate), '--duration', str(seconds)]
                                + [str(x) for x in extra], check=True)
                runs += [{'label': label, 'group': 'floor', 'fields': fields(line)}
                         for line in r.stdout.split('\n') if line.startswith('floor=')]
        return runs

    def bag(self, seconds):
        """A bag of SECONDS of the ROS scenario that the bag section reads (simulated once per run)."""
        if seconds not in self.bags:
            self.bags[seconds] = os.path.join(self.tmp, 'sea%d.bag' % seconds)
            with open(os.path.join(self.tmp, 'sim.log'), 'w') as f:
                subprocess.run([self.exe('simulate_imu'), '--scenario', self.ros_scenario, '--duration',
                                str(seconds), '--out', self.bags[seconds]], env=self.env, stdout=f,
                               stderr=subprocess.STDOUT, check=True)
        return self.bags[seconds]

    def timed(self, cmd, rss=None):
        """Wall time of CMD [s] (to 10 ms); with RSS (a list), its RSS every 0.5 s as [s, kB]."""
        log_path = os.path.join(self.tmp, 'compensate.log')
        start = time.time()
        next_sample = start
        with open(log_path, 'w') as f:
            p = subprocess.Popen(cmd, env=self.env, stdout=f, stderr=subprocess.STDOUT)
            while p.poll() is None:
                if rss is not None and time.time() >= next_sample:
                    next_sample += 0.5
                    try:
                        with open('/proc/%d/status' % p.pid) as status:
                            kb = re.search(r'^VmRSS:\s*(\d+)', status.read(), re.M)
                        if kb:
                            rss.append([round(time.time() - start, 2), int(kb.group(1))])
                    except OSError:
                        pass
                time.sleep(0.01)
        wall = time.time() - start
        if p.returncode:
            with open(log_path) as f:
                sys.stderr.write(f.read())
            raise RuntimeError('%s failed' % cmd[0])
        return wall

    def bag_runs(self, seconds, rss):
        """Floors and compensate_bag on one bag, alternating, the output removed before each run."""
        bag = self.bag(seconds)
        log('compensate_bag against a read-only loop on a %d s, 100 Hz bag (%d repetitions)'
            % (seconds, self.bag_reps[seconds]))
        runs = []
        out = os.path.join(self.tmp, 'out.bag')
        for _ in range(self.bag_reps[seconds]):
            for label, extra in (('floor', []), ('whole_bag', ['--whole-bag'])):
                # Timed from outside like the tool (process start and exit included).
                start = time.time()
                line = self.output([self.exe('bag_read_floor'), '--in', bag] + extra, check=True).stdout
                wall = time.time() - start
                floor = fields(line.strip().split('\n')[-1])
                floor.update(wall_s='%.2f' % wall, messages_per_s='%g' % (int(floor['messages']) / max(wall, 0.01)))
                runs.append({'label': label, 'fields': floor})
            messages = int(runs[-1]['fields']['messages'])
            del rss[:]  # the last repetition's is plotted
            for label, extra, sample in (('compensate_bag', [], rss),
                                         ('compensate_bag_lz4', ['--compression', 'lz4'], None),
                                         ('compensate_bag_filtered', ['--outputs', 'filtered'], None)):
                if os.path.exists(out):
                    os.remove(out)
                wall = float('%.2f' % self.timed([self.exe('compensate_bag'), '--in', bag, '--out', out] + extra,
                                                 sample))
                runs.append({'label': label, 'fields': {'messages': str(messages), 'wall_s': '%.2f' % wall,
                                                        'messages_per_s': '%g' % (messages / max(wall, 0.01))}})
        size = self.output(['du', '-h', bag]).stdout.split()[0]
        return {'seconds': seconds, 'size': size, 'reps': self.bag_reps[seconds], 'runs': runs}

    def bag_section(self):
        longest = self.bag(max(self.bag_lengths))
        # The longest bag is the one external nodes read too (add them here).
        log("robot_localization's node on the %d s bag" % max(self.bag_lengths))
        r = self.output([PY, os.path.join(REPO, 'scripts/bench_external.py'), 'throughput', '--bag', longest,
                         '--robot-localization', self.args.robot_localization or ''])
        external = {'blocks': parse_blocks(r.stdout.strip('\n')) if r.returncode == 0 and r.stdout.strip() else []}
        rss = []  # compensate_bag's RSS in its last run on the longest bag
        bags = [self.bag_runs(seconds, rss) for seconds in self.bag_lengths]
        return {'seed': self.ros_seed, 'bags': bags, 'rss': rss, 'external': external}

    def memory(self):
        self.start_master()
        log('memory: the nodelet fed %d s of 100 Hz data at full speed' % self.memory_s)
        rss_csv = os.path.join(self.tmp, 'rss.csv')
        run = self.nodelet_run('memory', 'intra', '--rate', 100, '--duration', self.memory_s, '--closed-loop',
                               '--stream', '--rss-csv', rss_csv, '--rss-every', 6000)
        with open(rss_csv) as f:
            rows = list(csv.DictReader(f))
        return {'seed': self.ros_seed, 'memory_s': self.memory_s, 'result': run, 'rows': rows}

    def accuracy(self):
        scenarios = []
        for sc in self.scenarios:
            log('accuracy: ' + sc)
            duration = [] if sc == 'paper_bench' else ['--duration', str(self.sea_duration)]
            r = self.output([self.exe('evaluate_compensator'), '--scenario',
                             os.path.join(REPO, 'config/scenarios/%s.yaml' % sc), '--seeds', str(self.seeds)]
                            + duration, stderr=subprocess.DEVNULL, check=True)
            scenarios.append({'name': sc, 'blocks': parse_blocks(r.stdout.rstrip('\n'))})
        return {'seeds': self.seeds, 'sea_duration': self.sea_duration, 'scenarios': scenarios}

    def external(self, command, *extra):
        """scripts/bench_external.py's markdown, and whether it failed."""
        r = self.output([PY, os.path.join(REPO, 'scripts/bench_external.py'), command, '--bin', self.bin,
                         '--robot-localization', self.args.robot_localization or '',
                         '--imu-tools', self.args.imu_tools or ''] + list(extra))
        return r.stdout, r.returncode != 0

    def external_accuracy(self):
        # ~600-900 IMU messages per second through ROS (one at a time): one seed of the four scenarios
        # takes ~7 min; more with PBC_BENCH_EXTERNAL_SEEDS.
        seeds = os.environ.get('PBC_BENCH_EXTERNAL_SEEDS', '1')
        log('accuracy: robot_localization and imu_tools')
        text, failed = self.external('accuracy', '--seeds', seeds, '--work', os.path.join(self.tmp, 'external'),
                                     '--scenarios', *[os.path.join(REPO, 'config/scenarios/%s.yaml' % sc)
                                                      for sc in self.scenarios])
        parts = re.split(r'^### (\S+)\n', text, flags=re.M)
        return {'seeds': int(seeds), 'preamble': parts[0].strip('\n').split('\n'), 'failed': failed,
                'scenarios': [{'name': n, 'blocks': parse_blocks(b.strip('\n'))}
                              for n, b in zip(parts[1::2], parts[2::2])]}

    def real_recordings(self):
        log('accuracy: real recordings')
        text, failed = self.external('real', '--work', os.path.join(self.tmp, 'real'))
        return {'blocks': parse_blocks(text.strip('\n')), 'failed': failed}

    def real_world(self):
        # Streams as real IMUs deliver them, made by generators of their own (not the simulator's), and
        # the real recordings at rest: test_core's RealWorldStreams tests record their figures.
        log('real-world streams (test_core RealWorldStreams*)')
        # The hull of the test's own (a second formulation of the sea) for the scenarios' seeds and length.
        xml = os.path.join(self.tmp, 'real_world.xml')
        env = dict(self.env, PBC_HULL_SEEDS=str(self.seeds), PBC_HULL_DURATION=str(self.sea_duration))
        r = subprocess.run([self.exe('test_core'), '--gtest_filter=RealWorldStreams*', '--gtest_output=xml:' + xml],
                           env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, universal_newlines=True)
        failed = len(re.findall(r'FAILED  \]', r.stdout)) if r.returncode else 0
        return {'tests': real_world_report.properties(xml), 'failed_lines': failed}

    def simulator_speed(self):
        log('simulator: 24 h of underway_course_changes')
        duration = 86400
        r = subprocess.run(['/usr/bin/time', '-f', '%e %M', self.exe('simulate_imu'), '--scenario',
                            os.path.join(REPO, 'config/scenarios/underway_course_changes.yaml'), '--duration',
                            str(duration)], env=self.env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                           universal_newlines=True, check=True)
        wall, kb = r.stderr.strip().split('\n')[-1].split()
        return {'duration': duration, 'wall_s': float(wall), 'max_rss_kb': int(kb)}


def read_text(path):
    try:
        with open(path) as f:
            return f.read().strip()
    except OSError:
        return None


def machine():
    """The CPU model (with how an idle core waits, which sets the wake-up latency that the nodelet
    tables hold) and the number of cores."""
    model = re.search(r'^Model name:\s*(.*)$', subprocess.run(['lscpu'], stdout=subprocess.PIPE,
                                                                universal_newlines=True).stdout, re.M)
    described = model.group(1).strip() if model else 'unknown CPU'
    idle = read_text('/sys/devices/system/cpu/cpuidle/current_driver')
    if idle:
        poll = read_text('/sys/module/haltpoll/parameters/guest_halt_poll_ns')
        described += ' (cpuidle driver %s%s)' % (idle, ', guest halt polling %s ns' % poll if poll is not None else '')
    return described, os.cpu_count()


def loadavg():
    with open('/proc/loadavg') as f:
        return ' '.join(f.read().split()[:3])


def run(args):
    only = args.only.split(',') if args.only else list(bench_render.SECTIONS)
    unknown = [s for s in only if s not in bench_render.SECTIONS]
    if unknown:
        sys.exit('unknown section(s): %s (sections: %s)' % (', '.join(unknown), ', '.join(bench_render.SECTIONS)))
    results = load(args.json)
    commit = subprocess.run(['git', '-C', REPO, 'rev-parse', '--short', 'HEAD'], stdout=subprocess.PIPE,
                            universal_newlines=True).stdout.strip()
    # Sources that differ from that commit (the JSON and the docs it renders aside) are said so.
    changed = subprocess.run(['git', '-C', REPO, 'status', '--porcelain', '--untracked-files=no', '--', '.',
                              ':!docs'], stdout=subprocess.PIPE, universal_newlines=True).stdout.strip()
    if changed:
        commit += ' with uncommitted changes'
    model, cores = machine()
    now = datetime.datetime.now(datetime.timezone.utc)
    run_info = {'id': now.strftime('%Y%m%dT%H%M%SZ'), 'date': now.strftime('%Y-%m-%d'), 'commit': commit,
                'quick': args.quick, 'machine': model, 'cores': cores, 'load_start': loadavg(),
                'sections': [s for s in bench_render.SECTIONS if s in only]}
    bench = Bench(args)
    methods = {'core-speed': bench.core_speed, 'core-latency': bench.core_latency, 'nodelet': bench.nodelet, 'bag': bench.bag_section,
               'memory': bench.memory, 'accuracy': bench.accuracy, 'external-accuracy': bench.external_accuracy,
               'real-recordings': bench.real_recordings, 'real-world': bench.real_world,
               'simulator-speed': bench.simulator_speed}
    try:
        for name in bench_render.SECTIONS:  # the order of measurement
            if name in only:
                section = methods[name]()
                section['run'] = {k: run_info[k] for k in ('id', 'date', 'commit', 'quick', 'machine', 'cores')}
                results.setdefault('sections', {})[name] = section
    except (RuntimeError, subprocess.CalledProcessError) as e:
        log('error: %s' % e)
        return 1
    finally:
        bench.close()
    run_info['load_end'] = loadavg()
    results['run'] = run_info
    os.makedirs(os.path.dirname(os.path.abspath(args.json)), exist_ok=True)
    with open(args.json, 'w') as f:
        json.dump(results, f, indent=1, sort_keys=False)
        f.write('\n')
    log('results: %s' % args.json)
    render(results, args.out)
    log('rendered: %s' % args.out)
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest='command', required=True)
    r = sub.add_parser('run', help='measure, write the JSON, render')
    r.add_argument('--quick', action='store_true', help='3 seeds instead of 10, short scenarios, short ROS runs')
    r.add_argument('--only', help='comma-separated sections to measure (the others are kept from the JSON): '
                   + ', '.join(bench_render.SECTIONS))
    r.add_argument('--robot-localization', default=os.environ.get('PBC_ROBOT_LOCALIZATION', ''))
    r.add_argument('--imu-tools', default=os.environ.get('PBC_IMU_TOOLS', ''))
    d = sub.add_parser('render', help='the JSON to markdown only')
    for p in (r, d):
        p.add_argument('--json', default=JSON, help='results (default docs/bench/results.json)')
        p.add_argument('--out', default=OUT, help='markdown (default docs/benchmarks.md; plots in bench/ beside it)')
    args = parser.parse_args()
    if not os.path.exists(args.json) and (args.command == 'render' or args.only) and \
            os.path.abspath(args.out) == OUT:
        # docs/benchmarks.md would be replaced by a file of "not measured" sections.
        sys.exit('%s does not exist: measure every section first (scripts/bench.py run), or give --json '
                 'and --out' % args.json)
    if args.command == 'render':
        render(load(args.json), args.out)
        return 0
    return run(args)


if __name__ == '__main__':
    sys.exit(main())
