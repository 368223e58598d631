#!/usr/bin/env bash
# The public items of the core crate (src/), counted the way the
# public-API count of ARCHITECTURE.md ("The public API") is: every item
# declared `pub` (not `pub(crate)`, not `pub(super)`) at the start of a
# line, by kind — `fn` (with `const fn`), `const`, `struct`, `enum`,
# `trait`, `type`, `static`, `mod` — outside `#[cfg(test)]` modules;
# `pub` re-exports and struct fields are not counted. With a revision it
# counts that commit's tree (`scripts/api-count.sh 0249634`).
#
# With --public (the working tree only) it also counts the public API:
# those items less the ones rustc's `unreachable_pub` lint finds no path
# to from outside the crate (an item declared `pub` in a crate-private
# module; the `internals` feature, which makes such modules public for the
# crate's own tests, is off), in the default build or, for what only it
# compiles, the fixed-point one. On a tree whose modules are all `pub` the
# two counts are the same.
#
# Usage: scripts/api-count.sh [REV | --public]
set -euo pipefail
cd "$(git rev-parse --show-toplevel)"
exec python3 - "${1:-}" <<'PY'
import json, os, pathlib, re, subprocess, sys
from collections import Counter

public = sys.argv[1] == "--public"
rev = "" if public else sys.argv[1]

def files():
    if rev:
        names = subprocess.run(["git", "ls-tree", "-r", "--name-only", rev, "src"],
                               check=True, capture_output=True, text=True).stdout.split()
        for p in names:
            if p.endswith(".rs"):
                yield subprocess.run(["git", "show", f"{rev}:{p}"], check=True,
                                     capture_output=True, text=True).stdout
    else:
        for p in sorted(pathlib.Path("src").rglob("*.rs")):
            yield p.read_text()

def without_test_modules(text):
    """The text without `#[cfg(test)] mod … { … }` blocks (brace count)."""
    out, skip, depth, pending = [], False, 0, False
    for line in text.split("\n"):
        s = line.strip()
        if skip:
            depth += line.count("{") - line.count("}")
            skip = depth > 0
            continue
        if s.startswith("#[cfg(test)]"):
            pending = True
            continue
        if pending:
            pending = False
            if re.match(r"(pub(\([a-z]+\))? )?mod \w+ *\{", s):
                depth = line.count("{") - line.count("}")
                skip = depth > 0
                continue
            if re.match(r"(pub(\([a-z]+\))? )?mod \w+;", s):
                continue
        out.append(line)
    return "\n".join(out)

ITEM = re.compile(r"^\s*pub ((?:const |unsafe |async )*fn|const|struct|enum|trait|type|static|mod)\b", re.M)
kinds, lines = Counter(), 0
for text in files():
    lines += text.count("\n")
    for m in ITEM.finditer(without_test_modules(text)):
        kinds["fn" if m.group(1).endswith("fn") else m.group(1)] += 1
total = sum(kinds.values())
order = ["fn", "const", "struct", "enum", "trait", "type", "static", "mod"]
print(f"{total} public items ({', '.join(f'{k} {kinds[k]}' for k in order)}); "
      f"{lines} lines, {total * 1000 / lines:.1f} per 1 000 lines")

if public:
    lib = open("src/lib.rs").read()
    anchor = "#![deny(missing_docs)]\n"
    mark = "#![warn(unreachable_pub)] // api-count.sh: removed when it ends\n"
    open("src/lib.rs", "w").write(lib.replace(anchor, anchor + mark, 1))
    try:
        # Both builds: a file only the fixed-point build compiles
        # (`chain/fixed.rs`) is linted only there.
        out = "".join(subprocess.run(["cargo", "check", "-p", "imu-emu", "--lib", "--message-format=json",
                                      "--quiet"] + extra, capture_output=True, text=True).stdout
                      for extra in ([], ["--features", "fixed-point"]))
    finally:
        open("src/lib.rs", "w").write(lib)
    hidden, seen = Counter(), set()
    for line in out.splitlines():
        m = json.loads(line) if line.startswith("{") else {}
        msg = m.get("message") or {}
        if (msg.get("code") or {}).get("code") != "unreachable_pub":
            continue
        for sp in msg["spans"]:
            if not sp["is_primary"] or sp.get("expansion"):
                continue
            if (sp["file_name"], sp["line_start"]) in seen:
                continue
            seen.add((sp["file_name"], sp["line_start"]))
            text = open(sp["file_name"]).read().split("\n")[sp["line_start"] - 1]
            m2 = ITEM.match(text[sp["column_start"] - 1:].rjust(0))
            if m2 and text[:sp["column_start"] - 1].strip() == "":
                hidden["fn" if m2.group(1).endswith("fn") else m2.group(1)] += 1
    shown = Counter({k: kinds[k] - hidden[k] for k in order})
    n = sum(shown.values())
    print(f"{n} in the public API ({', '.join(f'{k} {shown[k]}' for k in order)}); "
          f"{n * 1000 / lines:.1f} per 1 000 lines; {sum(hidden.values())} pub only "
          "inside the crate (reached by its own tests through `internals`)")
PY
