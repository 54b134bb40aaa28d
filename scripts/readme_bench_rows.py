#!/usr/bin/env python3
"""Copy the rows of a `cargo xtask bench` markdown file into README.md's tables.

    python3 scripts/readme_bench_rows.py README.md bench.md

Every row of a table in the bench's file replaces the README row of the table with the same header
and the same key: the voice, scene and tier for the main table, the first cell for the others (a
"(key N)" in it matches any key, so a target's slowest key may move). Rows the bench did not measure
this run (the playing-range grid's with `--no-grid`, the timed scenes' with `--grid-only`) stay
as they are, and so does the prose
around the tables: say in it which run the figures are from. Prints how many rows changed.
"""
import re
import sys


def tables(lines):
    """The (start, end) line ranges of the markdown tables in `lines`."""
    ranges, i = [], 0
    while i < len(lines):
        if lines[i].startswith('|'):
            j = i
            while j < len(lines) and lines[j].startswith('|'):
                j += 1
            ranges.append((i, j))
            i = j
        else:
            i += 1
    return ranges


def row_key(header, row):
    cells = [cell.strip() for cell in row.split('|')[1:-1]]
    if header.startswith('| voice'):
        return header, tuple(cells[:3])
    return header, re.sub(r'\(key \d+\)', '(key N)', cells[0])


def main(readme_path, bench_path):
    readme = open(readme_path, encoding='utf-8').read().split('\n')
    bench = open(bench_path, encoding='utf-8').read().split('\n')
    measured = {}
    for start, end in tables(bench):
        for row in bench[start + 2:end]:
            if '| not measured |' not in row:
                measured[row_key(bench[start], row)] = row
    changed = 0
    for start, end in tables(readme):
        for index in range(start + 2, end):
            key = row_key(readme[start], readme[index])
            if key in measured and readme[index] != measured[key]:
                readme[index] = measured[key]
                changed += 1
    open(readme_path, 'w', encoding='utf-8').write('\n'.join(readme))
    print(f'{changed} rows changed')


if __name__ == '__main__':
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
