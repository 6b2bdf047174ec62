"""Shared fixtures: the repository root, the `nlvid` command-line binary
(NLVID_BIN, else target/{release,debug}/nlvid) and a runner returning its
JSON output or its error message, so each test compares the Python entry
point with the CLI on the same inputs."""

import json
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def root():
    return ROOT


def _find_bin():
    env = os.environ.get("NLVID_BIN")
    if env:
        if not Path(env).is_file():
            pytest.fail(f"NLVID_BIN={env} does not exist")
        return env
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    for profile in ("release", "debug"):
        p = target / profile / "nlvid"
        if p.is_file():
            return str(p)
    pytest.fail(
        "no nlvid binary: build it (cargo build -p nlvid) or set NLVID_BIN; "
        "scripts/test-python.sh does both"
    )


@pytest.fixture(scope="session")
def nlvid_bin():
    return _find_bin()


class Cli:
    def __init__(self, binary):
        self.binary = binary

    def run(self, *args, cwd=None):
        """Runs `nlvid --json ARGS`; returns the parsed stdout."""
        p = subprocess.run(
            [self.binary, "--json", *map(str, args)],
            capture_output=True,
            text=True,
            cwd=cwd,
            env={**os.environ, "CI": "1"},
        )
        if p.returncode != 0:
            raise AssertionError(f"nlvid {' '.join(map(str, args))} failed:\n{p.stderr}")
        return json.loads(p.stdout)

    def error(self, *args, cwd=None):
        """Runs `nlvid ARGS` expecting failure; returns the message after `error: `."""
        p = subprocess.run(
            [self.binary, *map(str, args)], capture_output=True, text=True, cwd=cwd
        )
        assert p.returncode != 0, f"nlvid {args} unexpectedly succeeded"
        lines = [l for l in p.stderr.splitlines() if l.startswith("error: ")]
        assert lines, p.stderr
        return lines[-1][len("error: "):]


@pytest.fixture(scope="session")
def cli(nlvid_bin):
    return Cli(nlvid_bin)


def write_csv(path, header, columns):
    """CSV with `header` and float columns written with repr (shortest
    round trip), so the CLI reads exactly the doubles Python holds."""
    with open(path, "w") as f:
        f.write(",".join(header) + "\n")
        for row in zip(*columns):
            f.write(",".join(repr(float(v)) for v in row) + "\n")
