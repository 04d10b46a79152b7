#!/usr/bin/env python3
"""Instructions per source line with inlined code counted where it was inlined.

callgrind_annotate puts an inlined helper's instructions on the helper's own lines (a GLM
operator, std::clamp, a geometry.h function), so in a step built with -O3 most of a loop's cost
shows up in headers. This reads a callgrind output written with --dump-instr=yes, asks addr2line
(-i) for each instruction's chain of inlined frames, and charges the instruction to the innermost
frame that lies in SOURCE between lines FIRST and LAST: a GLM operator inlined into a lambda of
that file counts on the lambda's line. Instructions of functions that were not inlined count on
their own lines, not on their callers'.

    valgrind --tool=callgrind --dump-instr=yes \\
        --toggle-collect='sulcus::step(sulcus::Model const&, sulcus::State&, sulcus::Pose const&)' \\
        --callgrind-out-file=cg.out build/bin/sulcus-cli bench quadrant_two_regions --check-every 0
    tools/bench/callgrind_lines.py cg.out build/bin/sulcus-cli engine/src/renderer.cpp 1 4000 [TOP]

Prints the total and the TOP (default 40) costliest lines.

OUT may also be several outputs joined by commas, such as the per-tick dumps of a window of ticks
(callgrind with --dump-before on the step as in tick_instructions.sh, plus --dump-instr=yes: dump
k >= 3 holds tick k - 3); their costs are added and printed per output, in thousands:

    tools/bench/callgrind_lines.py $(seq -s, -f 'cg/part.%g' 2283 2312) build/bin/sulcus-cli \
        engine/src/renderer.cpp 1 4000
"""
import collections
import os
import re
import subprocess
import sys


def inline_chains(binary, addresses):
    """Each address's chain of (function, file:line) frames from addr2line -i, innermost first."""
    text = subprocess.run(['addr2line', '-a', '-i', '-f', '-C', '-e', binary],
                          input='\n'.join(hex(a) for a in addresses), capture_output=True, text=True,
                          check=True).stdout.split('\n')
    chains = {}
    current = None
    i = 0
    while i < len(text):
        entry = text[i]
        if entry.startswith('0x'):
            current = int(entry, 16)
            chains[current] = []
            i += 1
        elif entry and i + 1 < len(text) and current is not None:
            chains[current].append((entry, text[i + 1]))
            i += 2
        else:
            i += 1
    return chains


def cost_per_line(binary, cost, source, first, last, chains=None):
    """cost (per address of `binary`) charged to the innermost frame in `source` between lines
    first and last, per line; `chains` from inline_chains if already at hand."""
    if chains is None:
        chains = inline_chains(binary, sorted(cost))
    source_abs = os.path.abspath(source)
    per_line = collections.Counter()
    for address, frames in chains.items():
        for _function, location in frames:
            path, _, number = location.rpartition(':')
            number = number.split()[0] if number else ''
            if number.isdigit() and os.path.abspath(path) == source_abs and first <= int(number) <= last:
                per_line[int(number)] += cost[address]
                break
    return per_line


def read_cost(out, target, cost):
    """Adds the instructions of `target` in callgrind output `out` to `cost`, by address."""
    names = {}

    def name(kind, text):
        m = re.match(r'\((\d+)\)(?: (.*))?', text)
        if not m:
            return text
        if m.group(2):
            names[(kind, m.group(1))] = m.group(2)
        return names.get((kind, m.group(1)), '')

    obj = None
    addr = 0
    after_calls = False
    found = False
    with open(out) as f:
        for line in f:
            if line.startswith('ob='):
                obj = name('ob', line[3:].strip())
                continue
            if line.startswith('cob='):
                name('ob', line[4:].strip())
                continue
            if line.startswith(('cfn=', 'cfi=', 'cfl=', 'fn=', 'fl=', 'fi=', 'fe=')):
                continue
            if line.startswith('calls='):
                after_calls = True  # the next cost line is the call's inclusive cost
                continue
            if not line or line[0] not in '0123456789+-*':
                continue
            parts = line.split()
            a = parts[0]
            if a.startswith('0x'):
                addr = int(a, 16)
            elif a.startswith('+'):
                addr += int(a[1:])
            elif a.startswith('-'):
                addr -= int(a[1:])
            if after_calls:
                after_calls = False
                continue
            if obj and os.path.basename(obj) == target and len(parts) >= 3:
                cost[addr] += int(parts[2])
                found = True
    return found


def main():
    if len(sys.argv) < 6:
        sys.exit(__doc__)
    outs, binary, source, first, last = sys.argv[1].split(','), sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
    top = int(sys.argv[6]) if len(sys.argv) > 6 else 40
    target = os.path.basename(binary)
    cost = collections.Counter()
    found = False
    for out in outs:
        found |= read_cost(out, target, cost)
    if not found:
        sys.exit(f'callgrind_lines.py: {sys.argv[1]}: no instructions of {target} (written with --dump-instr=yes?)')

    per_line = cost_per_line(binary, cost, source, first, last)

    lines = open(source).read().split('\n')
    if len(outs) == 1:
        scale, unit, what = 1e6, 'M', ''
    else:
        scale, unit, what = 1e3 * len(outs), 'K', f' per output ({len(outs)} outputs)'
    print(f'total {sum(per_line.values()) / scale:.1f} {unit} instructions{what} on {source} lines {first}-{last}')
    for number, n in sorted(per_line.items(), key=lambda x: -x[1])[:top]:
        print(f'{n / scale:9.1f} {unit} {number:6} {lines[number - 1].strip()[:100]}')


if __name__ == '__main__':
    main()
