"""tools/bootstrap.sh on an installed machine: it checks what is installed without racing and never calls apt.

The script once piped ``ldconfig -p`` into ``grep -q`` under ``pipefail``: grep exited at its first match,
ldconfig died of SIGPIPE, and 20 of 300 calls under load ran apt again (failing for a user without sudo or
network). Here apt-get and sudo are replaced by stubs that record any call and fail; the script runs several
times at once to load the machine as make's parallel callers would.
"""

import os
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "tools" / "bootstrap.sh"
RUNS, AT_ONCE = 8, 4


def _installed_machine() -> str | None:
    """Why this machine cannot show it (None: it can): the script's stamp current, dpkg at hand."""
    if shutil.which("dpkg-query") is None:
        return "not a Debian machine (no dpkg-query)"
    stamp = ROOT / ".venv" / ".fepen-stamp"
    if not stamp.is_file():
        return "no .venv made by the set-up"
    probe = subprocess.run(["bash", "-c", "cat pyproject.toml tools/constraints.txt | sha256sum | cut -c1-16"],
                           cwd=ROOT, capture_output=True, text=True)
    if probe.stdout.strip() != stamp.read_text().strip():
        return "pyproject.toml changed since the set-up (the script would reinstall fepen into .venv)"
    return None


def test_an_installed_machine_never_calls_apt(tmp_path):
    why = _installed_machine()
    if why:
        pytest.skip(why)
    calls = tmp_path / "calls"
    for name in ("apt-get", "sudo", "apt"):
        stub = tmp_path / name
        stub.write_text(f'#!/bin/sh\necho "{name} $*" >> {calls}\nexit 1\n')
        stub.chmod(0o755)
    env = {**os.environ, "PATH": f"{tmp_path}:{os.environ['PATH']}"}

    def once(_):
        return subprocess.run(["bash", str(SCRIPT)], env=env, capture_output=True, text=True, timeout=120)

    with ThreadPoolExecutor(AT_ONCE) as pool:
        results = list(pool.map(once, range(RUNS)))
    assert all(r.returncode == 0 for r in results), [r.stderr for r in results if r.returncode][:1]
    assert not calls.exists(), calls.read_text()
    assert not any("[bootstrap]" in r.stdout for r in results), results[0].stdout  # nothing to install: silent
