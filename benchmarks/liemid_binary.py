"""Where the benchmark scripts find the liemid command: LIEMID_BIN or LIEMID, then
CARGO_TARGET_DIR/release/liemid, then target/release/liemid, then `liemid` on the PATH."""

from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def find_liemid() -> str | None:
    """The first executable candidate, or None (the caller prints its skip message)."""
    cands = [os.environ.get("LIEMID_BIN"), os.environ.get("LIEMID")]
    if os.environ.get("CARGO_TARGET_DIR"):
        cands.append(Path(os.environ["CARGO_TARGET_DIR"]) / "release" / "liemid")
    cands += [ROOT / "target" / "release" / "liemid", shutil.which("liemid")]
    for c in cands:
        if c and Path(c).is_file() and os.access(c, os.X_OK):
            return str(c)
    return None


def require_liemid(script: str) -> str:
    """The command's path, or the script's skip message and exit 0 (benchmarks skip,
    never fail, without what they compare)."""
    found = find_liemid()
    if found is None:
        print(f"{script}: skipped, no release liemid binary "
              "(cargo build --release -p liemid-cli, or set LIEMID_BIN)")
        sys.exit(0)
    return found
