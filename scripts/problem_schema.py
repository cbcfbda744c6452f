#!/usr/bin/env python3
"""Check problem files against the problem file's JSON Schema (docs/problem-file.schema.json).

  scripts/problem_schema.py FILE.json...      one line per fault: FILE: <JSON path>: <what>

Problem files are JSON with comments: `//` to the end of the line and `/* ... */` anywhere white
space may stand, outside strings, as the driver's parser reads them (src/problem/problem_file.cpp,
nlohmann::json with ignore_comments). They are blanked out before the JSON is parsed; as in the
driver, a duplicate key and a number that overflows a double are errors. The schema covers the
file's structure, types and ranges; what needs the mesh (a selection that is empty, a region
that does not exist, row counts) is checked by the driver only. Needs python3-jsonschema
(scripts/install_deps.sh); run it with /usr/bin/python3.
"""
import json
import math
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
SCHEMA = ROOT / "docs" / "problem-file.schema.json"


class ProblemFileError(ValueError):
    """A file that is not JSON with comments as the driver reads it."""


def _skip_comment(text, i):
    """The index after the comment that starts at text[i] == '/'."""
    if text.startswith("//", i):
        end = text.find("\n", i)
        return len(text) if end < 0 else end
    if text.startswith("/*", i):
        end = text.find("*/", i + 2)
        if end < 0:
            raise ProblemFileError(f"unterminated /* comment (byte {i + 1})")
        return end + 2
    raise ProblemFileError(f"invalid comment: expected '/' or '*' after '/' (byte {i + 1})")


def strip_comments(text):
    """The text with its comments blanked (line breaks kept, so JSON's line numbers stay)."""
    out, i, in_string = [], 0, False
    while i < len(text):
        c = text[i]
        if in_string:
            out.append(c)
            if c == "\\" and i + 1 < len(text):
                out.append(text[i + 1])
                i += 1
            elif c == '"':
                in_string = False
            i += 1
        elif c == '"':
            in_string = True
            out.append(c)
            i += 1
        elif c == "/":
            end = _skip_comment(text, i)
            out.append("".join(ch if ch == "\n" else " " for ch in text[i:end]))
            i = end
        else:
            out.append(c)
            i += 1
    return "".join(out)


def _no_duplicates(pairs):
    keys = set()
    for key, _ in pairs:
        if key in keys:
            raise ProblemFileError(f"duplicate key '{key}'")
        keys.add(key)
    return dict(pairs)


def _finite(literal):
    value = float(literal)
    if not math.isfinite(value):
        raise ProblemFileError(f"number {literal} is not finite")
    return value


def loads(text):
    """A problem file's text (JSON with comments) as Python objects."""
    try:
        return json.loads(strip_comments(text), object_pairs_hook=_no_duplicates, parse_float=_finite)
    except json.JSONDecodeError as e:
        raise ProblemFileError(f"malformed JSON: {e}") from None


def validator():
    import jsonschema  # noqa: PLC0415 (a clear message below when it is missing)
    schema = json.loads(SCHEMA.read_text(encoding="utf-8"))
    jsonschema.Draft7Validator.check_schema(schema)
    return jsonschema.Draft7Validator(schema)


def faults(problem, check=None):
    """Every schema violation of a parsed problem as 'path: message', deepest first."""
    from jsonschema.exceptions import best_match  # noqa: PLC0415
    check = check or validator()
    errors = [best_match([e]) for e in check.iter_errors(problem)]  # into oneOf's alternatives: the likeliest fault
    errors.sort(key=lambda e: (-len(e.absolute_path), json_path(e.absolute_path)))
    return [f"{json_path(e.absolute_path) or '(top level)'}: {e.message}" for e in errors]


def json_path(parts):
    """The driver's way of naming a place: boundary[2].where.box."""
    return "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in parts).lstrip(".")


def check_file(path, check=None):
    """The faults of one file (empty: valid)."""
    try:
        return faults(loads(Path(path).read_text(encoding="utf-8")), check)
    except (OSError, UnicodeDecodeError, ProblemFileError) as e:
        return [str(e)]


def main(argv):
    if len(argv) < 2 or argv[1] in ("-h", "--help"):
        print(__doc__)
        return 2
    try:
        check = validator()
    except ImportError:
        print("problem_schema.py: error: python3-jsonschema is missing (scripts/install_deps.sh)", file=sys.stderr)
        return 2
    bad = 0
    for path in argv[1:]:
        for fault in check_file(path, check):
            print(f"{path}: {fault}")
            bad += 1
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
