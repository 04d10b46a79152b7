#!/usr/bin/env python3
"""Step times of two or more builds of sulcus-cli on one bench scene, taken in turns.

This machine's speed drifts over minutes (interruptions from the host, slow spells), so builds
timed one after the other are compared across the drift. This runs each build's
`bench SCENE --runs RUNS --check-every 0 --ticks DIR` in turn, ROUNDS times over, and takes per
tick the least over all its runs (each run's `least_step_us` is already the least of its RUNS),
which the interruptions rarely reach in every run. Then, per build: the median, p99, p99.9 and
max of those per-tick least times, their mean over the ticks FROM to TO (the session's lean phase
by default), and each stage's mean there (a stage's time is the first run's of each round, the
least over rounds). It also says whether every build gave every tick the same answers (every
column but the times and the work (same_answers.WORK), which a cache may change without changing what is
found).

    tools/bench/alternate.py quadrant_two_regions base=/tmp/cli_base new=build/bin/sulcus-cli \\
        [--rounds 3] [--runs 6] [--lean 1350:4300] [--cases build/cases] [--out DIR]

A build is NAME=PATH (a copy of the binary: one being rebuilt meanwhile is timed as it is when its
turn comes). Differences of about a microsecond in the means are within what this resolves: two
builds of the same code with the code laid out differently land that far apart.
"""
import argparse
import csv
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from same_answers import other_answers  # noqa: E402

STAGES = ['detect_us', 'gather_us', 'solve_us', 'select_us', 'force_us']


def percentiles(values):
    s = sorted(values)
    n = len(s)
    return [s[int(q * n)] if n else float('nan') for q in (0.5, 0.99, 0.999)] + [s[-1] if n else float('nan')]


def read_ticks(directory, scene):
    path = os.path.join(directory, scene.replace('/', '_') + '_ticks.csv')
    with open(path, newline='') as f:
        return list(csv.DictReader(f))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('scene')
    parser.add_argument('builds', nargs='+', help='NAME=PATH')
    parser.add_argument('--rounds', type=int, default=3)
    parser.add_argument('--runs', type=int, default=6)
    parser.add_argument('--lean', default='1350:4300', help='FROM:TO, ticks for the means')
    parser.add_argument('--cases', default='build/cases')
    parser.add_argument('--out', default=None, help='where the tick files go (a temporary directory)')
    args = parser.parse_args()

    builds = []
    for b in args.builds:
        name, sep, path = b.partition('=')
        if not sep or not name or not os.access(path, os.X_OK):
            sys.exit(f'alternate.py: {b}: expected NAME=PATH of an executable')
        builds.append((name, path))
    try:
        lo, hi = (int(v) for v in args.lean.split(':'))
    except ValueError:
        sys.exit(f'alternate.py: --lean {args.lean}: expected FROM:TO')
    out = args.out or tempfile.mkdtemp(prefix='alternate_')

    runs = {name: [] for name, _ in builds}
    for r in range(args.rounds):
        for name, path in builds:
            directory = os.path.join(out, f'{name}_{r}')
            cmd = [path, 'bench', args.scene, '--runs', str(args.runs), '--check-every', '0', '--cases', args.cases,
                   '--ticks', directory]
            done = subprocess.run(cmd, capture_output=True, text=True)
            if done.returncode != 0:
                sys.exit(f'alternate.py: {" ".join(cmd)}: exit {done.returncode}: {done.stderr.strip()[:200]}')
            runs[name].append(read_ticks(directory, args.scene))

    first = None
    for name, _ in builds:
        rounds = runs[name]
        ticks = len(rounds[0])
        if any(len(t) != ticks for t in rounds):
            sys.exit(f'alternate.py: {name}: the rounds have different numbers of ticks')
        least = [min(float(t[k]['least_step_us']) for t in rounds) for k in range(ticks)]
        lean = least[lo:hi]
        stage = {s: min(statistics.mean(float(x[s]) for x in t[lo:hi]) for t in rounds) for s in STAGES}
        p = percentiles(least)
        print(f'{name}: least of {args.rounds * args.runs} runs, median / p99 / p99.9 / max '
              f'{p[0]:.1f} / {p[1]:.1f} / {p[2]:.1f} / {p[3]:.1f} us; ticks {lo}-{hi} mean {statistics.mean(lean):.2f} us '
              f'(' + ', '.join(f'{s[:-3]} {v:.2f}' for s, v in stage.items()) + ')')
        # The answers: every round of every build against the first build's first round.
        if first is None:
            first = rounds[0]
        differing = sum(1 for t in rounds for a, b in zip(first, t) if other_answers(a, b))
        print(f'  ticks whose answers differ from {builds[0][0]}\'s first round: {differing}')
    print(f'tick files in {out}')


if __name__ == '__main__':
    main()
