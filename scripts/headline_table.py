#!/usr/bin/env python3
"""The README's headline table, generated from a committed benchmark CSV.

The table is the H² path at the driver's defaults (H² at 1e-5, GMRES right-preconditioned by
PC h2 at 2e-3) against dense assembly + LU, one row per mesh of the sweep that
benchmarks/bench_h2_factor.py wrote to benchmarks/results/h2_factor_sweep.csv. It sits in
README.md between the two marker comments below, so it can only change through this script:

  scripts/headline_table.py            print the table
  scripts/headline_table.py --write    write it into README.md between the markers
  scripts/headline_table.py --check    exit 1 when README.md's table differs (ctest docs_headline_table)

Standard library only.
"""
import argparse
import csv
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CSV = Path("benchmarks/results/h2_factor_sweep.csv")
README = Path("README.md")
BEGIN = "<!-- headline-table:begin (scripts/headline_table.py --write; do not edit by hand) -->"
END = "<!-- headline-table:end -->"

FAMILIES = {"sphere": "sphere", "disk": "disk organ"}


def family_name(row):
    """'sphere', 'disk organ', or the mesh's stem for a --mesh family ('cardioid')."""
    family = row["family"]
    if family in FAMILIES:
        return FAMILIES[family]
    return row["mesh"].split("_T")[0].split(".")[0]


def thousands(n):
    """9969 -> '9 969' (a space between groups of three digits, as in the docs)."""
    digits = str(int(n))
    groups = []
    while digits:
        groups.insert(0, digits[-3:])
        digits = digits[:-3]
    return " ".join(groups)


def seconds(x):
    """Two decimals below 1 s, one from there on."""
    return f"{x:.2f}" if x < 1 else f"{x:.1f}"


def number(value):
    x = float(value)
    return None if math.isnan(x) else x


def table_row(row):
    compress, factor, solve = (float(row[k]) for k in ("compress_s", "factor_s", "solve_s"))
    total = compress + factor + solve
    assembly, lu = number(row["dense_assembly_s"]), number(row["dense_lu_s"])
    dense = speedup = "–"
    if assembly is not None and lu is not None:
        dense = f"{seconds(assembly + lu)} ({seconds(assembly)} + {seconds(lu)})"
        speedup = f"{(assembly + lu) / total:.1f}×"
    memory = float(row["h2_mb"]) + float(row["factor_mb"])
    cells = [family_name(row), thousands(row["N"]), seconds(compress), seconds(factor),
             f"{row['iterations']} / {seconds(solve)}", seconds(total), dense, speedup,
             thousands(round(memory))]
    return "| " + " | ".join(cells) + " |"


def table(csv_path):
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise SystemExit(f"headline_table.py: error: {csv_path}: no rows")
    lines = ["| mesh | unknowns | H² compress s | PC h2 factor s | GMRES its / s | H² total s "
             "| dense s (assembly + LU) | speed-up | H² + factors MB |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    lines += [table_row(r) for r in rows]
    # Blank lines around the table keep it a block of its own between the marker comments.
    return "\n" + "\n".join(lines) + "\n\n"


def split_readme(text, readme):
    """(before, table, after) around the markers; the markers stay in before/after."""
    try:
        head, rest = text.split(BEGIN + "\n", 1)
        body, tail = rest.split(END, 1)
    except ValueError:
        raise SystemExit(f"headline_table.py: error: {readme}: the markers {BEGIN!r} and {END!r} "
                         "are missing or out of order")
    return head + BEGIN + "\n", body, END + tail


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--root", type=Path, default=ROOT, help="repository root (default: this script's)")
    parser.add_argument("--csv", type=Path, default=CSV, help="sweep CSV, relative to the root")
    parser.add_argument("--readme", type=Path, default=README, help="README, relative to the root")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--write", action="store_true", help="write the table into the README")
    mode.add_argument("--check", action="store_true", help="exit 1 when the README's table differs")
    args = parser.parse_args(argv)

    generated = table(args.root / args.csv)
    if not (args.write or args.check):
        sys.stdout.write(generated)
        return 0
    readme = args.root / args.readme
    head, body, tail = split_readme(readme.read_text(encoding="utf-8"), args.readme)
    if args.write:
        readme.write_text(head + generated + tail, encoding="utf-8")
        return 0
    if body != generated:
        sys.stderr.write(f"headline_table.py: error: {args.readme}: the headline table differs from "
                         f"what {args.csv} gives; run scripts/headline_table.py --write\n")
        return 1
    print(f"{args.readme}: headline table matches {args.csv} ({generated.count(chr(10)) - 4} rows)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
