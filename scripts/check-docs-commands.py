#!/usr/bin/env python3
"""Runs the commands of every code block the manual marks as runnable, and fails when one fails.

A block is runnable when the line before its opening fence is `<!-- runnable -->`. Its commands
are its `$ `-prefixed lines when it has any (the rest is output shown), else all its lines; a
trailing backslash continues a command. Each block runs as one bash script with -e, so a
command that exits non-zero fails the block, in a fresh folder laid out as a checkout: `build/`
holds robotperf, `benchmarks/` and `scripts/` are the source tree's, and `../shared` is the
reference data. Usage: check-docs-commands.py DOCS_DIR ROBOTPERF SOURCE_DIR SHARED_DIR"""
import os
import re
import subprocess
import sys
import tempfile

docs, robotperf, source, shared = (os.path.abspath(a) for a in sys.argv[1:5])
MARK = '<!-- runnable -->'


def blocks(path):
    """(line, commands) of each runnable block of a Markdown file."""
    lines = open(path, encoding='utf-8').read().splitlines()
    out = []
    for i, line in enumerate(lines):
        if line.strip() != MARK:
            continue
        if i + 1 >= len(lines) or not lines[i + 1].startswith('```'):
            out.append((i + 1, None))  # a mark on no block: reported as such
            continue
        body = []
        for text in lines[i + 2:]:
            if text.startswith('```'):
                break
            body.append(text)
        prompted = [t[2:] for t in body if t.startswith('$ ')]
        commands = prompted if prompted else [t for t in body if t.strip()]
        out.append((i + 2, '\n'.join(commands).replace('\\\n', ' ')))
    return out


found = failed = 0
with tempfile.TemporaryDirectory(prefix='robotperf-docs-') as root:
    for dirpath, _, files in sorted(os.walk(docs)):
        for name in sorted(files):
            if not name.endswith('.md'):
                continue
            path = os.path.join(dirpath, name)
            shown = os.path.relpath(path, docs)
            for line, script in blocks(path):
                found += 1
                if script is None:
                    print(f'{shown}:{line}: {MARK} is not followed by a code block')
                    failed += 1
                    continue
                # A fresh checkout-like folder per block: nothing one block leaves behind (results,
                # bags) changes what the next one prints.
                work = tempfile.mkdtemp(dir=root)
                checkout = os.path.join(work, 'checkout')
                os.makedirs(os.path.join(checkout, 'build'))
                os.symlink(robotperf, os.path.join(checkout, 'build', 'robotperf'))
                for part in ('benchmarks', 'scripts', 'examples'):
                    os.symlink(os.path.join(source, part), os.path.join(checkout, part))
                os.symlink(shared, os.path.join(work, 'shared'))
                done = subprocess.run(['bash', '-euo', 'pipefail', '-c', script], cwd=checkout,
                                      capture_output=True, text=True, timeout=900)
                ok = done.returncode == 0
                failed += not ok
                print(f'{shown}:{line}: {"ok" if ok else "FAILED (exit %d)" % done.returncode}')
                if not ok:
                    print('\n'.join((done.stdout + done.stderr).splitlines()[-20:]))
if found == 0:
    sys.exit(f'check-docs-commands: no {MARK} block under {docs}')
print(f'check-docs-commands: {found - failed} of {found} runnable blocks ran')
sys.exit(1 if failed else 0)
