#!/usr/bin/python3
"""The renderer of docs/benchmarks.md (test/bench/bench_render.py) on a small JSON fixture: every
figure of the fixture reaches the markdown, the prose's figures are computed from it, no
placeholder is left, and a section absent from the JSON reads "not measured".

  test_bench_render.py [--xunit RESULTS.xml]    (the catkin test writes JUnit XML)
"""
import copy
import json
import os
import re
import sys
import unittest

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, HERE)
import bench_render  # noqa: E402
import pyunit_main  # noqa: E402
from bench_tables import table_lines  # noqa: E402

with open(os.path.join(HERE, 'fixtures', 'results_small.json')) as f:
    FIXTURE = json.load(f)
with open(os.path.join(REPO, 'docs', 'bench', 'benchmarks.md.in')) as f:
    TEMPLATE = f.read()
KEPT = '## Reliability runs\n\nKept by hand: 12.5 s.\n\n## Measurements behind the design\n\nAlso kept.'


def render(results):
    results = copy.deepcopy(results)
    results['kept'] = KEPT
    return bench_render.render(results, TEMPLATE)  # no plots: fast, no matplotlib


class RenderTest(unittest.TestCase):
    def assertIn(self, part, whole, msg=None):  # a short message: the rendered file is long
        if part not in whole:
            self.fail(msg or '%r not in the rendered markdown' % part)

    def setUp(self):
        self.md = render(FIXTURE)
        self.sections = FIXTURE['sections']

    def test_no_placeholder_left(self):
        for pattern in (r'\$\{', r'\{\{', r'\$[A-Za-z_]', '<!--'):
            self.assertIsNone(re.search(pattern, self.md), pattern)

    def test_every_section_rendered(self):
        self.assertNotIn('Not measured yet', self.md)
        for heading in ('## Accuracy on simulated scenarios', '## Accuracy against robot_localization',
                        '## Accuracy on real recordings', '### Where the baselines win or lose',
                        '## Real-world streams', '## Speed of the core', '## Latency of the core',
                        '## Speed of the simulator',
                        '## Speed of the nodelet', '## compensate_bag against a read-only loop',
                        '## Memory over a long run'):
            self.assertIn('\n' + heading, self.md)
        self.assertTrue(self.md.rstrip('\n').endswith(KEPT), 'the hand-kept sections close the file')

    def test_header_figures(self):
        run = FIXTURE['run']
        for key in ('machine', 'date', 'commit', 'load_start', 'load_end'):
            self.assertIn(str(run[key]), self.md)
        self.assertIn('%d cores' % run['cores'], self.md)

    def test_another_runs_machine_named_where_it_differs(self):
        results = copy.deepcopy(FIXTURE)
        run = results['sections']['simulator-speed']['run']
        run.update(machine='Another CPU', cores=4)
        self.assertIn('Measured 2026-11-23 at commit def5678, on Another CPU, 4 cores, `--quick`', render(results))
        run.update(machine=FIXTURE['run']['machine'], cores=FIXTURE['run']['cores'])
        self.assertIn('Measured 2026-11-23 at commit def5678, `--quick`', render(results))

    def test_accuracy_tables_verbatim(self):
        for name in ('accuracy', 'external-accuracy'):
            for scenario in self.sections[name]['scenarios']:
                self.assertIn('### %s\n' % scenario['name'], self.md)
                for block in scenario['blocks']:
                    if 'table' in block:
                        for line in table_lines(block['table']['header'], block['table']['rows']):
                            self.assertIn(line, self.md)
                    else:
                        for line in block['text']:
                            self.assertIn(line, self.md)
        self.assertIn('medians over seeds 1..%d;' % self.sections['accuracy']['seeds'], self.md)
        self.assertIn('%d s (`--duration`' % self.sections['accuracy']['sea_duration'], self.md)
        for block in self.sections['real-recordings']['blocks']:
            for row in block.get('table', {}).get('rows', []):
                self.assertIn('| ' + ' | '.join(row) + ' |', self.md)

    def test_nodelet_side_by_side(self):
        results = copy.deepcopy(FIXTURE)
        runs = results['sections']['nodelet']['runs']
        base = dict(runs[0]['fields'], p50_us='111', p99_us='222', max_us='333', cpu_us_per_msg='4.56',
                    nodelet_cpu_us_per_msg='1.23')
        runs += [{'label': '2.8 kHz', 'group': 'side-by-side', 'fields': dict(base, nodelet='compensator')},
                 {'label': '2.8 kHz', 'group': 'side-by-side',
                  'fields': dict(base, nodelet='compensator', queues='manager', p50_us='99')},
                 {'label': '2.8 kHz', 'group': 'side-by-side', 'fields': dict(base, nodelet='relay', p50_us='55')},
                 {'label': '2.8 kHz', 'group': 'side-by-side',
                  'fields': dict(base, nodelet='relay', realtime_priority='50', cpu='1', p50_us='44')},
                 {'label': '2.8 kHz', 'group': 'side-by-side', 'fields': dict(base, nodelet='madgwick', dropped='7')},
                 {'label': '2.8 kHz', 'group': 'side-by-side',
                  'fields': dict(base, nodelet='compensator', realtime_priority='50', cpu='1', cpu_wakeup_latency='0',
                                 p50_us='33')},
                 {'label': '2.8 kHz', 'group': 'side-by-side',
                  'fields': dict(base, nodelet='relay', cpu_wakeup_latency='2e-05', p50_us='22')}]
        md = render(results)
        self.assertIn('| compensator | 2.8 kHz | %s | %s | 111 | 222 | 333 | 4.6 | 1.2 |' % (base['sent'], base['dropped']), md)
        self.assertIn("| compensator, manager's queues | 2.8 kHz | %s | %s | 99 | 222 | 333 | 4.6 | 1.2 |"
                      % (base['sent'], base['dropped']), md)
        self.assertIn('| madgwick | 2.8 kHz | %s | 7 | 111 | 222 | 333 | 4.6 | 1.2 |' % base['sent'], md)
        self.assertIn('| relay | 2.8 kHz | %s | %s | 55 | 222 | 333 | 4.6 | 1.2 |' % (base['sent'], base['dropped']), md)
        self.assertIn('| relay, SCHED_FIFO 50, CPU 1 | 2.8 kHz | %s | %s | 44 | 222 | 333 | 4.6 | 1.2 |'
                      % (base['sent'], base['dropped']), md)
        self.assertIn('| compensator, SCHED_FIFO 50, CPU 1, idle CPUs polling | 2.8 kHz | %s | %s | 33 | 222 | 333 |'
                      % (base['sent'], base['dropped']), md)
        self.assertIn('| relay, CPU wake-up within 20 us | 2.8 kHz | %s | %s | 22 | 222 | 333 |'
                      % (base['sent'], base['dropped']), md)
        self.assertIn('`SCHED_FIFO P, CPU N`: the threads a sample passes through', md)
        self.assertIn('`idle CPUs polling`: the process holds a request', md)
        self.assertNotIn('Madgwick not measured', md)
        # Whether the fastest runs cover the start-up alone is said from their length.
        long_runs = dict(base, sent=str(int(40 * float(base['input_rate']))))
        short_runs = dict(base, sent=str(int(10 * float(base['input_rate']))))
        for fields, said in ((long_runs, 'The 2.8 kHz runs last 40 s, past the calibration window'),
                             (short_runs, 'The 2.8 kHz runs last 10 s: the start-up (calibration window, first '
                                          'designs) alone.')):
            timed = copy.deepcopy(results)
            for run in timed['sections']['nodelet']['runs'][-7:]:
                run['fields'].update(sent=fields['sent'])
            self.assertIn(said, render(timed))
        # The side-by-side runs stay out of the transport table.
        self.assertNotIn('| intra | 2.8 kHz |', md)
        self.assertIn('Madgwick not measured', render(dict(results, sections=dict(
            results['sections'], nodelet=dict(results['sections']['nodelet'], runs=runs[:-3])))))

    def test_wakeup_floor_rows(self):
        results = copy.deepcopy(FIXTURE)
        runs = results['sections']['nodelet']['runs']
        without = render(results)
        self.assertNotIn("The machine's own floor", without)
        floor = dict(rate='1000', samples='20000', p50_us='12.3', p99_us='45.6', max_us='7890.1', over_200us='9',
                     over_1ms='4', realtime_priority='50', cpu='1')
        runs += [{'label': '1 kHz', 'group': 'floor', 'fields': dict(floor, floor='handoff')},
                 {'label': '1 kHz', 'group': 'floor', 'fields': dict(floor, floor='spin', samples='17')},
                 {'label': '100 Hz', 'group': 'floor',
                  'fields': dict(floor, floor='timer', realtime_priority='0', cpu='-1', rate='100')},
                 {'label': '100 Hz', 'group': 'floor',
                  'fields': dict(floor, floor='handoff', realtime_priority='0', cpu='-1', rate='100',
                                 cpu_wakeup_latency='0', p50_us='5.9')}]
        md = render(results)
        self.assertIn("The machine's own floor in the same run", md)
        self.assertIn('| handoff | 1 kHz | SCHED_FIFO 50, CPU 1 | 20000 | 12 | 46 | 7890 | 4 |', md)
        # The spinning thread is never real-time, and paced by nothing.
        self.assertIn('| spin | - | ordinary, CPU 1 | 17 | 12 | 46 | 7890 | 4 |', md)
        self.assertIn('| timer | 100 Hz | ordinary | 20000 | 12 | 46 | 7890 | 4 |', md)
        self.assertIn('| handoff | 100 Hz | ordinary, idle CPUs polling | 20000 | 6 | 46 | 7890 | 4 |', md)
        # The floor stays out of the other tables.
        self.assertTrue(without.startswith(md.split("The machine's own floor")[0]))

    def test_ros_side_figures(self):
        nodelet = self.sections['nodelet']
        for run in nodelet['runs']:
            f = run['fields']
            self.assertIn('| %s | %s | %s | %s | %s | %s | %s | %s |' % (
                f['transport'], run['label'], f['sent'], f['dropped'], f['input_rate'], f['p50_us'], f['p99_us'],
                f['max_us']), self.md)
        self.assertIn('Paced runs last %d s (100 Hz),\n%d s (1 kHz) and %d s' % tuple(nodelet['paced_s']), self.md)
        self.assertIn('maximum sustained without drops: 26669 msg/s', self.md)
        self.assertIn('Closed-loop rate, intra-process / separate process: **5.85**', self.md)
        bag = self.sections['bag']
        self.assertIn('Bags of `swell_and_wind_sea` (seed %d) at 100 Hz from `simulate_imu`, 600 s (154M) and '
                      '3600 s (925M), with' % bag['seed'], self.md)
        for each in bag['bags']:
            self.assertIn('%d s bag:' % each['seconds'], self.md)
            for run in each['runs']:
                self.assertIn('| %s | %s |' % (run['fields']['messages'], run['fields']['wall_s']), self.md)
        # Ratios of the medians, per bag: 428571 / 71428.6 and 363636 / 70175.4 (its whole-bag floor).
        self.assertIn('| `compensate_bag` | 60000 | 0.84 | 7.14e+04 | 6.0 |', self.md)
        self.assertIn('| `compensate_bag` | 360000 | 5.13 | 7.02e+04 | 6.3 | **5.2** |', self.md)
        self.assertIn("time goes on the 3600 s bag", self.md)
        self.assertIn("robot_localization's node: not measured", self.md)
        memory = self.sections['memory']
        self.assertIn('fed %d h of' % (memory['memory_s'] // 3600), self.md)
        self.assertIn('(%d messages' % (memory['memory_s'] * 100), self.md)
        self.assertIn('RSS 1.8 MB after 0.1 s, 112.6 MB at the end (95.2 s)', self.md)
        self.assertIn('| start | 0.03 | 34.6 | 55.0 |', self.md)

    def test_core_simulator_real_world(self):
        for row in self.sections['core-speed']['rows']:
            self.assertIn('| %s | %.1f | %.3g |' % (row['name'], row['real_time'], row['items']), self.md)
        self.assertIn('| compensate/paper_bench_default | 42923.7 | 8.41e+05 | 396.4 | 863 |', self.md)
        sim = self.sections['simulator-speed']
        self.assertIn('%.2f s wall, %d kB max RSS' % (sim['wall_s'], sim['max_rss_kb']), self.md)
        self.assertIn('Measured 2026-11-23 at commit def5678, `--quick`', self.md)  # another run's section
        self.assertIn('| 0.63 (exact 0.64) |', self.md)
        self.assertIn('| 17.1 (84.8) |', self.md)  # no bound in these results: the older row
        self.assertIn('sway RMS error [% of true] (harmonic model alone; causal bound) | < 35 and < half of it '
                      '| 22.8 (88.3; 21.9) |', self.md)
        self.assertIn('slow periodic bias of 0.04 m/s^2 (120-240 s) | heave RMS error [% of Hs] (mean squared error '
                      'over the mean published variance) | variance: 1/3 to 2.5 | 3.41 (1.62) |', self.md)
        self.assertIn('random walk (2 seeds)', self.md)
        self.assertIn('300 components; 1 seed)', self.md)

    def test_core_latency(self):
        self.assertIn('`swell_and_wind_sea` (seed 7), 300 s of 100 Hz data given at 4 times its own pace', self.md)
        self.assertIn('| 100 | background | 1 | 12.6 | 10.7 | 53 | 140 | 542 | 5 | 0 | 0.16: 542, 86.12: 392, '
                      '10.00: 309, 45.99: 240, 35.40: 202 |', self.md)
        self.assertIn('| 100 | calling | 1 | 14.9 | 12.3 | 59 | 443 | 1942 | 25 | 3 |', self.md)
        self.assertIn('Outputs of every run at one rate the same (sum of the positions over the run): **yes**.',
                      self.md)
        self.assertIn('Calls over 1 ms at 100 Hz, background / calling: **0 / 3**; calls over 200 us: **5 / 25**.',
                      self.md)
        # Runs whose outputs differ say so.
        changed = copy.deepcopy(FIXTURE)
        changed['sections']['core-latency']['runs'][1]['checksum'] = '-19.8492'
        self.assertIn('(sum of the positions over the run): **no**.', render(changed))
        # A run at another rate has a row of its own, other outputs, and stays out of the 100 Hz sums.
        fast = copy.deepcopy(FIXTURE)
        run = dict(fast['sections']['core-latency']['runs'][0], rate='1000', checksum='3.5', over_1ms='7')
        fast['sections']['core-latency']['runs'].append(run)
        md = render(fast)
        self.assertIn('| 1000 | background | 1 | 12.6 |', md)
        self.assertIn('**yes**.', md.split('Outputs of every run at one rate')[1].split('\n')[0])
        self.assertIn('Calls over 1 ms at 100 Hz, background / calling: **0 / 3**', md)

    def test_prose_is_computed(self):
        prose = self.md.split('### Where the baselines win or lose')[1].split('\n## ')[0]
        # Heave: z % of Hs, harmonic heave -> default, from the moored ship's table.
        self.assertIn('`moored_sea_state_4` 17 -> 3.8 % of Hs (x 0.22)', prose)
        # Real recordings: Madgwick + default against default on the buoy.
        self.assertIn('buoy_morro_bay 0.43 against 0.72 m (better)', prose)
        self.assertIn('(the ship goes 7200 m from its start)', prose)
        # A changed table changes the wording: Madgwick made worse than default on the buoy.
        changed = copy.deepcopy(FIXTURE)
        for block in changed['sections']['real-recordings']['blocks']:
            for row in block.get('table', {}).get('rows', []):
                if row[0] == 'buoy_morro_bay' and row[2] == 'Madgwick + default':
                    row[3] = '2.500'
        self.assertIn('buoy_morro_bay 2.5 against 0.72 m (worse)', render(changed))

    def test_absent_section(self):
        results = copy.deepcopy(FIXTURE)
        del results['sections']['nodelet']
        del results['sections']['external-accuracy']
        md = render(results)
        self.assertIn('## Speed of the nodelet\n\nNot measured yet: `scripts/bench.py run --only nodelet`.', md)
        self.assertIn('--only external-accuracy', md)
        self.assertNotIn('robot_localization\'s EKF, IMU alone', md)  # its point needs that table
        self.assertIsNone(re.search(r'\$\{', md))

    def test_kept_section(self):
        text = '# Benchmarks\n\nmeasured\n\n' + KEPT + '\n'
        self.assertEqual(bench_render.kept_section(text), KEPT)
        self.assertEqual(bench_render.kept_section('# Benchmarks\n'), '')


if __name__ == '__main__':
    pyunit_main.main(RenderTest)
