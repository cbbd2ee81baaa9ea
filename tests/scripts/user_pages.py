#!/usr/bin/env python3
"""The user pages (README.md, docs/ but development.md and the generated reference) speak of the
program, not of its tests or its past: no test name (a suite of tests/ followed by a dot and a
name, as `LiveHdr.CalibrateRecoversTheResponse`), no "-dirty" commit stamp, no ticket number and
no phrase that dates the text (the patterns in `history` below). Prints each page:line that does.
Usage: user_pages.py ROOT"""
import pathlib
import re
import sys

sys.dont_write_bytecode = True


def main(root):
    root = pathlib.Path(root)
    suites = set()
    for p in root.glob('tests/**/*.cpp'):
        suites |= set(re.findall(r'\bTEST(?:_F|_P)?\(\s*([A-Za-z0-9_]+)\s*,',
                                 p.read_text(errors='ignore')))
    for p in root.glob('tests/**/CMakeLists.txt'):
        suites |= set(re.findall(r'add_test\(NAME ([A-Za-z0-9_]+)\.', p.read_text()))
    if len(suites) < 10:
        sys.exit(f'tests/: only {len(suites)} suites found')
    test = re.compile(r'`(?:%s)\.[A-Za-z0-9_*]+' % '|'.join(sorted(suites, key=len, reverse=True)))
    history = re.compile(r'-dirty\b|\bissue\s+\d+|\bthis\s+session\b|\bbefore\s+this\s+change\b',
                         re.I)
    pages = [root / 'README.md'] + sorted(p for p in (root / 'docs').glob('*.md')
                                          if p.name not in ('development.md', 'reference.md'))
    bad = 0
    for page in pages:
        for n, line in enumerate(page.read_text().splitlines(), 1):
            for what, rx in (('a test name', test), ('history', history)):
                if m := rx.search(line):
                    bad += 1
                    print(f'{page.relative_to(root)}:{n}: {what}: {m.group(0)}')
    print(f'{len(pages)} user pages read for {len(suites)} test suites\' names and history')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
