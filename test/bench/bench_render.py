"""docs/benchmarks.md from docs/bench/results.json and the template docs/bench/benchmarks.md.in
(Python's string.Template). scripts/bench.py measures and calls render(); the sections from
"## Reliability runs" on are kept by hand and carried over from the current docs/benchmarks.md.
"""
import os
import re
import string

import bench_prose
import bench_report
import real_world_report
from bench_tables import blocks_markdown, table_lines

# The sections of results.json, in the order scripts/bench.py measures them (--only takes these).
SECTIONS = ('core-speed', 'core-latency', 'nodelet', 'bag', 'memory', 'accuracy', 'external-accuracy', 'real-recordings',
            'real-world', 'simulator-speed')
KEPT_HEADINGS = ('## Reliability runs', '## Measurements behind the design')


def kept_section(markdown):
    """The hand-kept part of docs/benchmarks.md: from the first of KEPT_HEADINGS to the end."""
    lines = markdown.split('\n')
    for i, line in enumerate(lines):
        if line in KEPT_HEADINGS:
            return '\n'.join(lines[i:]).rstrip('\n')
    return ''


def split_template(text):
    """[(section id, template text)] of the template, comments dropped."""
    text = re.sub(r'<!--(?! section )(.|\n)*?-->\n?', '', text)
    parts = re.split(r'^<!-- section (\S+) -->\n', text, flags=re.M)
    return list(zip(parts[1::2], parts[2::2]))


def measured_note(section, header_run):
    """A line under the heading when the section comes from another run than the header's."""
    run = section.get('run', {})
    if not header_run or run.get('id') == header_run.get('id'):
        return ''
    machine = ''
    if run.get('machine') and run.get('machine') != header_run.get('machine'):
        machine = ', on %s, %s cores' % (run['machine'], run.get('cores', '?'))
    return '\nMeasured %s at commit %s%s%s (the other sections: see the top).\n' % (
        run.get('date', '?'), run.get('commit', '?'), machine, ', `--quick`' if run.get('quick') else '')


def core_table(rows):
    lines = ['| benchmark | time per run [us] | samples per second | ns per sample per axis '
             '| ratio to the read-only floor |', '|---|---|---|---|---|']
    floor = {r['name'].split('/')[1]: r['items'] for r in rows if r['name'].startswith('readFloor/')}
    for r in rows:
        name, t, items = r['name'], r['real_time'], r['items']
        scenario = name.split('/')[1].rsplit('_', 1)[0] if '/' in name else ''
        ns_axis = 1e9 / items / 3 if items and not name.startswith('fft') else None
        ratio = floor[scenario] / items if items and scenario in floor else None
        lines.append('| %s | %.1f | %.3g | %s | %s |' % (name, t, items, '-' if ns_axis is None else '%.1f' % ns_axis,
                                                        '-' if ratio is None else '%.0f' % ratio))
    return '\n'.join(lines)


def scenario_tables(section):
    return '\n\n'.join('### %s\n\n%s' % (s['name'], blocks_markdown(s['blocks']).strip('\n'))
                       for s in section.get('scenarios', []))


def failed_note(section):
    if section.get('failed'):
        return '\n\n**Not complete: scripts/bench_external.py failed in this run (its error is on stderr).**'
    return ''


def values(name, results, plots_dir):
    """The template's names for one section (None: not measured)."""
    s = results.get('sections', {}).get(name)
    header = results.get('run')
    if name == 'header':
        if not header:
            return None
        v = dict(header)
        v['quick_note'] = ('\n\n**A `--quick` run** (fewer seeds, shorter scenarios and ROS runs).'
                           if header.get('quick') else '')
        return v
    if name == 'kept':
        return {'kept': results.get('kept', '')}
    if name == 'baselines':
        secs = results.get('sections', {})
        if not any(k in secs for k in ('accuracy', 'external-accuracy', 'real-recordings')):
            return None
        return {'points': bench_prose.points(secs.get('accuracy'), secs.get('external-accuracy'),
                                             secs.get('real-recordings'))}
    if s is None:
        return None
    v = {'measured': measured_note(s, header)}
    if name == 'accuracy':
        v.update(seeds=s['seeds'], sea_duration=s['sea_duration'], tables=scenario_tables(s))
    elif name == 'external-accuracy':
        v['tables'] = '\n'.join(s.get('preamble', [])).strip('\n')
        if s.get('scenarios'):
            v['tables'] += '\n\n' + scenario_tables(s)
        v['tables'] += failed_note(s)
    elif name == 'real-recordings':
        v['table'] = blocks_markdown(s.get('blocks', [])).strip('\n') + failed_note(s)
    elif name == 'real-world':
        tests = s['tests']
        def count(test, prefix):
            n = len(real_world_report.seeds(tests.get(test, {}), prefix))
            return '%d seed%s' % (n, '' if n == 1 else 's')
        v.update(rest_seeds=count('SensorAtRestInventsNoMotion', 'max_wave_'),
                 bench_seeds=count('SlowPeriodicBiasIsBiasNotMotion', 'wave_error_'),
                 sea_seeds=count('MooredBroadSeaHeave', 'heave_error_percent_hs_clean_'),
                 horizontal_seeds=count('MooredBroadSeaSurgeAndSway', 'surge_error_'),
                 failures=('\n(test_core reported a failure: %d lines, figures below as measured)\n'
                           % s['failed_lines'] if s.get('failed_lines') else ''),
                 table=real_world_report.markdown(tests))
    elif name == 'core-speed':
        v.update(repetitions=s['repetitions'], table=core_table(s['rows']))
    elif name == 'core-latency':
        v.update(seed=s['seed'], duration=s['duration'], speed='%g' % s['speed'],
                 fast_duration=s.get('fast_duration', '-'),
                 table=bench_report.core_latency_markdown(s['runs']).strip('\n'))
    elif name == 'simulator-speed':
        v.update(hours='%g' % (s['duration'] / 3600), samples='%g' % (s['duration'] * 100 / 1e6),
                 duration=s['duration'], wall_s='%.2f' % s['wall_s'], max_rss_kb=s['max_rss_kb'])
    elif name == 'nodelet':
        v.update(seed=s['seed'], paced_100=s['paced_s'][0], paced_1k=s['paced_s'][1], paced_other=s['paced_s'][2],
                 max_data_s=s['max_data_s'], tables=bench_report.nodelet_markdown(s['runs']).strip('\n'))
        if plots_dir:
            bench_report.nodelet_plot(s['runs'], os.path.join(plots_dir, 'nodelet_latency.png'))
    elif name == 'bag':
        core = results.get('sections', {}).get('core-speed', {}).get('rows', [])
        v.update(seed=s['seed'], bags=bench_report.bag_list(s['bags']),
                 tables=bench_report.bag_markdown(s['bags'], core).strip('\n'))
        ext = s.get('external')
        if ext and ext.get('blocks'):
            v['external'] = (
                "robot_localization's `ekf_localization_node` ([config/bench/ekf_imu_only.yaml](../config/bench/ekf_imu_only.yaml))\n"
                "fed the same bag's IMU messages back to back by `scripts/bench_external.py`, a Python player slower\n"
                "than the node (the wall rate is the player's); the node's own CPU time gives its fastest rate\n"
                "on one core, to set against `compensate_bag`'s messages per second above (which also read the\n"
                "bag and write one):\n\n" + blocks_markdown(ext['blocks']).strip('\n'))
        else:
            v['external'] = "robot_localization's node: not measured (no built copy given, see the accuracy section)."
    elif name == 'memory':
        bag_rss = results.get('sections', {}).get('bag', {}).get('rss', [])
        v.update(seed=s['seed'], hours='%g' % (s['memory_s'] / 3600), messages=s['memory_s'] * 100,
                 tables=bench_report.memory_markdown(s['rows'], bag_rss).strip('\n'))
        if plots_dir:
            bench_report.memory_plot(s['rows'], bag_rss, os.path.join(plots_dir, 'memory.png'))
    return v


def render(results, template, plots_dir=None):
    """The markdown of RESULTS (the JSON's dict) through TEMPLATE (its text); the plots are written
    to PLOTS_DIR (none without)."""
    if plots_dir:
        os.makedirs(plots_dir, exist_ok=True)
    chunks = []
    for name, text in split_template(template):
        v = values(name, results, plots_dir)
        if v is None:
            heading = next((line for line in text.split('\n') if line.startswith('#')), None)
            if heading:
                chunks.append('%s\n\nNot measured yet: `scripts/bench.py run --only %s`.' % (heading, name)
                              if name in SECTIONS else heading + '\n\nNothing measured to read from yet.')
            continue
        chunk = string.Template(text).substitute({k: str(x) for k, x in v.items()}).strip('\n')
        if chunk:
            chunks.append(chunk)
    return '\n\n'.join(chunks) + '\n'


__all__ = ['SECTIONS', 'kept_section', 'render', 'table_lines']
