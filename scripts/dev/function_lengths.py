#!/usr/bin/env python3
"""Function definitions in C++ sources longer than a number of lines, longest first.

  scripts/dev/function_lengths.py [--min LINES] PATH...   (PATH: a file, or a folder searched
                                                             for *.cpp and *.hpp; default 120)

A rough reader, not a parser: comments and literals are blanked, then braces are matched; a
brace after a ')' outside any function opens a function (lambdas and local classes count
towards the function that holds them). Prints "LINES  FILE:LINE  NAME" from the line of the
opening brace to the line of the closing one. Used for issue 37 (long functions split into
named steps; docs/measurements/function-splits.md).
"""
import os
import re
import sys


def blank_comments_and_literals(src):
    """`src` with comments and string/char literals emptied, newlines kept (line numbers hold)."""
    out = []
    i, n = 0, len(src)
    while i < n:
        if src.startswith("//", i):
            j = src.find("\n", i)
            i = n if j < 0 else j
            continue
        if src.startswith("/*", i):
            j = src.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * src.count("\n", i, j))
            i = j
            continue
        raw = re.match(r'R"([^(\s]*)\(', src[i:i + 20]) if src.startswith('R"', i) else None
        if raw:
            end = src.find(")" + raw.group(1) + '"', i)
            end = n if end < 0 else end + len(raw.group(1)) + 2
            out.append('""' + "\n" * src.count("\n", i, end))
            i = end
            continue
        c = src[i]
        if c == '"' or (c == "'" and not (i > 0 and src[i - 1].isalnum())):  # not 1'000
            j = i + 1
            while j < n and src[j] != c:
                j += 2 if src[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
            continue
        out.append(c)
        i += 1
    return "".join(out)


def functions(path):
    """(lines, first line, name) of every function defined in the file at `path`."""
    with open(path, encoding="utf-8") as f:
        src = blank_comments_and_literals(f.read())
    found = []
    stack = []  # (kind, line of "{", name); kind: scope (namespace, class), function, block
    line, last = 1, 0
    for m in re.finditer(r"[{};\n]", src):
        ch = m.group(0)
        if ch == "\n":
            line += 1
            continue
        if ch == ";":
            last = m.end()
            continue
        if ch == "{":
            head = " ".join(src[last:m.start()].split())
            kind, name = "block", ""
            if not any(k == "function" for k, _, _ in stack):
                if re.search(r"\b(namespace|class|struct|union|enum)\b[^()]*$", head) or \
                        re.search(r'extern\s*""$', head):
                    kind = "scope"
                elif ")" in head and not head.endswith("="):
                    kind = "function"
                    bare = re.sub(r"__attribute__\s*\(\(.*?\)\)|\[\[.*?\]\]", "", head)
                    named = re.search(r"([~\w:]+)\s*\(", bare)
                    name = named.group(1) if named else "?"
            stack.append((kind, line, name))
        else:
            kind, first, name = stack.pop()
            if kind == "function":
                found.append((line - first + 1, first, name))
        last = m.end()
    return found


def main(argv):
    minimum = 120
    if len(argv) >= 2 and argv[0] == "--min":
        minimum = int(argv[1])
        argv = argv[2:]
    files = []
    for root in argv or ["src"]:
        if os.path.isfile(root):
            files.append(root)
            continue
        for folder, _, names in os.walk(root):
            files += [os.path.join(folder, f) for f in names if f.endswith((".cpp", ".hpp"))]
    rows = [(lines, path, first, name) for path in sorted(files)
            for lines, first, name in functions(path) if lines > minimum]
    for lines, path, first, name in sorted(rows, key=lambda r: (-r[0], r[1], r[2])):
        print(f"{lines:5d}  {path}:{first}  {name}")


if __name__ == "__main__":
    main(sys.argv[1:])
