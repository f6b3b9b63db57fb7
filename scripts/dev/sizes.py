#!/usr/bin/env python3
"""Source files and functions of a size a reader can hold in mind.

  sizes.py [SOURCE_DIR]          (ctest code_sizes; exit 1 naming file:line on a finding)
  sizes.py --list [SOURCE_DIR]   every file and function over the limits, largest first

Limits: a .cpp/.hpp file of the product (src/, include/, io/, daemon/, clients/, tools/) at
most MAX_FILE_LINES lines; a function defined at namespace level at most MAX_FUNCTION_LINES
lines from its first signature line to its closing brace. A function is found as a line at
column 0 that is not a comment, preprocessor line, type or namespace, holding "(" and ending
its signature with "{" within a few lines; its body ends at the next "}" at column 0 (the
project's clang-format style puts both braces there). Lambdas and member functions defined in
class bodies count towards the function or file around them.

KNOWN lists what is over a limit today, each with the size it has: the check fails when one
of them grows, and when one is back under the limit (take it off the list), so the list only
shrinks.
"""
import os
import re
import sys

MAX_FILE_LINES = 800
MAX_FUNCTION_LINES = 150
ROOTS = ["src", "include", "io", "daemon", "clients", "tools"]

# path (or path:function) -> lines today.
KNOWN = {
}

NOT_FUNCTIONS = ("//", "#", "}", "namespace", "using", "struct", "class", "enum", "template",
                 "static_assert", "extern", "typedef", "union")


def functions(lines):
    """(name, first line number, length) of every namespace-level function definition."""
    out, i, n = [], 0, len(lines)
    while i < n:
        line = lines[i]
        if line and not line[0].isspace() and not line.startswith(NOT_FUNCTIONS) and "(" in line:
            j = i
            while j < n and j - i < 8 and not lines[j].rstrip().endswith(("{", ";")):
                j += 1
            if j < n and lines[j].rstrip().endswith("{") and not lines[j].rstrip().endswith("= {"):
                k = j + 1
                while k < n and not lines[k].startswith("}"):
                    k += 1
                words = re.sub(r"\(.*", "", line).split()
                name = words[-1].lstrip("*&") if words else line
                out.append((name, i + 1, k - i + 1))
                i = k
        i += 1
    return out


def measure(root):
    """{key: (lines, where)} for every file and function over its limit."""
    over = {}
    for top in ROOTS:
        for folder, dirs, files in os.walk(os.path.join(root, top)):
            dirs[:] = sorted(d for d in dirs if not d.startswith("build"))
            for name in sorted(files):
                if not name.endswith((".cpp", ".hpp")):
                    continue
                path = os.path.join(folder, name)
                rel = os.path.relpath(path, root)
                lines = open(path, encoding="utf-8", errors="replace").read().split("\n")
                if lines and lines[-1] == "":
                    lines.pop()
                if len(lines) > MAX_FILE_LINES:
                    over[rel] = (len(lines), rel)
                for function, first, length in functions(lines):
                    if length > MAX_FUNCTION_LINES:
                        over[rel + ":" + function] = (length, "%s:%d" % (rel, first))
    return over


def main():
    args = [a for a in sys.argv[1:] if a != "--list"]
    root = args[0] if args else os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
    over = measure(root)
    if "--list" in sys.argv:
        for key, (size, where) in sorted(over.items(), key=lambda kv: -kv[1][0]):
            print("%5d  %s" % (size, where if ":" in key else key))
        return 0
    problems = []
    for key, (size, where) in sorted(over.items()):
        limit = MAX_FUNCTION_LINES if ":" in key else MAX_FILE_LINES
        what = "function" if ":" in key else "file"
        if key not in KNOWN:
            problems.append("%s: %s of %d lines (at most %d): split it into parts that each do "
                            "one thing" % (where, what, size, limit))
        elif size > KNOWN[key]:
            problems.append("%s: %s grew to %d lines (listed at %d in scripts/dev/sizes.py, the "
                            "limit is %d): split it rather than grow it" %
                            (where, what, size, KNOWN[key], limit))
    for key in sorted(set(KNOWN) - set(over)):
        problems.append("%s is within the limits now (or gone): take it off KNOWN in "
                        "scripts/dev/sizes.py" % key)
    for p in problems:
        print(p)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
