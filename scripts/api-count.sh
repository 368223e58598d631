#!/usr/bin/env bash
# The public items of the core crate (src/), counted the way the
# public-API count of ARCHITECTURE.md ("The public API") is: every item
# declared `pub` (not `pub(crate)`, not `pub(super)`) at the start of a
# line, by kind — `fn` (with `const fn`), `const`, `struct`, `enum`,
# `trait`, `type`, `static`, `mod` — outside `#[cfg(test)]` modules;
# `pub use` re-exports and struct fields are not counted. With a revision
# it counts that commit's tree (`scripts/api-count.sh 0249634`).
#
# Usage: scripts/api-count.sh [REV]
set -euo pipefail
cd "$(git rev-parse --show-toplevel)"
exec python3 - "${1:-}" <<'PY'
import pathlib, re, subprocess, sys
from collections import Counter

rev = sys.argv[1]

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
PY
