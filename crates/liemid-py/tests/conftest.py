"""Shared fixtures of the liemid Python tests."""

from __future__ import annotations

import os
import pathlib
import shutil

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def liemid_cli() -> str:
    """The `liemid` binary of this checkout (built by `cargo test` or `cargo build`)."""
    for candidate in (os.environ.get("LIEMID_BIN"), ROOT / "target/release/liemid", ROOT / "target/debug/liemid", shutil.which("liemid")):
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    pytest.fail("the liemid binary is not built: run `cargo build -p liemid-cli` (scripts/test does)")
