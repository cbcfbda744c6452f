#!/usr/bin/env python3
"""Checks that keep the README and docs/ honest (ctest -L quick runs each).

  scripts/check_docs.py figures   every measured figure README.md states outside its headline
                                  table is the table's or appears verbatim in a docs/ page or a
                                  benchmarks/results/ file (the rule is in CONTRIBUTING.md)
  scripts/check_docs.py docs-figures
                                  every measured figure of a docs/ page appears verbatim in a file
                                  of benchmarks/results/ (a dated log or a CSV), or is a range a–b
                                  whose two ends appear there with the same unit
  scripts/check_docs.py links     every relative link of the Markdown pages points to a file that
                                  exists, and every #anchor into a Markdown page to a heading of it
  scripts/check_docs.py all       all three, and the headline table (scripts/headline_table.py --check)

A measured figure is a number (digits, optionally grouped by spaces in threes, a decimal part, a
range a–b) followed by a unit of time (s, ms, µs, min, h, seconds, minutes), memory (B, kB, MB,
GB, TB, KiB, MiB, GiB), rate (Hz, kHz, GF/s, GB/s, "… per second"), a share (%), a factor (×
right after the number), or an iteration count (iterations, its). Fenced code blocks, inline
code, HTML comments and link targets are not read, so a number that is not a measurement (a
buffer size, a timeout, a limit of a format) is written as code. Standard library only.
"""
import re
import sys
import unicodedata
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import headline_table  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent

# Pages being written at the same time as these checks; a link to one is accepted while it is
# missing (once a page exists its links and anchors are checked like any other).
EXPECTED_PAGES = {"docs/h2-factorization.md", "docs/distributed.md", "docs/reliability.md",
                  "docs/limits.md", "docs/stress.md", "docs/contact.md"}

# Pages whose links are checked, relative to the root (globs).
LINKED_PAGES = ["README.md", "CONTRIBUTING.md", "docs/*.md", "benchmarks/README.md",
                "benchmarks/results/*.md", "meshes/README.md", "examples/README.md"]

# Where a figure of the README may come from, besides its headline table.
FIGURE_SOURCES = ["docs/**/*.md", "benchmarks/results/**/*"]

# Where a figure of a docs/ page may come from: the dated logs and their CSVs only.
PAGE_FIGURE_SOURCES = ["benchmarks/results/**/*"]

# Pages whose figures docs-figures does not check, and why: none (the last, docs/contact.md,
# quotes its logs since 2026-11-29). Keep it empty.
FIGURE_EXEMPT_PAGES = {}

NUMBER = r"\d{1,3}(?: \d{3})+(?:\.\d+)?|\d+(?:\.\d+)?"
UNITS = ["seconds", "minutes", "iterations", "its", "min", "ms", "µs", "s", "h",
         "KiB", "MiB", "GiB", "kB", "MB", "GB", "TB", "B", "kHz", "Hz", "GF/s", "GB/s", "%"]
FIGURE = re.compile(
    r"(?<![\w.^²³−-])"                                   # not inside a name, a number or an exponent
    rf"(?:{NUMBER})(?:\s?[–-]\s?(?:{NUMBER}))?"          # a number or a range
    r"(?:"
    r"\s?(?:" + "|".join(re.escape(u) for u in UNITS) + r")(?![\w/])"   # with a unit
    r"|×"                                                # a factor (a × with a space is a product)
    r"|(?:\s[A-Za-z-]+){0,3}\sper\ssecond\b"             # or a rate in words
    r")")


def normalise(text):
    """One ASCII space for any run of white space (thin and no-break spaces included)."""
    return re.sub(r"\s+", " ", text.replace("\u202f", " ").replace("\u00a0", " ").replace("\u2009", " "))


def prose(text):
    """The text without fenced code, inline code, HTML comments and link targets."""
    text = re.sub(r"^(```|~~~).*?^\1[^\n]*$", " ", text, flags=re.S | re.M)
    text = re.sub(r"<!--.*?-->", " ", text, flags=re.S)
    text = re.sub(r"`(?:[^`\n]|\n(?![ \t]*\n))*`", " ", text)   # inline code, across a line break too
    text = re.sub(r"\]\([^)\s]*\)", "]", text)
    return text


def figures(text):
    return [normalise(m.group(0)) for m in FIGURE.finditer(normalise(prose(text)))]


def occurs(figure, corpus):
    """figure in corpus as a whole figure: not the tail of a longer number or word."""
    pattern = r"(?<![\w.])" + re.escape(figure).replace(r"\ ", r"\s?")
    if figure[-1].isalnum():
        pattern += r"(?![\w])"
    return re.search(pattern, corpus) is not None


def source_texts(root, patterns=None):
    for pattern in patterns or FIGURE_SOURCES:
        for path in sorted(root.glob(pattern)):
            if path.is_file():
                try:
                    yield path, normalise(path.read_text(encoding="utf-8"))
                except UnicodeDecodeError:
                    continue


def check_figures(root):
    readme = root / "README.md"
    head, table, tail = headline_table.split_readme(readme.read_text(encoding="utf-8"), "README.md")
    corpus = normalise(table) + "\n" + "\n".join(text for _, text in source_texts(root))
    stated = figures(head + tail)
    missing = sorted({f for f in stated if not occurs(f, corpus)})
    for f in missing:
        print(f"README.md: the figure '{f}' is neither the headline table's nor in docs/ or "
              "benchmarks/results/ (CONTRIBUTING.md, 'Figures and the headline table')")
    if not missing:
        print(f"README.md: {len(stated)} figures outside the headline table, each found in the "
              "table, docs/ or benchmarks/results/")
    return not missing


RANGE = re.compile(rf"^({NUMBER})\s?[–-]\s?({NUMBER})(\s?\S.*)$")


def range_ends_occur(figure, corpus):
    """A range a–b U whose ends a U and b U both appear in the corpus (each a measurement)."""
    m = RANGE.match(figure)
    if not m:
        return False
    low, high, unit = m.groups()
    if "per second" in unit:
        return False
    return occurs(low + unit, corpus) and occurs(high + unit, corpus)


def check_page_figures(root):
    """Every measured figure of docs/*.md has a dated log or CSV of benchmarks/results/ behind it."""
    corpus = "\n".join(text for _, text in source_texts(root, PAGE_FIGURE_SOURCES))
    missing = checked = 0
    for page in sorted((root / "docs").glob("*.md")):
        name = page.relative_to(root).as_posix()
        if name in FIGURE_EXEMPT_PAGES:
            print(f"{name}: figures not checked ({FIGURE_EXEMPT_PAGES[name]})")
            continue
        stated = sorted(set(figures(page.read_text(encoding="utf-8"))))
        checked += len(stated)
        for f in stated:
            if not occurs(f, corpus) and not range_ends_occur(f, corpus):
                missing += 1
                print(f"{name}: the figure '{f}' appears in no file of benchmarks/results/ (quote its log "
                      "verbatim, or write a figure that is no measurement as code: CONTRIBUTING.md, "
                      "'Figures and the headline table')")
    if not missing:
        print(f"docs/: {checked} figures, each found in benchmarks/results/ (or a range whose ends are)")
    return not missing


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces to hyphens."""
    heading = re.sub(r"`([^`]*)`", r"\1", heading)
    heading = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading).strip().lower()
    kept = [c for c in heading if c in " -_" or unicodedata.category(c)[0] in "LM"
            or unicodedata.category(c) == "Nd"]
    return "".join(kept).replace(" ", "-")


def anchors(path):
    text = re.sub(r"^(```|~~~).*?^\1[^\n]*$", " ", path.read_text(encoding="utf-8"), flags=re.S | re.M)
    seen, result = {}, set()
    for m in re.finditer(r"^#{1,6}\s+(.*?)\s*#*\s*$", text, flags=re.M):
        base = slug(m.group(1))
        n = seen.get(base, 0)
        seen[base] = n + 1
        result.add(base if n == 0 else f"{base}-{n}")
    result |= set(re.findall(r'<a\s+(?:name|id)="([^"]+)"', text))
    return result


def links(text):
    text = re.sub(r"^(```|~~~).*?^\1[^\n]*$", " ", text, flags=re.S | re.M)
    text = re.sub(r"`[^`\n]*`", " ", text)
    return re.findall(r"\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", text)


def check_link(page, target, root):
    if re.match(r"^[a-z][a-z0-9+.-]*:", target):        # http:, https:, mailto:
        return None
    path_part, _, anchor = target.partition("#")
    dest = (page.parent / path_part).resolve() if path_part else page.resolve()
    try:
        rel = dest.relative_to(root.resolve()).as_posix()
    except ValueError:
        return f"{target}: outside the repository"
    if not dest.exists():
        return None if rel in EXPECTED_PAGES else f"{target}: no such file"
    if anchor and dest.suffix == ".md" and anchor not in anchors(dest):
        return f"{target}: no heading '#{anchor}' in {rel}"
    return None


def check_links(root):
    bad = checked = 0
    for pattern in LINKED_PAGES:
        for page in sorted(root.glob(pattern)):
            for target in links(page.read_text(encoding="utf-8")):
                checked += 1
                problem = check_link(page, target, root)
                if problem:
                    bad += 1
                    print(f"{page.relative_to(root).as_posix()}: broken link {problem}")
    if not bad:
        print(f"{checked} links checked, all point to existing files and headings")
    return not bad


def main(argv):
    what = argv[1] if len(argv) > 1 else "all"
    root = Path(argv[2]).resolve() if len(argv) > 2 else ROOT
    if what not in ("figures", "docs-figures", "links", "all"):
        print(__doc__)
        return 2
    ok = True
    if what in ("figures", "all"):
        ok &= check_figures(root)
    if what in ("docs-figures", "all"):
        ok &= check_page_figures(root)
    if what in ("links", "all"):
        ok &= check_links(root)
    if what == "all":
        ok &= headline_table.main(["--root", str(root), "--check"]) == 0
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv))
