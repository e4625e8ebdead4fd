"""The svi binary the tests compare the package with."""

import os
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def svi_binary():
    """The svi binary: $SVI_BIN, else the workspace's release build, else svi on PATH."""
    candidates = [os.environ.get("SVI_BIN")]
    target = os.environ.get("CARGO_TARGET_DIR", str(ROOT / "target"))
    candidates.append(str(Path(target) / "release" / "svi"))
    candidates.append(shutil.which("svi"))
    for candidate in candidates:
        if candidate and Path(candidate).is_file():
            return candidate
    pytest.skip("no svi binary (build it with cargo build --release -p svi-cli)")
