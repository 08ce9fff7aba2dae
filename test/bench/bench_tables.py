"""Markdown tables as data, for the benchmark results (docs/bench/results.json).

evaluate_compensator and scripts/bench_external.py print markdown; scripts/bench.py keeps their
output as blocks (text lines and tables) so that the renderer can print it back and the prose can
read single figures from it.
"""
import re


def parse_blocks(text):
    """Splits markdown into [{'text': [lines]} | {'table': {'header': [...], 'rows': [[...]]}}]."""
    blocks = []
    for line in text.split('\n'):
        if line.startswith('|'):
            cells = split_row(line)
            if blocks and 'table' in blocks[-1]:
                if not all(re.fullmatch(r':?-+:?', c) for c in cells):
                    blocks[-1]['table']['rows'].append(cells)
            else:
                blocks.append({'table': {'header': cells, 'rows': []}})
        elif blocks and 'text' in blocks[-1]:
            blocks[-1]['text'].append(line)
        else:
            blocks.append({'text': [line]})
    return blocks


def split_row(line):
    """The cells of a markdown table row; escaped bars (\\|) stay in their cell."""
    cells = re.split(r'(?<!\\)\|', line.strip())
    return [c.strip() for c in cells[1:-1]]


def table_lines(header, rows):
    lines = ['| ' + ' | '.join(header) + ' |', '|' + '---|' * len(header)]
    lines += ['| ' + ' | '.join(str(c) for c in row) + ' |' for row in rows]
    return lines


def blocks_markdown(blocks):
    lines = []
    for b in blocks:
        if 'text' in b:
            lines += b['text']
        else:
            lines += table_lines(b['table']['header'], b['table']['rows'])
    return '\n'.join(lines)


def number(cell):
    """The figure a cell starts with, or None ('-', empty, text)."""
    m = re.match(r'\s*\**([-+]?\d+(?:\.\d*)?(?:e[-+]?\d+)?)', str(cell))
    return float(m.group(1)) if m else None


# evaluate_compensator's columns, by short name.
COLUMNS = {
    'slow60': 'slow-motion error at 60 s [m]',
    'slow_end': 'at end [m]',
    'slow_rms': 'slow-motion RMS error [m]',
    'total_end': 'total position error at end [m]',
    'total_rms': 'total position RMS error [m]',
    'wave': 'wave RMS error [% of true wave RMS]',
    'hs': 'wave RMS error [% of Hs]',
}


class Accuracy:
    """Figures of evaluate_compensator's tables: {scenario: blocks}."""

    def __init__(self, scenarios):
        self.tables = {}
        self.travelled = {}
        for name, blocks in (scenarios or {}).items():
            for b in blocks:
                if 'table' in b and b['table']['header'][:2] == ['method', 'axis']:
                    self.tables[name] = b['table']
                elif 'text' in b:
                    m = re.search(r'goes (\d+(?:\.\d+)?) m from its start', ' '.join(b['text']))
                    if m:
                        self.travelled[name] = float(m.group(1))

    def scenarios(self):
        return list(self.tables)

    def methods(self, scenario):
        return list(dict.fromkeys(r[0] for r in self.tables.get(scenario, {'rows': []})['rows']))

    def get(self, scenario, method, axis, column):
        table = self.tables.get(scenario)
        if not table or COLUMNS[column] not in table['header']:
            return None
        c = table['header'].index(COLUMNS[column])
        for row in table['rows']:
            if row[0] == method and row[1] == axis:
                return number(row[c])
        return None

    def cell(self, scenario, method, axis, column):
        table = self.tables.get(scenario)
        if not table or COLUMNS[column] not in table['header']:
            return None
        c = table['header'].index(COLUMNS[column])
        for row in table['rows']:
            if row[0] == method and row[1] == axis:
                return row[c]
        return None
