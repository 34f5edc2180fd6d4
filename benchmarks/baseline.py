"""The source trees a benchmark measures side by side (its ratios in one run): this checkout, and a git worktree
of a baseline revision, made for the run and removed after it. Imported by benchmarks/latency.py and
benchmarks/rigid_throughput.py (run as scripts from the project root: this folder is first on their path).

    with baseline.trees(rev) as trees:      # [(this tree, "this tree"), (its worktree, "baseline REV")]
        ...
"""

from __future__ import annotations

import subprocess
import tempfile
from contextlib import contextmanager
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


@contextmanager
def trees(rev: str | None):
    """This tree and, given a revision, a detached worktree of it (removed on the way out).

    Args:
        rev: a git revision, or None (this tree alone).

    Returns:
        (on entering) a list of (source tree, label) pairs.
    """
    out = [(ROOT, "this tree")]
    worktree = None
    if rev:
        worktree = Path(tempfile.mkdtemp(prefix="fepen-baseline-")) / "tree"
        subprocess.run(["git", "worktree", "add", "--detach", str(worktree), rev], cwd=ROOT, check=True,
                       capture_output=True)
        out.append((worktree, f"baseline {rev}"))
    try:
        yield out
    finally:
        if worktree is not None:
            subprocess.run(["git", "worktree", "remove", "--force", str(worktree)], cwd=ROOT, capture_output=True)
