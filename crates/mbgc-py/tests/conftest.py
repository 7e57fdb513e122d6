"""Shared fixtures: the repository's root, and the `mbgc` command to compare against.

The tests compare with the numbers the command line gives for the same input. When MBGC_BIN
names an `mbgc` binary (tests/python_package.rs passes the one `cargo test` built), they run it
and compare with its output; otherwise they compare with the output recorded from it."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any, List, Optional

import pytest

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture
def root(monkeypatch: pytest.MonkeyPatch) -> Path:
    """Runs the test in the repository's root, where the README's commands run."""
    monkeypatch.chdir(ROOT)
    return ROOT


class Cli:
    """The `mbgc` binary of MBGC_BIN, run in the repository's root."""

    def __init__(self, path: str) -> None:
        self.path = path

    def run(self, *args: str, cwd: Optional[Path] = None) -> subprocess.CompletedProcess:  # type: ignore[type-arg]
        return subprocess.run(
            [self.path, *args], cwd=cwd or ROOT, capture_output=True, text=True, check=False
        )

    def ok(self, *args: str, cwd: Optional[Path] = None) -> str:
        out = self.run(*args, cwd=cwd)
        assert out.returncode == 0, f"mbgc {' '.join(args)}: {out.stderr}"
        return out.stdout

    def json(self, *args: str) -> Any:
        return json.loads(self.ok(*args))

    def error(self, *args: str) -> str:
        """The message of a failing command, without the `error: ` it prints before it."""
        out = self.run(*args)
        assert out.returncode != 0, f"mbgc {' '.join(args)} should fail"
        lines: List[str] = out.stderr.strip().splitlines()
        return lines[-1].removeprefix("error: ")


@pytest.fixture
def cli() -> Optional[Cli]:
    """The command line to compare with, or None (then the recorded numbers are the reference)."""
    path = os.environ.get("MBGC_BIN")
    return Cli(path) if path else None
