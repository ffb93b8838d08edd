#!/usr/bin/env python3
"""Checks every relative link of README.md and docs/**/*.md: the file it names exists in the
repository and, for a link to a Markdown heading (#anchor), the heading does, under the same
anchor on GitHub and in the mkdocs site (whose anchors collapse runs of '-' and drop accents).
Prints one line per broken link; exits 1 when there is any. Usage: check-docs-links.py [ROOT]"""
import os
import re
import sys
import unicodedata

root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), '..'))
LINK = re.compile(r'\]\(([^)\s]+)\)')


def slug(title):
    """GitHub's anchor of a heading."""
    t = re.sub(r'[^\w\- ]', '', title.strip().lower())
    return t.replace(' ', '-')


def site_slug(title):
    """The anchor Python-Markdown's toc extension (mkdocs) gives the same heading."""
    t = unicodedata.normalize('NFKD', title).encode('ascii', 'ignore').decode('ascii')
    t = re.sub(r'[^\w\s-]', '', t).strip().lower()
    return re.sub(r'[-\s]+', '-', t)


def outside_code(path):
    """The lines of a Markdown file outside fenced code blocks, with their numbers."""
    fence = False
    for number, line in enumerate(open(path, encoding='utf-8'), 1):
        if line.startswith('```'):
            fence = not fence
            continue
        if not fence:
            yield number, line.rstrip('\n')


def anchors(path, cache={}):
    """GitHub's anchors of a file's headings, each with the site's anchor of the same heading."""
    if path not in cache:
        found, counts = {}, {}
        for _, line in outside_code(path):
            m = re.match(r'^#{1,6} (.*)$', line)
            if m:
                s, site = slug(m.group(1)), site_slug(m.group(1))
                n = counts.get(s, 0)
                counts[s] = n + 1
                found[s if n == 0 else f'{s}-{n}'] = site if n == 0 else f'{site}_{n}'
        cache[path] = found
    return cache[path]


def markdown_files():
    yield os.path.join(root, 'README.md')
    for folder, _, files in os.walk(os.path.join(root, 'docs')):
        for f in sorted(files):
            if f.endswith('.md'):
                yield os.path.join(folder, f)


broken = 0
for md in markdown_files():
    for number, line in outside_code(md):
        for url in LINK.findall(re.sub(r'`[^`]*`', '', line)):
            if re.match(r'^[a-z]+:', url):
                continue
            path, _, anchor = url.partition('#')
            target = os.path.normpath(os.path.join(os.path.dirname(md), path)) if path else md
            where = f'{os.path.relpath(md, root)}:{number}'
            if not os.path.exists(target):
                print(f'{where}: link to {url}: no such file')
                broken += 1
            elif anchor and target.endswith('.md') and anchor not in anchors(target):
                print(f'{where}: link to {url}: no heading #{anchor} in {os.path.relpath(target, root)}')
                broken += 1
            elif anchor and target.endswith('.md') and anchors(target)[anchor] != anchor:
                print(f'{where}: link to {url}: the site names this heading '
                      f'#{anchors(target)[anchor]}; reword it so that both agree')
                broken += 1
sys.exit(1 if broken else 0)
