#!/usr/bin/env python3
"""The manual states the counts and lists the tree and the program have: every "N fuzz targets"
(or "N libFuzzer targets") in README.md and docs/ is the number of tests/fuzz/fuzz_*.cpp, every
"N stages" is the number of stages `liveprobe bench` times, and every list that names four or
more of those stages (the generated reference included) names all of them in the program's order,
the committed baseline's numbers the manual quotes ("calibration kernel X ms, render Y ms
median, contention xZ") are the file's, as rounded, and every exit-status table (the Markdown
tables headed "exit status" or "code", the man page's EXIT STATUS) lists every status the
program returns: 0, 1 and app/src/progress.h's kExit* constants; a frame rate measured over a
run's --duration is its frames over that time, and no picture's caption states a rate of its own. Prints each page:line that differs. Usage: doc_counts.py ROOT LIVEPROBE"""
import itertools
import json
import pathlib
import re
import subprocess
import sys
import tempfile

sys.dont_write_bytecode = True

WORDS = ['zero', 'one', 'two', 'three', 'four', 'five', 'six', 'seven', 'eight', 'nine', 'ten',
         'eleven', 'twelve', 'thirteen', 'fourteen', 'fifteen', 'sixteen']


def count(text):
    return int(text) if text.isdigit() else WORDS.index(text.lower())


def bench_stages(liveprobe):
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp) / 'bench.json'
        subprocess.run([liveprobe, 'bench', '--frames', '1', '--repeat', '1', '--quiet', '--json',
                        str(out)], check=True, stdout=subprocess.DEVNULL, timeout=300)
        return list(json.loads(out.read_text())['stages'])


def paragraphs(page):
    """(first line, text) of each run of non-empty lines, joined by spaces."""
    lines = page.read_text().splitlines()
    start = 0
    for n, line in enumerate(lines + [''], 1):
        if not line.strip():
            if n - 1 > start:
                yield start + 1, ' '.join(lines[start:n - 1])
            start = n


def main(root, liveprobe):
    root = pathlib.Path(root)
    fuzz = len(list((root / 'tests/fuzz').glob('fuzz_*.cpp')))
    stages = bench_stages(liveprobe)
    number = r'\b(\d+|' + '|'.join(WORDS) + r')'
    pages = [root / 'README.md'] + sorted((root / 'docs').glob('*.md'))
    bad = checked = 0
    for page in pages:
        for n, line in enumerate(page.read_text().splitlines(), 1):
            where = f'{page.relative_to(root)}:{n}'
            for m in re.finditer(number + r' (?:libFuzzer |fuzz )targets', line, re.I):
                checked += 1
                if count(m.group(1)) != fuzz:
                    bad += 1
                    print(f'{where}: "{m.group(0)}", but tests/fuzz has {fuzz}')
            for m in re.finditer(number + r' stages\b', line, re.I):
                checked += 1
                if count(m.group(1)) != len(stages):
                    bad += 1
                    print(f'{where}: "{m.group(0)}", but bench times {len(stages)}: {stages}')
        # A measured frame rate: in a paragraph that gives a run's --duration D, every "N of
        # [its] M [frames] (F frames/s)" is N / D, and no picture's caption there states a rate of
        # its own (the picture is a moment of a measured run, not another measurement).
        for par_start, par in paragraphs(page):
            d = re.search(r'--duration (\d+(?:\.\d+)?)', par)
            if not d:
                continue
            for m in re.finditer(r'(\d+) of (?:its )?\d+(?: frames)? \((\d+(?:\.\d+)?) frames/s', par):
                checked += 1
                rate = int(m.group(1)) / float(d.group(1))
                digits = len(m.group(2).split('.')[1]) if '.' in m.group(2) else 0
                if abs(float(m.group(2)) - round(rate, digits)) > 1e-9:
                    bad += 1
                    print(f'{page.relative_to(root)}:{par_start}: "{m.group(0)}", but {m.group(1)} frames '
                          f'in {d.group(1)} s are {rate:.2f} frames/s')
        for n, line in enumerate(page.read_text().splitlines(), 1):
            if re.match(r'!\[[^\]]*\d frames/s', line):
                bad += 1
                print(f'{page.relative_to(root)}:{n}: a caption states a frame rate; the text measures it')
        # A list of stages, within a paragraph (a list may break across lines): names joined by
        # commas or "and" (a parenthesis may follow a name).
        for par_start, text in paragraphs(page):
            sep = r'(?:,? and |, )'
            for m in re.finditer(r'\b[a-z]+(?: \([^)]*\))?(?:' + sep + r'[a-z]+(?: \([^)]*\))?){3,}',
                                 text):
                named = re.findall(r'\b([a-z]+)(?: \([^)]*\))?(?=' + sep + r'|$)', m.group(0))
                if sum(name in stages for name in named) < 4:
                    continue
                checked += 1
                if named != stages:
                    bad += 1
                    print(f'{page.relative_to(root)}:{par_start}: stages {named}, but bench times {stages}')
    # The committed baseline, as the manual quotes it.
    base = json.loads((root / 'recordings/bench-baseline.json').read_text())
    quoted = {'calibration kernel': base['calibration_ms'],
              'render': base['stages']['render']['median_ms'], 'contention x': base['contention']}
    for page in pages:
        for n, line in enumerate(page.read_text().splitlines(), 1):
            m = re.search(r'calibration kernel (\d+(?:\.\d+)?) ms, render (\d+(?:\.\d+)?) ms median, '
                          r'contention x(\d+(?:\.\d+)?)', line)
            if not m:
                continue
            for (name, value), text in zip(quoted.items(), m.groups()):
                checked += 1
                digits = len(text.split('.')[1]) if '.' in text else 0
                if abs(float(text) - round(value, digits)) > 1e-9:
                    bad += 1
                    print(f'{page.relative_to(root)}:{n}: {name} {text}, but '
                          f'recordings/bench-baseline.json has {value:.{digits + 2}f}')
    # The exit statuses: the program's, against every table of them.
    codes = {0, 1} | {int(c) for c in re.findall(r'constexpr int kExit\w+ = (\d+);',
                                                   (root / 'app/src/progress.h').read_text())}
    tables = []
    for page in pages:
        lines = page.read_text().splitlines()
        for n, line in enumerate(lines):
            if re.match(r'\| (exit status|code) \|', line):
                rows = itertools.takewhile(lambda l: l.startswith('|'), lines[n + 2:])
                tables.append((f'{page.relative_to(root)}:{n + 1}',
                               {int(m.group(1)) for r in rows if (m := re.match(r'\| (\d+) \|', r))}))
    man = (root / 'docs/liveprobe.1').read_text()
    section = man.split('.SH EXIT STATUS\n', 1)[1].split('\n.SH ', 1)[0]
    tables.append(('docs/liveprobe.1 EXIT STATUS', {int(c) for c in re.findall(r'^\.B (\d+)$', section, re.M)}))
    for where, listed in tables:
        checked += 1
        if listed != codes:
            bad += 1
            print(f'{where}: exit statuses {sorted(listed)}, but the program returns {sorted(codes)}')
    if len(tables) < 3:
        bad += 1
        print(f'{len(tables)} exit-status tables found; commands.md, reference.md and the man page have one each')
    print(f'{checked} stated counts, stage lists and exit tables checked ({fuzz} fuzz targets, '
          f'{len(stages)} stages, exit statuses {sorted(codes)})')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1], sys.argv[2]))
