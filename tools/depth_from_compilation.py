"""Convert the public depth-of-penetration compilation into fepen's shipped depth sets (fepen/data/depth/*.csv).

The compilation is ``Data.xlsx`` of the public GitHub repository
DavidZyh-0319/Concrete-Penetration-Failure-Response-Dataset (1012 rows from 89 references). Its column
"Number" numbers the data rows 1, 2, ... after the header (sheet row = Number + 1); ``shot = zyh#N`` and
``compilation_row = N`` are that number. Every set below is a contiguous range of it, checked here against
the compilation's own reference column, so that a changed compilation fails loudly instead of shipping the
wrong shots.

Only the depth's unit changes (mm -> m). Strengths are kept as the compilation gives them; each set says
whether they are cylinder or cube strengths (``strength_basis``, decided per set from its original
publication, with the evidence in fepen/data/depth/SOURCES.md). Numbers are written with 10 significant
digits, which drops the spreadsheet's binary noise (88.90000000000001 -> 88.9) and nothing else.

Standard library only:

    git --git-dir=MIRROR show 3463a15d33f619fd3677e362c449ff1576b4b937:Data.xlsx > /tmp/Data.xlsx
    python tools/depth_from_compilation.py /tmp/Data.xlsx fepen/data/depth --commit 3463a15d33f6...
"""

from __future__ import annotations

import argparse
import csv
import re
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

REPO = "DavidZyh-0319/Concrete-Penetration-Failure-Response-Dataset"
COMMIT = "3463a15d33f619fd3677e362c449ff1576b4b937"
NS = "{http://schemas.openxmlformats.org/spreadsheetml/2006/main}"

#: the compilation's columns this script reads (its header text -> our name)
HEADER = {
    "Number": "number", "Article": "article", "Concrete Type": "concrete",
    "Projectile Mass (kg)": "m_kg", "Projectile Diameter (mm)": "d_mm", "Projectile Length (mm)": "L_mm",
    "Nose CRH Ratio (CRH)": "crh", "Concrete Density (kg/m^3)": "rho_kgm3",
    "Concrete Compressive Strength (MPa)": "fc_mpa", "Concrete Target Thickness (m)": "T_m",
    "Impact Velocity (m/s)": "v_ms", "Penetration Depth (mm)": "depth_mm",
}

SANDIA_HELD = "very probably one of the 57 Sandia shots held aside to judge fepen (docs/validation-depth.md)"

#: name -> (first row, last row, text the compilation's reference must start with, source, strength_basis,
#: note for every row of the set)
SETS = {
    "feng2018": (24, 38, "Feng, J., Song, M., Sun, W., et al., 2018.",
                 "Feng, Song, Sun et al. 2018, Int J Impact Eng 122:305", "cube",
                 "eroded or not is not recorded (841-1872 m/s: almost surely eroded)"),
    "forrestal1994_d26.9mm": (39, 55, "Forrestal, M.J., Frew, D.J., Hickerson, J.P., et al., 2003.",
                              "Forrestal, Altman, Cargile, Hanchak 1994, Int J Impact Eng 15:395", "cylinder",
                              "the compilation cites Forrestal, Frew, Hickerson et al. 2003, Int J Impact Eng "
                              "28:479; attributed to Forrestal et al. 1994 after a worked example of its shot 14 "
                              "(docs/validation-depth.md)"),
    "forrestal1994_d76.2mm": (56, 70, "Forrestal, M., Altman, B., Cargile, J., et al., 1994.",
                              "Forrestal, Altman, Cargile et al. 1994, Int J Impact Eng 15:395 (as the compilation "
                              "cites it; attribution unsure)", "cylinder",
                              "attribution unsure: the compilation's tag, not checked against the paper"),
    "frew2006": (71, 93, "Frew, D.J., Forrestal, M.J., Cargile, J.D., 2006.",
                 "Frew, Forrestal, Cargile 2006, Int J Impact Eng 32:1584", "cylinder", ""),
    "geng2020": (118, 129, "Geng, H., Lu, H., Sun, S., et al., 2020.",
                 "Geng, Lu, Sun et al. 2020, Shock Vib 2020:2137945", "cube", ""),
    "gu2004": (168, 173, "Gu, X.H., Wang, X.M., Chen, H.W., et al., 2004.",
               "Gu, Wang, Chen et al. 2004, J Exp Mech 2004(1):103", "cube", ""),
    "forrestal1996": (236, 276, "Forrestal, M.J., Frew, D.J., Hanchak, S.J., et al., 1996.",
                      "Forrestal, Frew, Hanchak, Brar 1996, Int J Impact Eng 18:465", "cylinder", SANDIA_HELD),
    "oneil1999": (541, 548, "O'Neil, E.F., Neeley, B.D., Cargile, J.D., 1999.",
                  "O'Neil, Neeley, Cargile 1999, Shock Vib 6:237", "cylinder", ""),
    "sun2010": (628, 638, "Sun, C.J., Lu, Y.G., Zhang, F.J., et al., 2010.",
                "Sun, Lu, Zhang et al. 2010, Explos Shock Waves 30(3):269", "cube", ""),
    "wu2020": (693, 699, "Wu, B., Ren, H.Q., Chen, L., et al., 2020.",
               "Wu, Ren, Chen et al. 2020, Prot Eng 42(2):1", "cube", ""),
    "yao2025": (886, 891, "Yao, Z., Qin, F., Li, J., et al., 2025.",
                "Yao, Qin, Li et al. 2025, Int J Impact Eng 195:105140", "cube", ""),
    "zhai2021": (892, 893, "Zhai, Y.X., Wu, H., Fang, Q., 2021.",
                 "Zhai, Wu, Fang 2021, Int J Impact Eng 154:103888", "cube",
                 "the paper's normal-strength concrete (NSC) shots only; its two UHPC shots, zyh#894-895, "
                 "are not in this set"),
}

#: further notes on single rows: (set, row) -> note
ROW_NOTES = {
    ("forrestal1996", 261): "half as deep as zyh#253 (19.5 MPa, 1356 m/s): probably a failed projectile "
                            "(docs/validation-depth.md)",
}

COLUMNS = ("shot", "d_mm", "m_kg", "crh", "L_mm", "v_ms", "fc_mpa", "rho_kgm3", "depth_m", "obliquity_deg",
           "attack_deg", "strength_basis", "source", "compilation_row", "notes")


def read_compilation(path) -> dict[int, dict]:
    """The compilation's data rows by their Number (dicts keyed by HEADER's names; text as stored)."""
    sheet = ET.fromstring(zipfile.ZipFile(path).read("xl/worksheets/sheet1.xml"))
    rows = []
    for r in sheet.iter(f"{NS}row"):
        cells = {}
        for c in r.iter(f"{NS}c"):
            col = re.match(r"[A-Z]+", c.get("r")).group()
            if c.get("t") == "s":
                raise SystemExit(f"{path}: shared strings are not read by this script")
            if c.get("t") == "inlineStr":
                cells[col] = "".join(t.text or "" for t in c.iter(f"{NS}t"))
            else:
                v = c.find(f"{NS}v")
                cells[col] = v.text if v is not None else None
        rows.append((int(r.get("r")), cells))
    (_, head), data = rows[0], rows[1:]
    cols = {HEADER[text]: col for col, text in head.items() if text in HEADER}
    missing = set(HEADER.values()) - set(cols)
    if missing:
        raise SystemExit(f"{path}: columns not found: {', '.join(sorted(missing))}")
    out = {}
    for sheet_row, cells in data:
        rec = {name: (cells.get(col) or "").strip() for name, col in cols.items()}
        n = int(float(rec["number"]))
        if n != sheet_row - 1:
            raise SystemExit(f"{path}: Number {n} on sheet row {sheet_row} (expected Number = sheet row - 1)")
        out[n] = rec
    return out


def num(text: str) -> float:
    return float(text)


def fmt(x: float) -> str:
    """10 significant digits: the spreadsheet's binary noise goes, nothing measured does."""
    return f"{x:.10g}"


def _close(a: str, b: str, rel: float) -> bool:
    return abs(num(a) / num(b) - 1) <= rel


def duplicates(n: int, comp: dict[int, dict]) -> list[str]:
    """Rows of the compilation from another reference that may be the same shot: same calibre and CRH,
    striking speed within 1 m/s, mass within 5 %, strength and depth within 15 %."""
    r = comp[n]
    found = []
    for k, o in comp.items():
        if k == n or o["article"] == r["article"]:
            continue
        try:
            same = (num(o["d_mm"]) == num(r["d_mm"]) and num(o["crh"]) == num(r["crh"])
                    and abs(num(o["v_ms"]) - num(r["v_ms"])) <= 1.0 and _close(o["m_kg"], r["m_kg"], 0.05)
                    and _close(o["fc_mpa"], r["fc_mpa"], 0.15) and _close(o["depth_mm"], r["depth_mm"], 0.15))
        except (ValueError, ZeroDivisionError):  # a missing or malformed number cannot be compared
            continue
        if same:
            cite = re.sub(r"\s+", " ", o["article"]).split(", 1")[0].split(", 2")[0]
            year = re.search(r"(19|20)\d\d", o["article"])
            found.append(f"possibly the same shot as zyh#{k} ({cite} {year.group() if year else ''}): "
                         f"{fmt(num(o['m_kg']))} kg, {fmt(num(o['fc_mpa']))} MPa, {fmt(num(o['v_ms']))} m/s, "
                         f"{fmt(num(o['depth_mm']))} mm")
    return found


def convert(comp: dict[int, dict], commit: str) -> dict[str, list[dict]]:
    """The shipped sets' rows, checked against the compilation's reference column."""
    sets = {}
    for name, (first, last, ref, source, basis, set_note) in SETS.items():
        rows = []
        for n in range(first, last + 1):
            r = comp[n]
            article = re.sub(r"\s+", " ", r["article"]).replace("\u2019", "'")
            if not article.startswith(ref):
                raise SystemExit(f"{name}: zyh#{n} cites {article[:80]!r}, not {ref!r}: the compilation changed")
            depth_mm, thick = num(r["depth_mm"]), num(r["T_m"])
            notes = [f"{REPO}@{commit[:7]} Data.xlsx Number {n}",
                     f"concrete '{r['concrete']}', target {fmt(thick)} m thick"]
            if depth_mm / 1e3 > thick:
                notes.append("depth exceeds the stated target thickness")
            if name == "frew2006" and num(r["d_mm"]) < 76:
                notes.append("rod shot: probably Frew et al. 1998, Int J Impact Eng 21:489; " + SANDIA_HELD)
            notes += [set_note] if set_note else []
            notes += [ROW_NOTES[(name, n)]] if (name, n) in ROW_NOTES else []
            notes += duplicates(n, comp)
            rows.append({"shot": f"zyh#{n}", "d_mm": fmt(num(r["d_mm"])), "m_kg": fmt(num(r["m_kg"])),
                         "crh": fmt(num(r["crh"])), "L_mm": fmt(num(r["L_mm"])), "v_ms": fmt(num(r["v_ms"])),
                         "fc_mpa": fmt(num(r["fc_mpa"])), "rho_kgm3": fmt(num(r["rho_kgm3"])),
                         "depth_m": fmt(depth_mm / 1e3), "obliquity_deg": "0", "attack_deg": "0",
                         "strength_basis": basis, "source": source, "compilation_row": str(n),
                         "notes": "; ".join(notes)})
        sets[name] = rows
    return sets


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("xlsx", help="the compilation's Data.xlsx")
    ap.add_argument("out", help="folder for the CSV files (fepen/data/depth)")
    ap.add_argument("--commit", default=COMMIT, help="the compilation's commit the file was taken from")
    args = ap.parse_args(argv)
    comp = read_compilation(args.xlsx)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    total = 0
    for name, rows in convert(comp, args.commit).items():
        with open(out / f"{name}.csv", "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=COLUMNS, lineterminator="\n")
            w.writeheader()
            w.writerows(rows)
        total += len(rows)
        print(f"{name}: {len(rows)} shots (zyh#{rows[0]['compilation_row']}-{rows[-1]['compilation_row']}), "
              f"{rows[0]['strength_basis']}")
    print(f"{total} shots from {len(comp)} compilation rows -> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
