"""The link check (docs/check-links.py) on the real tree and its built book, and on copies with
planted broken links; the book's link preprocessor (docs/guide/repo-links.py) on pages of its own."""

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GUIDE = ROOT / "docs" / "guide"
SUMMARY = re.compile(r"\d+ relative links in \d+ (files|pages of the book .*), (\d+) broken")


def check(root, *args):
    """`check-links.py ROOT ARGS` as (exit status, output lines)."""
    done = subprocess.run(
        [sys.executable, str(ROOT / "docs" / "check-links.py"), str(root), *args],
        capture_output=True,
        text=True,
        timeout=120,
    )
    return done.returncode, (done.stdout + done.stderr).splitlines()


def broken(lines):
    """The lines naming a broken link (the summaries and notes left out)."""
    return [line for line in lines if not SUMMARY.fullmatch(line) and not line.startswith("note:")]


def mdbook():
    """The mdbook to build with: $MDBOOK, on PATH, or where .ci/run installs it; else None."""
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    for candidate in (os.environ.get("MDBOOK"), shutil.which("mdbook"), target / "tools/bin/mdbook"):
        if candidate and Path(candidate).is_file():
            return str(candidate)
    return None


@pytest.fixture(scope="module")
def book(tmp_path_factory):
    """The guide's book: built afresh into a scratch directory when mdbook is at hand, else the one
    `mdbook build docs/guide` left in docs/guide/book (as .ci/run does before the tests)."""
    if (tool := mdbook()) is not None:
        out = tmp_path_factory.mktemp("book") / "book"
        subprocess.run([tool, "build", str(GUIDE), "-d", str(out)], check=True, capture_output=True,
                       timeout=300)
        return out
    if (GUIDE / "book" / "index.html").is_file():
        return GUIDE / "book"
    pytest.skip("no mdbook and no built book (mdbook build docs/guide)")


def plant(page, html):
    """Inserts `html` into a page before </main>; returns the line it starts on."""
    text = page.read_text(encoding="utf-8")
    at = text.index("</main>")
    page.write_text(text[:at] + "\n" + html + "\n" + text[at:], encoding="utf-8")
    return text[:at].count("\n") + 2


# (a) the real tree


def test_real_tree_and_book_have_no_broken_link(book):
    status, lines = check(ROOT, "--book", str(book))
    assert status == 0, "\n".join(lines)
    summaries = [m for line in lines if (m := SUMMARY.fullmatch(line))]
    assert [m.group(2) for m in summaries] == ["0", "0"], lines
    assert broken(lines) == []


def test_book_holds_the_pages_and_pictures_the_guide_links_out_to(book):
    """The links that leave the guide's sources land on the book's own copies."""
    benchmarks = (book / "benchmarks.html").read_text(encoding="utf-8")
    assert 'href="results/kepler-work-precision.html"' in benchmarks
    assert 'src="assets/benches/results/kepler.svg"' in benchmarks
    solar = (book / "results" / "outer-solar-system.html").read_text(encoding="utf-8")
    assert 'src="../assets/docs/solar-system.svg"' in solar
    assert 'href="../command-line.html#comparing-methods-the-outer-solar-system"' in solar
    architecture = (book / "architecture.html").read_text(encoding="utf-8")
    assert 'href="repository/ARCHITECTURE.html"' in architecture
    for copy in ("assets/docs/solar-system.svg", "assets/benches/results/kepler.svg",
                 "results/index.html", "repository/ARCHITECTURE.html"):
        assert (book / copy).is_file(), copy


# (b) planted broken links


def test_broken_links_in_a_copy_of_the_book_fail(book, tmp_path):
    copy = tmp_path / "book"
    shutil.copytree(book, copy)
    page = copy / "results" / "outer-solar-system.html"
    missing = plant(page, '<p><a href="../nowhere.html#section">gone</a></p>')
    # The bug this check was written for: a picture that exists, but outside the book.
    outside = plant(copy / "stability.html", '<img src="../../kepler-energy-error.svg" alt="">')
    status, lines = check(ROOT, "--book", str(copy))
    assert status == 1, lines
    found = broken(lines)
    assert len(found) == 2, lines
    assert any(line.startswith(f"{page}:{missing}: href=\"../nowhere.html#section\": no file")
               for line in found), found
    assert any(line.startswith(f"{copy / 'stability.html'}:{outside}: "
                               'src="../../kepler-energy-error.svg":')
               and line.endswith("is outside the book") for line in found), found


def test_what_the_book_check_skips_and_resolves(tmp_path):
    """A book of its own: schemes, anchors, queries and fragments, <base href="/">, a directory
    with index.html; one broken link among them."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "index.html").write_text('<a href="sub/page.html">page</a>', encoding="utf-8")
    (tmp_path / "pic.svg").write_text("<svg/>", encoding="utf-8")
    (tmp_path / "sub" / "page.html").write_text(
        "\n".join([
            '<a href="https://example.org/x">web</a> <a href="mailto:a@b.c">mail</a>',
            '<a href="#top">anchor</a> <a href="../index.html#x">up</a> <img src="../pic.svg?v=1">',
            '<a href="..">the root</a> <a href="">empty</a> <a href="//cdn.example.org/x.js">cdn</a>',
            '<img src="pic.svg">',
        ]),
        encoding="utf-8",
    )
    (tmp_path / "404.html").write_text(
        '<base href="/">\n<a href="sub/page.html">page</a> <a href="/">home</a>', encoding="utf-8")
    status, lines = check(ROOT, "--book", str(tmp_path))
    assert status == 1, lines
    assert broken(lines) == [
        f'{tmp_path / "sub" / "page.html"}:4: src="pic.svg": no file {tmp_path / "sub" / "pic.svg"}'
    ], lines
    assert f"7 relative links in 3 pages of the book {tmp_path}, 1 broken" in lines


def test_a_missing_book_given_fails(tmp_path):
    status, lines = check(ROOT, "--book", str(tmp_path / "none"))
    assert status == 1
    assert f"{tmp_path / 'none'}: no built book there" in lines


def test_broken_markdown_links_in_a_copy_fail(tmp_path):
    """A copy of the tracked files, a link to nowhere and an include of nothing planted in the guide;
    no built book in the copy, so only the Markdown is checked."""
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        pytest.skip("not a git checkout")
    tracked = subprocess.run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=ROOT, capture_output=True, check=True)
    for name in tracked.stdout.decode().split("\0"):
        if name and (ROOT / name).exists():
            (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / name, tmp_path / name, follow_symlinks=False)
    json_md = tmp_path / "docs/guide/src/json.md"
    line = json_md.read_text(encoding="utf-8").count("\n") + 1
    with json_md.open("a", encoding="utf-8") as out:
        out.write("See [nowhere](../../results/nowhere.md).\n")
    (tmp_path / "docs/guide/src/results/gone.md").write_text(
        "{{#include ../../../results/gone.md}}\n", encoding="utf-8")
    status, lines = check(tmp_path)
    assert status == 1, lines
    assert broken(lines) == [
        f"docs/guide/src/json.md:{line}: ../../results/nowhere.md: no file docs/results/nowhere.md",
        "docs/guide/src/results/gone.md:1: ../../../results/gone.md: no file docs/results/gone.md",
    ], lines
    assert any(line.startswith("note: no built book") for line in lines), lines


# (c) the preprocessor


def preprocess(**pages):
    """repo-links.py on the guide's book (the pages SUMMARY.md lists), the given pages with the
    given text (keyword: the page's path, `/` written `__`); their text afterwards and stderr."""
    context = {"root": str(GUIDE), "config": {"book": {"src": "src"}}, "renderer": "html",
               "mdbook_version": "0.5.4"}
    texts = {path.replace("__", "/") + ".md": text for path, text in pages.items()}
    listed = re.findall(r"\]\(([^)]+\.md)\)", (GUIDE / "src" / "SUMMARY.md").read_text("utf-8"))
    items = [{"Chapter": {"name": path, "content": texts.get(path, ""), "number": None,
                          "sub_items": [], "path": path, "source_path": path, "parent_names": []}}
             for path in listed]
    done = subprocess.run([sys.executable, str(GUIDE / "repo-links.py")],
                          input=json.dumps([context, {"items": items}]), capture_output=True,
                          text=True, timeout=60, check=True)
    out = {item["Chapter"]["path"]: item["Chapter"]["content"]
           for item in json.loads(done.stdout)["items"]}
    return [out[path] for path in texts], done.stderr


def test_preprocessor_points_links_at_the_book_copies():
    (guide, results), errors = preprocess(
        benchmarks="\n".join([
            "![k](../../../benches/results/kepler.svg) [a](../../results/adaptive.md#x)",
            "[s](stability.md) [arch](../../../ARCHITECTURE.md) `[code](../../results/adaptive.md)`",
            "```", "[fenced](../../results/adaptive.md)", "```",
            "[web](https://example.org) [top](#top)",
        ]),
        results__stress="[s](../guide/src/stress.md#x) ![d](../../benches/results/stress/drift.svg)"
                        " [m](multiscale.md) [all](../guide/src/SUMMARY.md)",
    )
    assert guide.split("\n") == [
        "![k](assets/benches/results/kepler.svg) [a](results/adaptive.md#x)",
        "[s](stability.md) [arch](repository/ARCHITECTURE.md) `[code](../../results/adaptive.md)`",
        "```", "[fenced](../../results/adaptive.md)", "```",
        "[web](https://example.org) [top](#top)",
    ]
    assert results == ("[s](../stress.md#x) ![d](../assets/benches/results/stress/drift.svg)"
                       " [m](multiscale.md) [all](../getting-started.md)")
    assert errors == ""


def test_preprocessor_names_a_target_the_book_has_no_copy_of():
    (page,), errors = preprocess(json="[src](../../../src/lib.rs)")
    assert page == "[src](../../../src/lib.rs)"
    assert "json.md: ../../../src/lib.rs:" in errors and "has no copy in the book" in errors
