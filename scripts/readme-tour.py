#!/usr/bin/env python3
"""Runs the README's short tour as a newcomer would, command by command, in a fresh folder, and
checks that each command succeeds and prints what the README shows: every line shown, in order,
with numbers free to differ (timings, dates) and runs of spaces taken as one; `...` stands for
lines left out. Usage: readme-tour.py README.md ROBOTPERF"""
import os
import re
import subprocess
import sys
import tempfile

readme, robotperf = sys.argv[1], os.path.abspath(sys.argv[2])
text = open(readme, encoding='utf-8').read()
tour = re.search(r'^## A short tour\n.*?^```console\n(.*?)^```', text, re.S | re.M)
if not tour:
    sys.exit('readme-tour: no "## A short tour" with a console block in ' + readme)

steps = []  # (command, the lines it is shown to print)
for line in tour.group(1).splitlines():
    if line.startswith('$ '):
        steps.append((re.sub(r'\s+#.*$', '', line[2:]), []))
    elif steps:
        steps[-1][1].append(line)


def pattern(shown):
    """A shown line as a regex: numbers match any number, spaces any run of spaces."""
    parts = re.split(r'(\d+(?:\.\d+)?)', ' '.join(shown.split()))
    return re.compile('^' + ''.join(r'\d+(?:\.\d+)?' if i % 2 else re.escape(p)
                                     for i, p in enumerate(parts)) + '$')


failed = False  # any step
with tempfile.TemporaryDirectory(prefix='robotperf-tour-') as folder:
    for command, shown in steps:
        run = command.replace('./build/robotperf', robotperf, 1)
        done = subprocess.run(run, shell=True, cwd=folder, capture_output=True, text=True,
                              timeout=600)
        printed = [' '.join(l.split()) for l in (done.stdout + done.stderr).splitlines()]
        ok = done.returncode == 0
        if not ok:
            print(f'readme-tour: `{command}` exited {done.returncode}:\n' + '\n'.join(printed[-20:]))
        at = 0
        for line in shown if ok else []:
            if line.strip() in ('...', ''):
                continue
            want = pattern(line)
            while at < len(printed) and not want.match(printed[at]):
                at += 1
            if at == len(printed):
                print(f'readme-tour: `{command}` did not print, where the README shows it:\n  {line}')
                ok = False
                break
            at += 1
        failed |= not ok
        print(f'readme-tour: {"ok" if ok else "FAILED"}: {command}')
sys.exit(1 if failed else 0)
