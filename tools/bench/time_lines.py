#!/usr/bin/env python3
"""Time per source line, from the processor's own clock: where the step waits, not what it counts.

Instruction counts (callgrind, tick_instructions.sh) say how much work a tick does; they do not say
where it waits. A square root whose answer a branch needs at once, a record written on the stack a
field at a time and read back whole (the store cannot be forwarded to the load, and the load waits
for the store to reach the cache), a table larger than the nearer caches: each costs far more time
than its instructions, and a change that removes instructions the processor ran alongside others
gains nothing. This reads a `perf record -e cpu-clock` profile (timer sampling, which a virtual
machine without hardware counters still has), maps each sample's address to its chain of inlined
frames (addr2line -i) and charges it to the innermost frame in SOURCE between lines FIRST and LAST,
with callgrind_lines.py's own charging, as it does for instructions.

    perf record -e cpu-clock -F 20000 -o perf.data \\
        build/bin/sulcus-cli bench quadrant_two_regions --runs 6 --check-every 0
    tools/bench/time_lines.py perf.data build/bin/sulcus-cli engine/src/renderer.cpp 1 5000 [TOP]

Prints the samples in all and on those lines, the TOP (default 40) lines with the most, and the
sampled addresses that look like failed store-to-load forwards: a load from the stack that an
earlier store of a narrower or offset piece of the same bytes wrote, up to 14 instructions before
(the sample usually lands on the load or just after it). Needs perf (Debian: linux-perf),
addr2line and objdump (binutils).
"""
import collections
import os
import re
import subprocess
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from callgrind_lines import cost_per_line, inline_chains  # noqa: E402


def samples_by_address(data, binary):
    """Samples per address of `binary` (its own addresses, as nm and addr2line give them)."""
    out = subprocess.run(['perf', 'script', '-i', data, '-G', '--no-demangle', '-F', 'ip,sym,symoff,dso'],
                         capture_output=True, text=True, check=True).stdout
    by_symbol = collections.Counter()
    total = 0
    for line in out.split('\n'):
        m = re.match(r'\s*[0-9a-f]+ (\S+)\+0x([0-9a-f]+) \((.*)\)', line)
        if not m:
            continue
        total += 1
        if os.path.basename(m.group(3)) == os.path.basename(binary):
            by_symbol[(m.group(1), int(m.group(2), 16))] += 1
    symbols = {}
    for line in subprocess.run(['nm', binary], capture_output=True, text=True, check=True).stdout.split('\n'):
        parts = line.split()
        if len(parts) == 3:
            symbols[parts[2]] = int(parts[0], 16)
    counts = collections.Counter()
    for (symbol, offset), n in by_symbol.items():
        if symbol in symbols:
            counts[symbols[symbol] + offset] += n
    return total, counts


STACK = re.compile(r'(-?0x[0-9a-f]+|)\((%r[bs]p)\)')


def stack_slot(operand):
    m = STACK.fullmatch(operand.strip())
    if not m:
        return None
    return m.group(2), int(m.group(1), 16) if m.group(1) else 0


def width(op, register):
    """Bytes a move of `register` by instruction `op` takes (roughly, for the usual moves)."""
    if register.startswith('%ymm'):
        return 32
    if register.startswith('%xmm'):
        scalar = re.search(r'(sd|ss|q)$', op) and not op.startswith(('vmovdq', 'vmovap', 'vmovup'))
        return 8 if scalar else 16
    if re.fullmatch(r'%r[a-z0-9]+', register) and not register.endswith(('d', 'w', 'b')):
        return 8
    if register.startswith('%e') or register.endswith('d'):
        return 4
    if register.endswith('w') or op.endswith('w'):
        return 2
    return 1


def forward_failures(binary, counts, least):
    """(samples, address, store, load) for sampled addresses with `least` samples or more whose load
    from the stack, within the last four instructions, reads bytes an earlier store wrote only in
    part."""
    listing = subprocess.run(['objdump', '-d', '--no-show-raw-insn', binary], capture_output=True, text=True,
                             check=True).stdout
    text, order = {}, []
    for line in listing.split('\n'):
        m = re.match(r'\s*([0-9a-f]+):\s*(.*)', line)
        if m:
            address = int(m.group(1), 16)
            text[address] = m.group(2)
            order.append(address)
    place = {a: i for i, a in enumerate(order)}
    def move(k):
        """(instruction, source operand, destination operand) of a two-operand instruction."""
        m = re.match(r'(\S+)\s+(.*)', text[order[k]])
        if not m:
            return None
        args = m.group(2).split(',')
        return (m.group(1), args[0].strip(), args[1].strip()) if len(args) == 2 else None

    found = []
    for address, n in counts.items():
        if n < least or address not in place:
            continue
        p = place[address]
        hit = None
        for j in range(max(0, p - 3), p + 1):
            load = move(j)
            source = stack_slot(load[1]) if load and load[2].startswith('%') else None
            if not source:
                continue
            load_width = width(load[0], load[2])
            for k in range(j - 1, max(0, j - 14) - 1, -1):
                store = move(k)
                if not store or not store[1].startswith('%'):
                    continue
                target = stack_slot(store[2])
                if not target or target[0] != source[0]:
                    continue
                store_width = width(store[0], store[1])
                s, l = target[1], source[1]
                overlaps = s < l + load_width and l < s + store_width
                covers = s <= l and s + store_width >= l + load_width
                if overlaps and not covers:
                    hit = (n, address, text[order[k]], text[order[j]])
                    break
            if hit:
                break
        if hit:
            found.append(hit)
    return sorted(found, reverse=True)


def main():
    if len(sys.argv) < 6:
        sys.exit(__doc__)
    data, binary, source, first, last = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4]), int(sys.argv[5])
    top = int(sys.argv[6]) if len(sys.argv) > 6 else 40
    total, counts = samples_by_address(data, binary)
    if not counts:
        sys.exit(f'time_lines.py: {data}: no samples in {binary}')
    chains = inline_chains(binary, sorted(counts))
    per_line = cost_per_line(binary, counts, source, first, last, chains)
    lines = open(source).read().split('\n')
    print(f'{total} samples, {sum(per_line.values())} on {source} lines {first}-{last}')
    for number, n in sorted(per_line.items(), key=lambda x: -x[1])[:top]:
        print(f'{n:8d} {100.0 * n / total:5.2f}% {number:6} {lines[number - 1].strip()[:90]}')
    failures = forward_failures(binary, counts, max(20, total // 5000))
    if failures:
        print('loads that may wait on a store they only partly overlap (samples, address, store, load):')
        for n, address, store, load in failures[:top]:
            place = ' < '.join(loc.split('/')[-1] for _f, loc in chains[address])[:80]
            print(f'{n:8d} {100.0 * n / total:5.2f}% {address:#x} [{store[:40]}] [{load[:40]}] {place}')


if __name__ == '__main__':
    main()
