#!/usr/bin/env python3
"""The user documents state the shipped settings as daemon/findmugd.yaml sets them.

  check_docs.py [SOURCE_DIR]     (ctest docs_consistency; exit 1 naming file:line on a finding)

Reads the effective values of daemon/findmugd.yaml (section -> key -> value; the file is two
levels deep) and fails where README.md, BENCHMARKS.md or models/README.md state a shipped value
that differs:
  - `section.key: value` or `key: value` in backticks (quoting the file) states the shipped
    value when its sentence, table row or command speaks of the shipped configuration (shipped,
    findmugd.yaml, the default config, models/findmug.fmf);
  - `section.key=value` (a --set, or in backticks) and `section.key value` / `key value` in
    words state it when their sentence, table row or command speaks of the shipped
    configuration and names no other one (instead of, without, until, before, earlier, older,
    not, only with, "shipped + ...", ...). In a command, ground.source, learner.num_threads,
    forest.seed and daemon.* may differ (how a tool finds the ground, uses the machine).
A bare key counts only when one section of the file has it. It also fails where a user
document (those three and daemon/findmugd.yaml) names an issue number ("issue 35",
"issue #35"): history is in git, and docs/perf-log.md, a log, may keep them.
"""
import os
import re
import sys

USER_DOCS = ["README.md", "BENCHMARKS.md", "models/README.md"]
YAML = "daemon/findmugd.yaml"

SHIPPED = re.compile(r"shipped|ships\b|findmugd\.yaml|default config|(?<![\w-])findmug\.fmf|"
                     r"the daemon's settings", re.I)
OTHER = re.compile(r"instead of|without|\buntil\b|\bbefore\b|\bearlier\b|\bolder\b|\bprevious|"
                   r"\bnot\b|\bor\b `?--set|against|\bthan\b|\bformer|\bonly with\b|\s\+\s",
                   re.I)
# Settings a command may set otherwise than the daemon's file on purpose: how training and
# evaluation find the ground and use the machine, and the daemon's own section in benchmarks.
COMMAND_OWN = re.compile(r"^(ground\.source|learner\.num_threads|forest\.seed|daemon\..*)$")
ISSUE = re.compile(r"\b(?:issues?|pull request|PR)\s*#?\s*\d+", re.I)


def read_yaml(path):
    """section -> key -> (value, line); two levels. A key shown commented out with one value
    and nothing after it ("  # key: value": the value a model records, or a default path) is
    read as stated too; other comments are skipped."""
    values, section = {}, None
    for n, raw in enumerate(open(path, encoding="utf-8"), 1):
        line = raw.rstrip("\n")
        shown = re.match(r"^  # ([a-z_][a-z0-9_]*): (\S+)$", line)
        if shown and section:
            values[section][shown.group(1)] = (shown.group(2), n)
            continue
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        m = re.match(r"^([a-z_][a-z0-9_]*):\s*(?:#.*)?$", line)
        if m:
            section = m.group(1)
            values.setdefault(section, {})
            continue
        m = re.match(r"^\s+([a-z_][a-z0-9_]*):\s*(.*?)\s*(?:\s#.*)?$", line)
        if m and section:
            value = m.group(2).strip()
            if len(value) >= 2 and value[0] == value[-1] and value[0] in "\"'":
                value = value[1:-1]
            values[section][m.group(1)] = (value, n)
    return values


def same(a, b):
    a, b = a.strip().strip("`\"'"), b.strip().strip("`\"'")
    if a.lower() in ("true", "on", "yes") and b.lower() in ("true", "on", "yes"):
        return True
    if a.lower() in ("false", "off", "no") and b.lower() in ("false", "off", "no"):
        return True
    try:
        return float(a) == float(b)
    except ValueError:
        return a == b


def units(lines):
    """(first line number, text, is a command) of each sentence, table row and command of a markdown file."""
    out, in_code, buf, start, comment = [], False, [], 0, ""
    for n, line in enumerate(lines, 1):
        if line.lstrip().startswith("```"):
            if buf:
                out.append((start, " ".join(buf), False))
                buf = []
            in_code = not in_code
            comment = ""
            continue
        if in_code:
            if line.lstrip().startswith("#"):
                comment = line
                continue
            if not buf:
                start = n
            buf.append(line.rstrip("\\"))
            if not line.rstrip().endswith("\\"):
                out.append((start, comment + " " + " ".join(buf), True))
                buf, comment = [], ""
            continue
        if line.lstrip().startswith("|") or not line.strip() or line.lstrip().startswith("#"):
            if buf:
                out.append((start, " ".join(buf), False))
                buf = []
            if line.strip():
                out.append((n, line, False))
            continue
        # prose: split into sentences, keeping the line each starts on
        for piece in re.split(r"(?<=[.;:!?])\s+(?=[A-Z(`*])", line):
            if not buf:
                start = n
            buf.append(piece)
            if re.search(r"[.!?]$", piece.rstrip()):
                out.append((start, " ".join(buf), False))
                buf = []
    if buf:
        out.append((start, " ".join(buf), in_code))
    return out


def line_of(lines, start, needle):
    """The line at or after `start` where `needle` first appears (a unit may span lines)."""
    for n in range(start, min(start + 12, len(lines) + 1)):
        if needle in lines[n - 1]:
            return n
    return start


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..")
    os.chdir(root)
    shipped = read_yaml(YAML)
    sections_of = {}
    for section, keys in shipped.items():
        for key in keys:
            sections_of.setdefault(key, []).append(section)
    enum_values = {v for keys in shipped.values() for v, _ in keys.values()
                   if re.fullmatch(r"[a-z][a-z0-9_]*", v)}

    def lookup(section, key):
        if section:
            return (section, shipped[section][key]) if key in shipped.get(section, {}) else None
        owners = sections_of.get(key, [])
        return (owners[0], shipped[owners[0]][key]) if len(owners) == 1 else None

    findings = []
    key_re = r"(?:([a-z_][a-z0-9_]*)\.)?([a-z_][a-z0-9_]*)"
    quoted_yaml = re.compile(r"`" + key_re + r":\s*([^`\s]+)`")
    assigned = re.compile(r"(?<![\w.])" + r"([a-z_][a-z0-9_]*)\.([a-z_][a-z0-9_]*)=([^\s`,;)]+)")
    worded = re.compile(r"(?<![\w.=`-])" + key_re + r"`?\s+`?([a-z0-9_.]+)\b")

    for doc in USER_DOCS:
        lines = open(doc, encoding="utf-8").read().split("\n")
        for start, text, is_command in units(lines):
            claims = []
            if not SHIPPED.search(text):
                continue
            for m in quoted_yaml.finditer(text):
                claims.append((m.group(1), m.group(2), m.group(3), m.group(0)))
            if not OTHER.search(text):
                for m in assigned.finditer(text):
                    claims.append((m.group(1), m.group(2), m.group(3), m.group(0)))
                for m in worded.finditer(text):
                    value = m.group(3)
                    if value in enum_values or re.fullmatch(r"\d+(\.\d+)?", value):
                        if m.group(1) is None and m.group(2) not in sections_of:
                            continue
                        claims.append((m.group(1), m.group(2), value, m.group(0)))
            for section, key, value, said in claims:
                found = lookup(section, key)
                if not found:
                    continue
                sec, (actual, yaml_line) = found
                if is_command and COMMAND_OWN.match(f"{sec}.{key}"):
                    continue
                if os.environ.get("CHECK_DOCS_VERBOSE"):
                    print(f"{doc}:{start}: {sec}.{key} = {value} (file: {actual})")
                if not same(value, actual):
                    n = line_of(lines, start, said.split(":")[0].split("=")[0].strip("`"))
                    findings.append(f"{doc}:{n}: states {sec}.{key} = {value} ({said!r}), "
                                    f"but {YAML}:{yaml_line} sets {actual}")

    for doc in USER_DOCS + [YAML]:
        for n, line in enumerate(open(doc, encoding="utf-8"), 1):
            for m in ISSUE.finditer(line):
                findings.append(f"{doc}:{n}: names an issue number ({m.group(0)!r}); "
                                "say what it is, history is in git")

    for f in findings:
        print(f)
    if findings:
        sys.exit(f"check_docs.py: {len(findings)} finding(s)")
    print(f"check_docs.py: {', '.join(USER_DOCS)} agree with {YAML} "
          f"({sum(len(k) for k in shipped.values())} settings); no issue numbers")


if __name__ == "__main__":
    main()
