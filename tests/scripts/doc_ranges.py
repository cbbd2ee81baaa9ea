#!/usr/bin/env python3
"""The manual states no option range the program does not have: every "`--OPTION ...` ... A to B"
in README.md and docs/ (the generated reference aside) must be one of the ranges the reference,
written from the parser's declarations, gives that option. Prints each page:line that differs.
Usage: doc_ranges.py ROOT"""
import pathlib
import re
import sys

sys.dont_write_bytecode = True


def number(text):
    text = text.replace(',', '').rstrip('.')
    m = re.fullmatch(r'10\^(\d+)', text)
    return float(10 ** int(m.group(1))) if m else float(text)


RANGE = r'(10\^\d+|\d[\d,.]*) to (10\^\d+|\d[\d,.]*)'


def main(root):
    root = pathlib.Path(root)
    declared = {}
    for line in (root / 'docs/reference.md').read_text().splitlines():
        m = re.match(r'\| `(--[a-z0-9-]+)[^`]*` \| (.*) \|$', line)
        if not m:
            continue
        for a, b in re.findall(RANGE, m.group(2)):
            declared.setdefault(m.group(1), set()).add((number(a), number(b)))
    if not declared:
        sys.exit('docs/reference.md: no option ranges found')
    pages = [root / 'README.md'] + sorted(p for p in (root / 'docs').glob('*.md')
                                          if p.name != 'reference.md')
    bad = 0
    checked = 0
    for page in pages:
        for n, line in enumerate(page.read_text().splitlines(), 1):
            # An option, then within the same clause (no other option, no sentence end) a range.
            for m in re.finditer(r'`(--[a-z0-9-]+)[^`]*`([^`.;]{0,60}?)\b' + RANGE, line):
                opt, a, b = m.group(1), number(m.group(3)), number(m.group(4))
                if opt not in declared:
                    continue
                checked += 1
                if (a, b) not in declared[opt]:
                    bad += 1
                    print(f'{page.relative_to(root)}:{n}: {opt} {m.group(3)} to {m.group(4)}, '
                          f'but the parser takes {sorted(declared[opt])}')
    print(f'{checked} stated ranges checked against {len(declared)} options')
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
