#!/usr/bin/env python3
"""Whether two builds of sulcus-cli give every tick of every bench scene the same answers.

A change meant to make the step faster should not change what it finds. This runs
`bench --runs 1 --check-every 0 --ticks DIR` with each build over the whole bench set and
compares the tick files column by column, the times left out: status, pose, force, atoms,
candidates, QP solves and iterations, passes and the rest, as printed (to the last bit). The
work columns are compared apart (triangles tested, tissue sets gathered, quiet triangles, the
memos' misses): a cache may do other work and find the same.

    tools/bench/same_answers.py /tmp/cli_base build/bin/sulcus-cli [--cases build/cases] [--out DIR]

Prints, per scene, the ticks and how many differ (with the first differing tick and its columns),
and exits 1 when any tick's answers differ.
"""
import argparse
import csv
import glob
import os
import subprocess
import sys
import tempfile

TIMES = {'step_us', 'detect_us', 'gather_us', 'solve_us', 'select_us', 'force_us', 'least_step_us'}
WORK = {'triangles_tested', 'compliant_gathers', 'quiet_triangles', 'edge_queries', 'edge_memos_ahead', 'face_searches',
        'deferred'}


def other_answers(x, y):
    """The columns (times and work left out) where tick rows x and y differ."""
    return [k for k in x if k not in TIMES and k not in WORK and x[k] != y.get(k)]


def other_work(x, y):
    """The work columns where tick rows x and y differ."""
    return [k for k in WORK if x.get(k) != y.get(k)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('a')
    parser.add_argument('b')
    parser.add_argument('--cases', default='build/cases')
    parser.add_argument('--out', default=None)
    args = parser.parse_args()
    out = args.out or tempfile.mkdtemp(prefix='same_answers_')
    dirs = []
    for k, binary in enumerate((args.a, args.b)):
        directory = os.path.join(out, 'ab'[k])
        cmd = [binary, 'bench', '--runs', '1', '--check-every', '0', '--cases', args.cases, '--ticks', directory]
        done = subprocess.run(cmd, capture_output=True, text=True)
        if done.returncode != 0:
            sys.exit(f'same_answers.py: {" ".join(cmd)}: exit {done.returncode}: {done.stderr.strip()[:200]}')
        dirs.append(directory)
    files = sorted(glob.glob(os.path.join(dirs[0], '*_ticks.csv')))
    if not files:
        sys.exit(f'same_answers.py: no tick files in {dirs[0]}')
    total = 0
    for fa in files:
        fb = os.path.join(dirs[1], os.path.basename(fa))
        if not os.path.exists(fb):
            print(f'{os.path.basename(fa)}: missing from the second build\'s run')
            total += 1
            continue
        with open(fa, newline='') as f:
            ra = list(csv.DictReader(f))
        with open(fb, newline='') as f:
            rb = list(csv.DictReader(f))
        differ, other_work_ticks, first = 0, 0, None
        if len(ra) != len(rb):
            differ = max(len(ra), len(rb))
            first = ('tick count', len(ra), len(rb))
        for i, (x, y) in enumerate(zip(ra, rb)):
            columns = other_answers(x, y)
            if columns:
                differ += 1
                if first is None:
                    first = (i, columns[:6])
            other_work_ticks += bool(other_work(x, y))
        name = os.path.basename(fa)[:-len('_ticks.csv')]
        print(f'{name}: {len(ra)} ticks, {differ} with other answers' + (f' (first: {first})' if first else '') +
              f', {other_work_ticks} with other work (triangles tested, sets gathered, quiet triangles, memo misses)')
        total += differ
    print('the same answers at every tick' if total == 0 else f'{total} ticks with other answers')
    sys.exit(0 if total == 0 else 1)


if __name__ == '__main__':
    main()
