"""Every command the docs quote that finishes in seconds runs as quoted (issue 61). Before: docs/uncertainty.md's
`fepen envelope --set projectile.diameter=0.3 ...` exited 2 with a deformable mesh budget error, for a command
that runs nothing.

The commands are read from the fenced code blocks of README.md and docs/*.md (a `$ ` prompt, `\\` line joins and
`# comments` understood). A quick command is one that meshes and integrates nothing deformable: `fepen keys`,
`--version`, `fepen envelope`, and rigid runs and Table 1 validations. Each runs from the project root with its
`--out` moved into a scratch directory, and must exit 0. The rest (plastic runs, studies, make targets, mpirun)
are the long lanes' (tests/system, the demos' tests, make docs); `test_the_docs_quote_quick_commands` makes sure
the parser keeps finding the quick ones.
"""

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def quoted_commands() -> list[tuple[str, str]]:
    """(page, command) for every fepen command line in the pages' fenced code blocks."""
    found = []
    for page in PAGES:
        for block in re.findall(r"^```[a-z]*\n(.*?)^```", page.read_text(), re.S | re.M):
            for line in re.sub(r"\\\n\s*", " ", block).splitlines():
                line = line.strip().removeprefix("$ ")
                if not line.startswith((".venv/bin/fepen ", "fepen ")):
                    continue
                words = shlex.split(line, comments=True)
                if words:
                    found.append((page.name, " ".join(shlex.quote(w) for w in words)))
    return found


def quick(words: list[str]) -> bool:
    """Whether a quoted fepen command finishes in seconds (see the module's docstring)."""
    sub = words[1] if len(words) > 1 else ""
    rigid = "effects.fidelity=rigid" in words
    if sub in ("keys", "envelope", "--version"):
        return True
    if sub == "run":
        return rigid and "--resume" not in words and "effects.charge=true" not in words
    if sub == "validate":
        return rigid and "--samples" not in words
    return False


QUICK = [(page, cmd) for page, cmd in quoted_commands() if quick(shlex.split(cmd))]


def test_the_docs_quote_quick_commands():
    """The parser finds the pages' quick commands (the envelope line among them), so the test below runs them."""
    assert len(QUICK) >= 8, QUICK
    assert any("envelope" in c and "projectile.diameter=0.3" in c for _, c in QUICK), QUICK


@pytest.mark.parametrize("page,cmd", QUICK, ids=[f"{p}:{c[:60]}" for p, c in QUICK])
def test_a_quoted_quick_command_runs_as_quoted(page, cmd, tmp_path):
    words = shlex.split(cmd)
    args = words[1:]
    if "--out" in args:
        i = args.index("--out") + 1
        args[i] = str(tmp_path / Path(args[i]).name)
    elif args[0] in ("run", "validate"):
        args += ["--out", str(tmp_path / "out")]
    r = subprocess.run([sys.executable, "-m", "fepen", *args], cwd=ROOT, capture_output=True, text=True,
                       timeout=300)
    assert r.returncode == 0, f"{page}: `{cmd}` exited {r.returncode}:\n{r.stderr[-1500:]}"
    assert "Traceback" not in r.stderr
