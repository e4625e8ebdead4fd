#!/usr/bin/env python3
"""mdBook preprocessor (book.toml: [preprocessor.repo-links]): the relative links of the book's
pages, written for the repository, rewritten to the book's own copies of their targets.

Every page is written where it lives in the repository, so that its relative links work on
GitHub: `../../results/adaptive.md`, `../../kepler-energy-error.svg`, `../../../ARCHITECTURE.md`
from the guide, `../guide/src/stress.md` or `../solar-system.svg` from docs/results. Out of the
book (src/) those targets are not part of the built HTML, so the book holds its own copies, made
by mdBook without copied text:

- a Markdown file outside src/ is a page of the book whose source is one whole-file
  `{{#include PATH}}` of it (src/results/*.md, src/repository/ARCHITECTURE.md), listed in
  SUMMARY.md;
- any other file (a picture, the JSON schema) is a symbolic link under src/assets/, at its path
  in the repository (src/assets/docs/solar-system.svg -> docs/solar-system.svg); mdBook copies
  the file it points to into the book.

This preprocessor resolves each relative link of a page against the page's file in the
repository (for an include page, the included file), looks the target up among the book's pages
(SUMMARY.md: the first page) and the files under src/, and writes the link relative to the page's
place in the book (mdBook then turns `.md` into `.html`). A target the book holds no copy of is
left as it is and named on stderr; docs/check-links.py fails on it in the built HTML. Fenced code
blocks and code spans are left alone. Standard library only.
"""
import json
import os
import posixpath
import re
import sys
from urllib.parse import quote, unquote

# A page that is one whole-file include (no anchor, no line range).
STUB = re.compile(r'\{\{#include\s+([^\s:}]+)\s*\}\}')
# Link destinations: inline links and images `](dest`, reference definitions `[x]: dest`, and the
# src/href attributes of raw HTML.
INLINE = re.compile(r'(\]\(\s*<?)([^)\s>]+)')
REFERENCE = re.compile(r'^( {0,3}\[[^\]]+\]:[ \t]*<?)([^\s>]+)')
ATTRIBUTE = re.compile(r'(\b(?:src|href)\s*=\s*")([^"]*)(?=")')
CODE_SPAN = re.compile(r'(`+)(?:.+?)\1')
SCHEME = re.compile(r'[A-Za-z][A-Za-z0-9+.-]*:')


def chapters(items):
    """Every chapter of the book, depth first."""
    for item in items:
        chapter = item.get('Chapter') if isinstance(item, dict) else None
        if chapter:
            yield chapter
            yield from chapters(chapter.get('sub_items', []))


def origin(source):
    """The repository file whose text a page shows: the included file of a page that is one
    whole-file include, else the page's own file."""
    try:
        text = open(source, encoding='utf-8').read()
    except OSError:
        return source
    if (m := STUB.fullmatch(text.strip())):
        return os.path.normpath(os.path.join(os.path.dirname(source), m.group(1)))
    return source


class Book:
    def __init__(self, src, pages):
        self.src = src
        self.places = {}   # the real path of a repository file -> its place in the book
        for dirpath, _, names in os.walk(src, followlinks=True):
            for name in names:
                if not name.endswith('.md'):
                    path = os.path.join(dirpath, name)
                    self.places[os.path.realpath(path)] = os.path.relpath(path, src)
        for page in pages:
            source = os.path.join(src, page['source_path'])
            self.places[os.path.realpath(source)] = page['path']
            self.places[os.path.realpath(origin(source))] = page['path']
        if pages:
            self.places.setdefault(os.path.realpath(os.path.join(src, 'SUMMARY.md')), pages[0]['path'])

    def rewrite(self, page):
        """The page's text with its relative links rewritten to the book's copies."""
        source = os.path.join(self.src, page['source_path'])
        home = os.path.dirname(origin(source))           # where the text's links start, on GitHub
        here = posixpath.dirname(page['path'].replace(os.sep, '/'))   # where they start in the book

        def link(target):
            if not target or target.startswith(('#', '/')) or SCHEME.match(target):
                return target
            path, hash_, fragment = target.partition('#')
            real = os.path.realpath(os.path.join(home, unquote(path)))
            place = self.places.get(real)
            if place is None:
                print(f'repo-links: {page["source_path"]}: {target}: '
                      f'{os.path.relpath(real)} has no copy in the book (an include page '
                      f'in SUMMARY.md, or a symbolic link under src/assets/)', file=sys.stderr)
                return target
            new = posixpath.relpath(place.replace(os.sep, '/'), here or '.')
            return quote(new) + hash_ + fragment if new != path else target

        out, fence = [], None
        for line in page['content'].split('\n'):
            stripped = line.lstrip()
            if fence:
                if stripped.startswith(fence):
                    fence = None
            elif (m := re.match(r'(`{3,}|~{3,})', stripped)):
                fence = m.group(1)
            else:
                line = REFERENCE.sub(lambda m: m.group(1) + link(m.group(2)), line)
                pieces, last = [], 0
                for span in CODE_SPAN.finditer(line):
                    pieces += [links(line[last:span.start()], link), span.group(0)]
                    last = span.end()
                line = ''.join(pieces) + links(line[last:], link)
            out.append(line)
        return '\n'.join(out)


def links(text, link):
    text = INLINE.sub(lambda m: m.group(1) + link(m.group(2)), text)
    return ATTRIBUTE.sub(lambda m: m.group(1) + link(m.group(2)), text)


def main():
    if len(sys.argv) > 1:        # `repo-links.py supports RENDERER`: every renderer
        sys.exit(0)
    context, book = json.load(sys.stdin)
    src = os.path.join(context['root'], context['config'].get('book', {}).get('src', 'src'))
    items = book.get('items', book.get('sections', []))
    pages = [c for c in chapters(items) if c.get('path')]
    repo = Book(src, pages)
    for page in pages:
        page['content'] = repo.rewrite(page)
    json.dump(book, sys.stdout)


if __name__ == '__main__':
    main()
