"""Compare the results directories of two runs, or two trees of them, file for file.

    python tools/compare_results.py BEFORE AFTER

history.csv must match to the character; summary.json key for key, except what measures the machine
(wall and split times, peak memory, versions, mesh timing). Prints one line per run and, for what differs,
the largest relative difference per column or key. Exit 1 when anything differs.
"""

import math
import sys
from pathlib import Path

from fepen.io import results

#: summary keys that measure the machine or the software, not the physics
VOLATILE = {"wall_s", "time_split_s", "peak_memory_bytes", "versions", "mesh_s"}


def _flat(d, prefix=""):
    out = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _rel(a, b):
    try:
        a, b = float(a), float(b)
    except (TypeError, ValueError):
        return 0.0 if a == b else math.inf
    if a == b:
        return 0.0
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def compare(a: Path, b: Path) -> list[str]:
    diffs = []
    ha, hb = ([h, *rows] for h, rows in (results.read(d).history_text() for d in (a, b)))
    if ha[0] != hb[0]:
        diffs.append(f"history.csv columns differ: {set(ha[0]) ^ set(hb[0])}")
    elif len(ha) != len(hb):
        diffs.append(f"history.csv rows {len(ha) - 1} vs {len(hb) - 1}")
    else:
        worst = {}
        for ra, rb in zip(ha[1:], hb[1:]):
            for name, x, y in zip(ha[0], ra, rb):
                if x != y:
                    worst[name] = max(worst.get(name, 0.0), _rel(x, y))
        diffs += [f"history.csv {k}: largest relative difference {v:.3g}" for k, v in worst.items()]
    sa, sb = (_flat(results.read(d).summary()) for d in (a, b))
    for k in sorted(set(sa) | set(sb)):
        if k.split(".")[0] in VOLATILE or k.endswith("mesh_s"):
            continue
        if sa.get(k) != sb.get(k):
            rel = _rel(sa.get(k), sb.get(k))
            diffs.append(f"summary.json {k}: {sa.get(k)!r} vs {sb.get(k)!r} (relative {rel:.3g})")
    return diffs


def main(a, b) -> int:
    a, b = Path(a), Path(b)
    pairs = [(x, b if x == a else b / x.name) for x in results.finished_runs(a)]
    bad = 0
    for x, y in pairs:
        if not results.read(y).finished:
            print(f"{x.name}: missing in {b}")
            bad += 1
            continue
        diffs = compare(x, y)
        print(f"{x.name}: " + ("identical (history.csv, summary.json)" if not diffs else f"{len(diffs)} differences"))
        for d in diffs:
            print("    " + d)
        bad += bool(diffs)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
