#!/usr/bin/env python3
"""Every relative link of README.md, the guide's sources (docs/guide/src) and docs/results/*.md
resolves to an existing file, and every #anchor to a heading of that file (GitHub's and mdBook's
slugs); every {{#include}} of the guide names an existing file. Then the built book (the HTML
that `mdbook build docs/guide` writes): every relative href and src of its pages points to an
existing file inside the book (#fragments and ?queries stripped; http(s), mailto and other
schemes, and pure #anchors, skipped).

    python3 docs/check-links.py [ROOT] [--book DIR]

ROOT is the repository (default: the one holding this script). The book is DIR (it must exist),
else ROOT/docs/guide/book when it has been built; when it has not, its check is skipped with a
note. Exit status 1 when a link is broken, each named as FILE:LINE: LINK."""
import argparse, glob, os, re, sys
from html.parser import HTMLParser
from urllib.parse import unquote

parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
parser.add_argument('root', nargs='?',
                    default=os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
parser.add_argument('--book', help='the built book (default: ROOT/docs/guide/book if built)')
args = parser.parse_args()
book = os.path.abspath(args.book) if args.book else None
os.chdir(args.root)

# (a) the Markdown sources, as GitHub shows them
files = (['README.md'] + sorted(glob.glob('docs/guide/src/**/*.md', recursive=True))
         + sorted(glob.glob('docs/results/*.md')))
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
        out += [(n, t.split(':')[0]) for t in re.findall(r'\{\{#include\s+([^\s}]+)\s*\}\}', line)]
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

# (b) the built book, as a browser opens it from its files
class Links(HTMLParser):
    """The href and src attributes of a page, with their lines, and its <base href>."""
    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.found, self.base = [], None
    def handle_starttag(self, tag, attrs):
        for name, value in attrs:
            if name in ('href', 'src') and value is not None:
                if tag == 'base' and name == 'href': self.base = value
                else: self.found.append((self.getpos()[0], name, value))
    handle_startendtag = handle_starttag
def shown(path):
    rel = os.path.relpath(path)
    return path if rel.startswith('..') else rel
if book is None and os.path.isdir('docs/guide/book'):
    book = os.path.abspath('docs/guide/book')
if book is None:
    print('note: no built book at docs/guide/book (mdbook build docs/guide); its links are not checked',
          file=sys.stderr)
elif not os.path.isdir(book):
    print(f'{book}: no built book there'); bad += 1
else:
    pages = sorted(glob.glob(os.path.join(book, '**', '*.html'), recursive=True))
    checked = broken = 0
    for page in pages:
        found = Links()
        found.feed(open(page, encoding='utf-8').read())
        here = os.path.dirname(page)
        if found.base is not None:   # 404.html: <base href="/">, the site's root is the book's
            here = (os.path.join(book, found.base.lstrip('/')) if found.base.startswith('/')
                    else os.path.join(here, found.base))
        for line, name, value in found.found:
            target = value.strip()
            if not target or target.startswith(('#', '//')) or re.match(r'[A-Za-z][A-Za-z0-9+.-]*:', target):
                continue
            path = unquote(re.split(r'[#?]', target, maxsplit=1)[0])
            if not path: continue
            checked += 1
            dest = os.path.normpath(os.path.join(book, path.lstrip('/')) if path.startswith('/')
                                    else os.path.join(here, path))
            inside = os.path.commonpath([dest, book]) == book
            if inside and os.path.isdir(dest): dest = os.path.join(dest, 'index.html')
            if not inside:
                print(f'{shown(page)}:{line}: {name}="{value}": {shown(dest)} is outside the book'); broken += 1
            elif not os.path.isfile(dest):
                print(f'{shown(page)}:{line}: {name}="{value}": no file {shown(dest)}'); broken += 1
    print(f'{checked} relative links in {len(pages)} pages of the book {shown(book)}, {broken} broken')
    bad += broken
sys.exit(1 if bad else 0)
