#!/usr/bin/env python3
"""The layer check (ARCHITECTURE.md, "The layers of the library"): no module imports from a
layer after its own, and no workspace crate depends on a crate after its own.

The layers are declared once, in `.ci/layers.toml`: per source tree (`[trees."src"]`, ...) an
ordered list of layers, each a list of files (`error.rs`) and folders (`model/`) relative to
the tree's root. A file belongs to the layer of its most specific entry (a file, else the
longest folder); a file in no layer, an entry that matches no file, or an entry declared twice
is an error, so new files and folders must be declared. The crate roots (`exempt`, e.g.
`lib.rs`) are not checked; a path through the root (`crate::Integrator`) is followed through
the root's `use` declarations and type aliases to the module that defines it.

An import is every path to another module of the same crate outside comments (`//`, `///`,
`//!`, `/* */`: doc links are not imports) and string literals: `use` declarations with their
nested groups (`pub use` too), and paths in code (`crate::a::b::f(...)`, types, traits),
starting with `crate::`, `super::` (resolved against the module the path is written in,
inline modules such as `mod tests` included), `self::`, or a child module's name. Its module
is the longest prefix of the path that is a file of the tree. Code under `#[cfg(test)]`
(unit-test modules, and files declared by a `#[cfg(test)] mod x;`) is checked only with
`tests = "check"` in the tree's table or `--tests`.

The crate rule (`[crates]`): workspace members in levels, bottom up; a crate's
`[dependencies]` (also `[build-dependencies]` and `[target.*.dependencies]`, not
`[dev-dependencies]`) may name only workspace crates of earlier levels.

Exit status: 0 if nothing is wrong; 1 if a module imports from a later layer, or a file,
declaration or crate is undeclared or malformed; 3 if the only findings are crate
dependencies against the order (not listed in `[crates] allow`).

Python 3.11 standard library only. Usage: python3 .ci/layers.py [--config .ci/layers.toml]
[--root .] [--tests]
"""

import argparse
import re
import sys
import tomllib
from pathlib import Path

IDENT = r"[A-Za-z_][A-Za-z0-9_]*"
KEYWORD_ROOTS = ("crate", "$crate", "super", "self")


class ConfigError(Exception):
    pass


# --- Rust source: comments and literals out, then declarations and paths ----------------------

CHAR_LITERAL = re.compile(r"'(?:[^'\\\n]|\\(?:x[0-9a-fA-F]{2}|u\{[0-9a-fA-F_]{1,6}\}|.))'")


LEXEME = re.compile(r"""//|/\*|\b(?:br|cr|r|b|c)(?=[#"'])|["']""")


def strip(text):
    """The text with comments, string and character literals replaced by spaces (newlines
    kept, so offsets and line numbers are the original's)."""
    out = []  # the pieces of the result
    n = len(text)

    def blank(a, b):
        out.append(re.sub(r"[^\n]", " ", text[a:b]))

    def string_end(j):  # j: index of the opening quote of a non-raw string
        j += 1
        while j < n:
            if text[j] == "\\":
                j += 2
            elif text[j] == '"':
                return j + 1
            else:
                j += 1
        return n

    i = 0
    while (m := LEXEME.search(text, i)) is not None:
        out.append(text[i : m.start()])
        i, lexeme = m.start(), m.group()
        if lexeme == "//":
            end = text.find("\n", i)
            end = n if end < 0 else end
        elif lexeme == "/*":  # block comments nest
            depth, end = 0, i
            while end < n:
                if text.startswith("/*", end):
                    depth, end = depth + 1, end + 2
                elif text.startswith("*/", end):
                    depth, end = depth - 1, end + 2
                    if depth == 0:
                        break
                else:
                    end += 1
        elif lexeme in ("r", "br", "cr"):
            k = m.end()
            while k < n and text[k] == "#":
                k += 1
            if k < n and text[k] == '"':  # a raw string r#"..."#
                close = '"' + "#" * (k - m.end())
                end = text.find(close, k + 1)
                end = n if end < 0 else end + len(close)
            else:  # a raw identifier r#name
                out.append(text[i:k])
                i = k
                continue
        elif lexeme in ("b", "c", '"'):
            quote = m.end() if lexeme != '"' else i
            if text[quote] == '"':
                end = string_end(quote)
            else:  # b'x'
                char = CHAR_LITERAL.match(text, quote)
                end = char.end() if char else quote + 1
        else:  # ': a character, or a lifetime or label (kept)
            char = CHAR_LITERAL.match(text, i)
            if not char:
                out.append("'")
                i += 1
                continue
            end = char.end()
        blank(i, end)
        i = end
    out.append(text[i:])
    return "".join(out)


OPEN, CLOSE = "([{", ")]}"


BRACKET = re.compile(r"[()\[\]{};]")


def matching(code, i):
    """The index after the bracket that closes the one at `i`."""
    depth = 0
    for m in BRACKET.finditer(code, i):
        ch = m.group()
        if ch in OPEN:
            depth += 1
        elif ch in CLOSE:
            depth -= 1
            if depth == 0:
                return m.end()
    return len(code)


CFG = re.compile(r"#\s*\[\s*cfg\s*\((.*?)\)\s*\]", re.S)
INNER_CFG_TEST = re.compile(r"#\s*!\s*\[\s*cfg\s*\(\s*test\s*\)\s*\]")
ATTRIBUTE = re.compile(r"\s*#\s*\[")
USE_ITEM = re.compile(r"\s*(?:pub\s*(?:\([^)]*\))?\s*)?use\b")


def test_only(condition):
    """Whether a `cfg(...)` condition holds only in test builds."""
    return re.search(r"\btest\b", condition) and not re.search(r"\b(not|any)\b", condition)


def item_end(code, i):
    """The end of the item that starts at `i` (after its attributes)."""
    while m := ATTRIBUTE.match(code, i):
        i = matching(code, m.end() - 1)
    if USE_ITEM.match(code, i):
        end = code.find(";", i)
        return len(code) if end < 0 else end + 1
    depth = 0
    for m in BRACKET.finditer(code, i):
        ch = m.group()
        if ch in OPEN:
            depth += 1
        elif ch in CLOSE:
            depth -= 1
            if depth == 0 and ch == "}":
                return m.end()
        elif depth == 0:  # ;
            return m.end()
    return len(code)


def test_spans(code):
    """The (start, end) spans of the items under `#[cfg(test)]`."""
    spans = []
    for m in CFG.finditer(code):
        if test_only(m.group(1)) and not any(a <= m.start() < b for a, b in spans):
            spans.append((m.start(), item_end(code, m.end())))
    return spans


# `mod name {` (inline) or `mod name;` (a file); the character before is checked apart (a
# leading \b or look-behind would keep the regex engine from searching for "mod" directly).
MOD = re.compile(rf"mod\s+({IDENT})\s*([{{;])")


def modules_declared(code):
    """Each `mod` declaration: (offset, name, inline)."""
    return [
        (m.start(), m.group(1), m.group(2) == "{")
        for m in MOD.finditer(code)
        if m.start() == 0 or not (code[m.start() - 1].isalnum() or code[m.start() - 1] in "_$")
    ]


class Scopes:
    """The inline modules (`mod tests { ... }`) of a file: the module path at each offset and
    the child modules each declares."""

    def __init__(self, code, module):
        self.spans = [(0, len(code), tuple(module))]  # in order of their start
        self.children = {}
        for offset, name, inline in modules_declared(code):
            parent = self.at(offset)
            self.children.setdefault(parent, set()).add(name)
            if inline:
                brace = code.index("{", offset)
                self.spans.append((brace, matching(code, brace), parent + (name,)))

    def at(self, offset):
        """The module path at an offset: its innermost inline module's."""
        path = self.spans[0][2]
        for start, end, inner in self.spans[1:]:
            if start <= offset < end:
                path = inner
        return path


USE = re.compile(r"(?<![A-Za-z0-9_#$.])use\b")
USE_TOKEN = re.compile(rf"::|[{{}},*;]|\$?{IDENT}|\S")
PUB_IN = re.compile(r"\bpub\s*\(\s*in\b[^)]*\)")
INLINE_PATH = re.compile(rf"(?<![A-Za-z0-9_$#.:])(\$?{IDENT})((?:\s*::\s*{IDENT})+)")


def use_declarations(code):
    """Each `use` declaration as (start, end, [(segments, offset of the last segment), ...])."""
    found = []
    for m in USE.finditer(code):
        end = code.find(";", m.end())
        end = len(code) if end < 0 else end
        tokens = [(t.group(), t.start()) for t in USE_TOKEN.finditer(code, m.end(), end)]
        found.append((m.start(), end + 1, parse_use_tree(tokens, m.start())))
    return found


def parse_use_tree(tokens, offset):
    """The paths of a use tree: `a::{b, c::{self, d as e}, f::*}` gives a::b, a::c, a::c::d,
    a::f."""
    paths = []
    k = 0

    def peek():
        return tokens[k][0] if k < len(tokens) else None

    def tree(prefix):
        nonlocal k
        segments, last = list(prefix), offset
        if peek() == "::":  # `use ::name`: an external crate
            segments.append("::")
            k += 1
        while True:
            token = peek()
            if token == "{":
                k += 1
                while peek() not in ("}", None):
                    tree(segments)
                    if peek() == ",":
                        k += 1
                k += 1
                return
            if token == "*":
                k += 1
                paths.append((segments + ["*"], last))
                return
            if token is None or not re.fullmatch(rf"\$?{IDENT}", token):
                raise ValueError(f"unexpected {token!r} in a use declaration")
            segments.append(token)
            last = tokens[k][1]
            k += 1
            if peek() == "::":
                k += 1
                continue
            if peek() == "as":
                k += 2
            if segments[-1] == "self" and len(segments) > 1:
                segments.pop()
            paths.append((segments, last))
            return

    tree([])
    return paths


# --- The declaration --------------------------------------------------------------------------


def module_path(rel):
    """The module path of a file relative to its tree's root: `a/b.rs` and `a/b/mod.rs` are
    ("a", "b"); `lib.rs` and `main.rs` the root ()."""
    parts = rel.split("/")
    if len(parts) == 1 and parts[0] in ("lib.rs", "main.rs"):
        return ()
    if parts[-1] == "mod.rs":
        return tuple(parts[:-1])
    return tuple(parts[:-1]) + (parts[-1][: -len(".rs")],)


def show(module):
    return "::".join(module) or "crate"


class Tree:
    def __init__(self, root, name, table, config):
        self.name = name
        self.label = f'{config} [trees."{name}"]'
        self.dir = root / name
        self.check_tests = table.get("tests", "skip") == "check"
        if table.get("tests", "skip") not in ("skip", "check"):
            raise ConfigError(f'trees."{name}".tests: "skip" or "check", not {table["tests"]!r}')
        self.exempt = list(table.get("exempt", []))
        self.layers = []
        names = set()
        for layer in table.get("layers", []):
            if "name" not in layer or not layer.get("paths"):
                raise ConfigError(f'trees."{name}": every layer needs a name and paths')
            if layer["name"] in names:
                raise ConfigError(f'trees."{name}": layer {layer["name"]!r} declared twice')
            names.add(layer["name"])
            self.layers.append((layer["name"], list(layer["paths"])))
        if not self.layers:
            raise ConfigError(f'trees."{name}": no layers')
        seen = set(self.exempt)
        for _, entries in self.layers:
            for entry in entries:
                if not (entry.endswith(".rs") or entry.endswith("/")):
                    raise ConfigError(
                        f'trees."{name}": {entry!r} is neither a file (.rs) nor a folder (/)'
                    )
                if entry in seen:
                    raise ConfigError(f'trees."{name}": {entry!r} declared twice')
                seen.add(entry)
        if not self.dir.is_dir():
            raise ConfigError(f'trees."{name}": no folder {self.dir}')

    def layer_of(self, rel):
        """The layer index of a file, None if exempt; KeyError if undeclared."""
        if rel in self.exempt:
            return None
        best, length = None, -1
        for index, (_, entries) in enumerate(self.layers):
            for entry in entries:
                if entry == rel:
                    return index
                if entry.endswith("/") and rel.startswith(entry) and len(entry) > length:
                    best, length = index, len(entry)
        if best is None:
            raise KeyError(rel)
        return best


class Source:
    def __init__(self, tree, path):
        self.path = path
        self.rel = path.relative_to(tree.dir).as_posix()
        self.module = module_path(self.rel)
        text = path.read_text(encoding="utf-8")
        self.code = strip(text)
        self.scopes = Scopes(self.code, self.module)
        self.tests = test_spans(self.code)
        self.whole_file_test = bool(INNER_CFG_TEST.search(self.code))
        self.test_children = {
            self.scopes.at(offset) + (name,)
            for offset, name, inline in modules_declared(self.code)
            if not inline and self.in_tests(offset)
        }

    def line(self, offset):
        return self.code.count("\n", 0, offset) + 1

    def in_tests(self, offset):
        return any(a <= offset < b for a, b in self.tests)

    def references(self):
        """Each path to a module of this crate: (offset, its segments from the crate root)."""
        refs, pieces, done = [], [], 0
        for start, end, paths in self.uses():  # taken out of the code for the inline paths
            refs += [(offset, segments) for segments, offset in paths]
            pieces += [self.code[done:start], re.sub(r"[^\n]", " ", self.code[start:end])]
            done = end
        code = "".join(pieces) + self.code[done:]
        code = PUB_IN.sub(lambda m: re.sub(r"[^\n]", " ", m.group()), code)
        for m in INLINE_PATH.finditer(code):
            segments = [m.group(1)] + re.findall(IDENT, m.group(2))
            refs.append((m.start(), segments))
        resolved = []
        for offset, segments in refs:
            absolute = self.absolute(segments, self.scopes.at(offset))
            if absolute is not None:
                resolved.append((offset, absolute))
        return resolved

    def uses(self):
        try:
            return use_declarations(self.code)
        except ValueError as error:
            raise SourceError(f"{self.path}: cannot read a use declaration: {error}") from None

    def absolute(self, segments, scope):
        """The path from the crate root, None if the path leaves the crate."""
        head = segments[0]
        if head in ("crate", "$crate"):
            return tuple(segments[1:])
        if head in ("self", "super"):
            path, rest = list(scope), list(segments)
            if rest[0] == "self":
                rest.pop(0)
            while rest and rest[0] == "super":
                if not path:
                    raise SourceError(f"{self.path}: `{'::'.join(segments)}` leaves the crate")
                path.pop()
                rest.pop(0)
            return tuple(path + rest)
        if head in self.scopes.children.get(scope, ()):
            return tuple(scope) + tuple(segments)
        return None


class SourceError(Exception):
    pass


def check_tree(tree, run_tests, out):
    """The errors and upward imports of one tree; prints them, returns (files, problems)."""
    problems = 0
    files = sorted(tree.dir.rglob("*.rs"))
    sources, layer_of = {}, {}
    for path in files:
        rel = path.relative_to(tree.dir).as_posix()
        try:
            layer_of[rel] = tree.layer_of(rel)
        except KeyError:
            print(f"{tree.name}/{rel}: in no layer of {tree.label}", file=out)
            problems += 1
            continue
        sources[rel] = Source(tree, path)
    rels = [path.relative_to(tree.dir).as_posix() for path in files]
    for entry in tree.exempt + [e for _, entries in tree.layers for e in entries]:
        if not any(rel == entry or (entry.endswith("/") and rel.startswith(entry)) for rel in rels):
            print(f"{tree.label}: {entry!r} matches no file", file=out)
            problems += 1

    modules = {source.module: rel for rel, source in sources.items()}
    test_modules = set()
    for source in sources.values():
        if source.whole_file_test:
            test_modules.add(source.module)
        test_modules |= source.test_children

    def is_test_file(source):
        return any(source.module[: len(m)] == m for m in test_modules)

    root_names = root_aliases(sources, modules)

    def target(path, depth=0):
        """The file (relative path) of the module a path names, None for the root itself."""
        for length in range(len(path), 0, -1):
            if path[:length] in modules:
                return modules[path[:length]]
        # A name the root makes (a module and a function may share it: try each).
        for alias in root_names.get(path[0] if path else None, []) if depth < 8 else []:
            if (found := target(alias + path[1:], depth + 1)) is not None:
                return found
        return None

    checked_tests = tree.check_tests or run_tests
    for rel, source in sorted(sources.items()):
        own = layer_of[rel]
        if own is None or (not checked_tests and is_test_file(source)):
            continue
        seen = set()
        for offset, path in source.references():
            if not checked_tests and source.in_tests(offset):
                continue
            to = target(path)
            if to is None or to not in layer_of or layer_of[to] is None:
                continue
            if layer_of[to] > own:
                line = source.line(offset)
                key = (line, to)
                if key in seen:
                    continue
                seen.add(key)
                print(
                    f"{tree.name}/{rel}:{line}: module {show(source.module)} (layer "
                    f"{tree.layers[own][0]}) imports {show(sources[to].module)} (layer "
                    f"{tree.layers[layer_of[to]][0]}, a later layer)",
                    file=out,
                )
                problems += 1
    return len(files), problems


def root_aliases(sources, modules):
    """The names the crate root makes, `use a::b::C;` (also `as D`) and `type T = a::U;`:
    each name to its paths from the root."""
    names = {}
    root = sources.get(modules.get(()))
    if root is None:
        return names
    for _, _, paths in root.uses():
        for segments, offset in paths:
            if segments[-1] == "*" or segments[0] == "::":
                continue
            # Paths from the root: `crate::a::B`, or `a::B` (a module, or a name the root
            # makes, followed by target()).
            absolute = (
                root.absolute(segments, ()) if segments[0] in KEYWORD_ROOTS else tuple(segments)
            )
            if absolute:
                rename = re.match(rf"\s*as\s+({IDENT})", root.code[offset + len(segments[-1]) :])
                names.setdefault(rename.group(1) if rename else absolute[-1], []).append(absolute)
    for m in re.finditer(rf"\btype\s+({IDENT})[^=;]*=\s*((?:{IDENT}\s*::\s*)*{IDENT})", root.code):
        segments = re.findall(IDENT, m.group(2))
        names.setdefault(m.group(1), []).append(
            root.absolute(segments, ()) if segments[0] in KEYWORD_ROOTS else tuple(segments)
        )
    return names


# --- The crates -------------------------------------------------------------------------------

DEPENDENCY_SECTION = re.compile(r"(target\..*\.)?(build-)?dependencies")


def check_crates(root, table, out):
    """The workspace's crates against `[crates] order`: (crate count, level count, errors,
    dependencies against the order)."""
    manifest = tomllib.loads((root / "Cargo.toml").read_text(encoding="utf-8"))
    workspace = manifest.get("workspace", {})
    members = []
    for pattern in workspace.get("members", []):
        found = root.glob(pattern) if any(ch in pattern for ch in "*?[") else [root / pattern]
        members += sorted(p.resolve() for p in found if (p / "Cargo.toml").is_file())
    if "package" in manifest and root.resolve() not in members:
        members.insert(0, root.resolve())
    levels = {}
    for index, level in enumerate(table.get("order", [])):
        for name in [level] if isinstance(level, str) else level:
            if name in levels:
                raise ConfigError(f"crates.order: {name!r} listed twice")
            levels[name] = index
    allowed = {tuple(pair) for pair in table.get("allow", [])}
    shared = workspace.get("dependencies", {})
    crates = {}
    for member in members:
        path = member / "Cargo.toml"
        crates[tomllib.loads(path.read_text(encoding="utf-8"))["package"]["name"]] = path
    errors = against = 0
    for name, path in crates.items():
        rel = path.relative_to(root.resolve()).as_posix()
        if name not in levels:
            print(f"{rel}: crate {name} is in no level of [crates] order", file=out)
            errors += 1
            continue
        for line, dependency in dependencies(path, shared):
            if dependency not in crates or dependency not in levels:
                continue
            if levels[dependency] >= levels[name]:
                relation = "a later" if levels[dependency] > levels[name] else "the same"
                message = (
                    f"{rel}:{line}: crate {name} (level {levels[name] + 1}) depends on "
                    f"{dependency} (level {levels[dependency] + 1}, {relation} level)"
                )
                if (name, dependency) in allowed:
                    print(f"{message} [allowed by [crates] allow]", file=out)
                else:
                    print(message, file=out)
                    against += 1
    for name in levels:
        if name not in crates:
            print(f"[crates] order: {name} is no workspace crate", file=out)
            errors += 1
    return len(crates), len(table.get("order", [])), errors, against


def dependencies(path, shared):
    """(line, crate name) of each dependency of a manifest, dev-dependencies left out."""
    manifest = tomllib.loads(path.read_text(encoding="utf-8"))
    sections = [manifest.get("dependencies", {}), manifest.get("build-dependencies", {})]
    for target in manifest.get("target", {}).values():
        sections += [target.get("dependencies", {}), target.get("build-dependencies", {})]
    names = {}
    for section in sections:
        for key, spec in section.items():
            if isinstance(spec, dict) and spec.get("workspace"):
                spec = shared.get(key, {})
            names[key] = spec.get("package", key) if isinstance(spec, dict) else key
    lines, section = {}, None
    for number, text in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
        header = re.match(r"\s*\[([^\]]+)\]", text)
        if header:
            section = header.group(1).replace("'", "").replace('"', "")
            continue
        key = re.match(r'\s*"?([A-Za-z0-9_-]+)"?\s*[.=]', text)
        if key and section and DEPENDENCY_SECTION.fullmatch(section) and key.group(1) in names:
            lines.setdefault(key.group(1), number)
    return [(lines.get(key, 1), names[key]) for key in names]


def plural(count, one, many=None):
    return f"{count} {one if count == 1 else many or one + 's'}"


# --- Main -------------------------------------------------------------------------------------


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--config", help="the declaration (default: ROOT/.ci/layers.toml)")
    parser.add_argument("--root", default=".", help="the workspace root (default: .)")
    parser.add_argument("--tests", action="store_true", help="check #[cfg(test)] code too")
    args = parser.parse_args(argv)
    root = Path(args.root)
    config = Path(args.config) if args.config else root / ".ci" / "layers.toml"
    out = sys.stdout
    try:
        declaration = tomllib.loads(config.read_text(encoding="utf-8"))
        trees = [
            Tree(root, name, table, config)
            for name, table in declaration.get("trees", {}).items()
        ]
        if not trees:
            raise ConfigError("no [trees.NAME] table")
        problems = 0
        for tree in trees:
            files, found = check_tree(tree, args.tests, out)
            problems += found
            if found == 0:
                print(
                    f"layers: {files} files of {tree.name} in {len(tree.layers)} layers, "
                    f"no upward import",
                    file=out,
                )
            else:
                print(f"layers: {plural(found, 'problem')} in {tree.name}", file=out)
        against = 0
        if "crates" in declaration:
            count, levels, errors, against = check_crates(root, declaration["crates"], out)
            problems += errors
            if errors == 0 and against == 0:
                print(
                    f"crates: {count} workspace crates in {levels} levels, no upward dependency",
                    file=out,
                )
            else:
                findings = [plural(errors, "problem")] if errors else []
                if against:
                    findings.append(
                        f"{plural(against, 'dependency', 'dependencies')} against the order"
                    )
                print(f"crates: {', '.join(findings)}", file=out)
    except (ConfigError, SourceError, OSError, tomllib.TOMLDecodeError) as error:
        where = f"{config}: " if isinstance(error, ConfigError) else ""
        print(f"layers: {where}{error}", file=out)
        return 1
    return 1 if problems else 3 if against else 0


if __name__ == "__main__":
    sys.exit(main())
