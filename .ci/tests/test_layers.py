"""The layer check (.ci/layers.py) on the real tree and on copies of it with planted imports."""

import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
# The workspace's manifests (the crate rule reads them).
MANIFESTS = ["Cargo.toml"] + [
    f"{member}/Cargo.toml"
    for member in tomllib.loads((ROOT / "Cargo.toml").read_text(encoding="utf-8"))["workspace"][
        "members"
    ]
    if member != "."
]
# The one crate dependency against the order today (ARCHITECTURE.md: to go away).



def check(root, *args):
    """`layers.py --root ROOT ARGS` as (exit status, output lines)."""
    done = subprocess.run(
        [sys.executable, str(root / ".ci" / "layers.py"), "--root", str(root), *args],
        capture_output=True,
        text=True,
        timeout=60,
    )
    return done.returncode, (done.stdout + done.stderr).splitlines()


def module_findings(lines):
    """The lines about src/ (crate findings left out)."""
    return [line for line in lines if line.startswith("src")]


@pytest.fixture
def tree(tmp_path):
    """A copy of what the check reads: .ci/, the source trees and the workspace's manifests."""
    shutil.copytree(
        ROOT / ".ci", tmp_path / ".ci", ignore=shutil.ignore_patterns("__pycache__", "tests")
    )
    for source in ("src", "experiments/src"):
        shutil.copytree(ROOT / source, tmp_path / source)
    for manifest in MANIFESTS:
        (tmp_path / manifest).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(ROOT / manifest, tmp_path / manifest)
    return tmp_path


def plant(root, rel, text):
    """Appends `text` to a file; returns the line number of its first line."""
    path = root / rel
    before = path.read_text(encoding="utf-8")
    if not before.endswith("\n"):
        before += "\n"
    path.write_text(before + text, encoding="utf-8")
    return before.count("\n") + 1


# (a) the real tree


@pytest.fixture(scope="module")
def real():
    return check(ROOT)


def test_real_tree_has_no_upward_import(real):
    status, lines = real
    assert status == 0, "\n".join(lines)
    assert module_findings(lines) == []
    summary = re.compile(r"layers: \d+ files of src in \d+ layers, no upward import")
    assert any(summary.fullmatch(line) for line in lines), lines


def test_real_crates_follow_the_order(real):
    status, lines = real
    assert status == 0, "\n".join(lines)


# (b) planted upward imports


def test_use_of_a_later_layer_fails(tree):
    line = plant(tree, "src/error.rs", "use crate::stepping::run::Integrator;\n")
    status, lines = check(tree)
    assert status == 1
    assert (
        f"src/error.rs:{line}: module error (layer leaves) imports stepping::run "
        "(layer stepping, a later layer)"
    ) in lines


def test_nested_groups_and_pub_use_fail_on_the_later_leaf(tree):
    line = plant(
        tree,
        "src/scalar.rs",
        "pub use crate::{\n    error::Error,\n    method::{space::SO3, step::Step},\n};\n",
    )
    status, lines = check(tree)
    assert status == 1
    found = module_findings(lines)
    # One finding per leaf of the tree, on the leaf's line; error::Error is allowed.
    assert found == [
        f"src/scalar.rs:{line + 2}: module scalar (layer leaves) imports {module} "
        "(layer methods, a later layer)"
        for module in ("method::space", "method::step")
    ], found


def test_inline_path_into_a_later_layer_fails(tree):
    line = plant(
        tree,
        "src/model/so3.rs",
        "pub fn planted() -> usize {\n    crate::analysis::verify::planted(1)\n}\n",
    )
    status, lines = check(tree)
    assert status == 1
    assert (
        f"src/model/so3.rs:{line + 1}: module model::so3 (layer model) imports analysis::verify "
        "(layer analysis, a later layer)"
    ) in lines


def test_super_super_into_a_later_layer_fails(tree):
    # spectral::basis: super is spectral, super::super the crate root.
    planted = "fn planted(step: &dyn super::super::method::step::Step) {}\n"
    line = plant(tree, "src/spectral/basis.rs", planted)
    status, lines = check(tree)
    assert status == 1
    assert (
        f"src/spectral/basis.rs:{line}: module spectral::basis (layer bases) imports method::step "
        "(layer methods, a later layer)"
    ) in lines


def test_super_inside_an_inline_module_climbs_from_it(tree):
    # In spectral::inner, super is spectral and super::super the root: stepping::grid.
    line = plant(
        tree, "src/spectral/mod.rs", "mod inner {\n    use super::super::stepping::grid;\n}\n"
    )
    status, lines = check(tree)
    assert status == 1
    assert (
        f"src/spectral/mod.rs:{line + 1}: module spectral (layer bases) imports stepping::grid "
        "(layer stepping, a later layer)"
    ) in lines


def test_a_name_the_crate_root_reexports_is_followed(tree):
    # lib.rs: `pub use stepping::run::{Integrator, ...}`.
    line = plant(tree, "src/dimension.rs", "type Planted = crate::Integrator<(), (), ()>;\n")
    status, lines = check(tree)
    assert status == 1
    assert (
        f"src/dimension.rs:{line}: module dimension (layer leaves) imports stepping::run "
        "(layer stepping, a later layer)"
    ) in lines


def test_self_and_child_module_paths_resolve(tree):
    # linalg (linear algebra) names its child combination (leaves): allowed, downward.
    plant(
        tree, "src/linalg.rs", "use self::combination::Rows;\nfn f() { combination::planted(); }\n"
    )
    status, lines = check(tree)
    assert module_findings(lines) == [], lines
    # A child declared in a later layer than its parent is found through its bare name.
    (tree / "src/error").mkdir()
    (tree / "src/error/late.rs").write_text("pub fn f() {}\n", encoding="utf-8")
    line = plant(tree, "src/error.rs", "mod late;\nfn g() { late::f(); }\n")
    config = tree / ".ci/layers.toml"
    config.write_text(
        config.read_text(encoding="utf-8").replace(
            'paths = ["analysis/"]', 'paths = ["analysis/", "error/"]'
        ),
        encoding="utf-8",
    )
    status, lines = check(tree)
    assert status == 1
    assert (
        f"src/error.rs:{line + 1}: module error (layer leaves) imports error::late "
        "(layer analysis, a later layer)"
    ) in lines


# (c) comments, strings and tests


def test_imports_in_comments_and_strings_do_not_count(tree):
    plant(
        tree,
        "src/error.rs",
        "// use crate::stepping::run::Integrator;\n"
        "/// See [`crate::analysis::drift`] and [`super::stepping::run`].\n"
        "/* use crate::stepping::run::Integrator;\n"
        "   /* nested */ crate::analysis::verify::f() */\n"
        'const A: &str = "use crate::stepping::run::Integrator;";\n'
        'const B: &str = r#"crate::analysis::verify::f() "quoted" "#;\n'
        "const C: char = '\"'; // a quote in a character literal\n"
        "fn lifetimes<'a>(x: &'a str) -> &'a str { x }\n"
        "#[doc = \"crate::stepping::run\"]\n"
        "pub struct Documented;\n",
    )
    (tree / "src/scalar.rs").write_text(
        "//! Inner doc: [`crate::stepping::run::Integrator`].\n"
        + (tree / "src/scalar.rs").read_text(encoding="utf-8"),
        encoding="utf-8",
    )
    status, lines = check(tree)
    assert status != 1, lines
    assert module_findings(lines) == []
    assert any(line.endswith("no upward import") for line in lines)


def test_unit_tests_are_checked_only_when_asked(tree):
    line = plant(
        tree,
        "src/error.rs",
        "#[cfg(test)]\nmod planted_tests {\n    use crate::stepping::run::Integrator;\n}\n",
    )
    status, lines = check(tree)
    assert module_findings(lines) == [], lines
    status, lines = check(tree, "--tests")
    assert status == 1
    assert (
        f"src/error.rs:{line + 2}: module error (layer leaves) imports stepping::run "
        "(layer stepping, a later layer)"
    ) in lines


# (d) the declaration covers the tree


def test_undeclared_folder_is_an_error(tree):
    (tree / "src/experimental").mkdir()
    (tree / "src/experimental/mod.rs").write_text("pub fn f() {}\n", encoding="utf-8")
    status, lines = check(tree)
    assert status == 1
    assert any(line.startswith("src/experimental/mod.rs: in no layer of") for line in lines), lines


def test_declared_path_without_files_is_an_error(tree):
    shutil.rmtree(tree / "src/analysis")
    status, lines = check(tree)
    assert status == 1
    assert any("'analysis/' matches no file" in line for line in lines), lines


# The crate rule


def test_crate_depending_on_a_later_crate_fails(tree):
    manifest = tree / "Cargo.toml"
    manifest.write_text(
        manifest.read_text(encoding="utf-8").replace(
            "[dependencies]\n", "[dependencies]\nsvi-models.workspace = true\n", 1
        ),
        encoding="utf-8",
    )
    status, lines = check(tree)
    assert status == 3
    finding = "crate svi (level 1) depends on svi-models (level 2, a later level)"
    assert any(line.startswith("Cargo.toml:") and finding in line for line in lines), lines


def test_allowed_crate_dependency_passes(tree):
    config = tree / ".ci/layers.toml"
    config.write_text(
        config.read_text(encoding="utf-8").replace(
            "allow = []", 'allow = [["svi-python", "svi-cli"]]'
        ),
        encoding="utf-8",
    )
    status, lines = check(tree)
    assert status == 0, lines
    assert any(line.endswith("no upward dependency") for line in lines), lines
