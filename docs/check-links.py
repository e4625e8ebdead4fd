#!/usr/bin/env python3
"""Every relative link of README.md, docs/guide/src/*.md and docs/results/*.md resolves to an
existing file, and every #anchor to a heading of that file (GitHub's and mdBook's slugs)."""
import glob, os, re, sys
root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..")
os.chdir(root)
files = ['README.md'] + sorted(glob.glob('docs/guide/src/*.md')) + sorted(glob.glob('docs/results/*.md'))
def slug(heading):
    s = heading.strip().lower()
    s = re.sub(r'`', '', s)
    s = re.sub(r'[^\w\- ]', '', s)   # \w is Unicode: letters, digits (also ⁶), underscore
    return s.replace(' ', '-')
def anchors(path):
    out, fence = set(), False
    for line in open(path):
        if line.lstrip().startswith('```'): fence = not fence; continue
        if not fence and (m := re.match(r'#{1,6} (.*)', line)): out.add(slug(m.group(1)))
    return out
def links(path):
    text, fence, out = open(path).read(), False, []
    for n, line in enumerate(text.split('\n'), 1):
        if line.lstrip().startswith('```'): fence = not fence; continue
        if fence: continue
        out += [(n, t) for t in re.findall(r'\]\(([^)\s]+)\)', line)]
    return out
bad = count = 0
for f in files:
    for n, target in links(f):
        if re.match(r'[a-z]+:', target): continue
        count += 1
        path, _, anchor = target.partition('#')
        dest = os.path.normpath(os.path.join(os.path.dirname(f), path)) if path else f
        if not os.path.exists(dest):
            print(f'{f}:{n}: {target}: no file {dest}'); bad += 1; continue
        if anchor and dest.endswith('.md') and anchor not in anchors(dest):
            print(f'{f}:{n}: {target}: no heading #{anchor} in {dest}'); bad += 1
print(f'{count} relative links in {len(files)} files, {bad} broken')
sys.exit(1 if bad else 0)
