#!/usr/bin/env bash
# docs-check.sh — the README and docs/ hold together (docs/TESTING.md "The docs and their figures").
#
#   tests/docs-check.sh [AMBIENCE [SCRATCH]]      (ctest: docs_check)
#
# 1. Every file README.md and docs/*.md link to ([text](path), ![alt](path), outside code) exists
#    in the repository and lies inside it.
# 2. README.md's results table (between <!-- results:begin --> and <!-- results:end -->) is the
#    one in docs/RESULTS.md, which scripts/make-figures.sh writes: no figure in it is hand-typed.
# 3. Every subcommand `AMBIENCE --help` lists is in the README's table of commands.
# 4. `scripts/make-figures.sh --short --out SCRATCH/figures` runs and writes every picture the
#    docs link to, RESULTS.md and a README.md with its table filled in (docs/ is left alone).
# With no AMBIENCE only 1 and 2 run. Exit code: 0 all hold, 1 one does not (each reason on
# stderr), 77 no offscreen GL platform for step 4.
set -euo pipefail

root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${1:-}"
scratch="${2:-}"
python=python3
[[ -x /usr/bin/python3 ]] && python=/usr/bin/python3
failed=0
fail() { echo "docs-check: $*" >&2; failed=1; }

# 1 and 2: links and the results table (Python: markdown links outside code spans and blocks).
"$python" - "$root" <<'EOF' || failed=1
import os, re, sys
root = os.path.realpath(sys.argv[1])
files = [os.path.join(root, "README.md")] + sorted(
    os.path.join(root, "docs", f) for f in os.listdir(os.path.join(root, "docs")) if f.endswith(".md"))
bad = 0
link = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
for path in files:
    text = open(path, encoding="utf-8").read()
    text = re.sub(r"^```.*?^```", "", text, flags=re.S | re.M)   # fenced code
    text = re.sub(r"`[^`\n]*`", "", text)                          # inline code
    for target in link.findall(text):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("#"):
            continue  # a web address or an anchor in the same file
        rel = target.split("#")[0]
        full = os.path.realpath(os.path.join(os.path.dirname(path), rel))
        name = os.path.relpath(path, root)
        if not (full == root or full.startswith(root + os.sep)):
            print("docs-check: %s links outside the repository: %s" % (name, target), file=sys.stderr)
            bad = 1
        elif not os.path.exists(full):
            print("docs-check: %s links to a missing file: %s" % (name, target), file=sys.stderr)
            bad = 1
def block(path):
    if not os.path.exists(path):
        return None
    text = open(path, encoding="utf-8").read()
    m = re.search(r"<!-- results:begin -->\n(.*?)<!-- results:end -->", text, flags=re.S)
    return m.group(1) if m else None
readme, results = block(os.path.join(root, "README.md")), block(os.path.join(root, "docs", "RESULTS.md"))
if readme is None or results is None:
    print("docs-check: README.md and docs/RESULTS.md must each hold the results markers", file=sys.stderr)
    bad = 1
elif readme != results or not readme.strip():
    print("docs-check: README.md's results table is not docs/RESULTS.md's "
          "(run scripts/make-figures.sh, or copy the block between the markers)", file=sys.stderr)
    bad = 1
sys.exit(bad)
EOF

if [[ -z $bin ]]; then
  ((failed)) && exit 1
  echo "docs-check: links and the results table hold (no executable given: no more checks)"
  exit 0
fi

# 3: the table of commands names every subcommand.
subs=$("$bin" --help | sed -n '/^Subcommands:/,$p' | sed -nE 's/^  ([a-z][a-z-]*) .*/\1/p')
[[ -n $subs ]] || fail "'$bin --help' lists no subcommand"
for s in $subs; do
  grep -qE "^\| \`ambience $s( |\`)" "$root/README.md" ||
    fail "README.md's table of commands has no line for 'ambience $s'"
done

# 4: the figures script, short, into a scratch folder.
if [[ -z $scratch ]]; then
  scratch="$(mktemp -d "${TMPDIR:-/tmp}/ambience-docs-check.XXXXXX")"
  trap 'rm -rf "$scratch"' EXIT
fi
out="$scratch/figures"
rm -rf "$out"
mkdir -p "$out"
docs_sum() { cat "$root/README.md" "$root"/docs/* | sha1sum; }
before=$(docs_sum)
start=$SECONDS
set +e
"$root/scripts/make-figures.sh" --short --out "$out" --bin "$bin" >"$scratch/make-figures.log" 2>&1
status=$?
set -e
if ((status == 77)); then
  echo "docs-check: make-figures skipped: $(tail -n 1 "$scratch/make-figures.log")"
  ((failed)) && exit 1
  exit 77
fi
if ((status != 0)); then
  tail -n 20 "$scratch/make-figures.log" >&2
  fail "scripts/make-figures.sh --short failed (exit $status)"
else
  echo "docs-check: scripts/make-figures.sh --short ran in $((SECONDS - start)) s"
  # Every picture the docs link to, made again in the scratch folder.
  for picture in $(grep -ohE '\]\((docs/)?[a-z0-9-]+\.(png|jpg)\)' "$root"/docs/*.md "$root/README.md" |
                   sed -E 's/^\]\((docs\/)?//; s/\)$//' | sort -u); do
    [[ $picture == soak-memory.png ]] && continue  # the soak is left out of the short setting
    [[ -s $out/$picture ]] || fail "make-figures.sh --short did not write $picture"
  done
  for f in RESULTS.md README.md; do [[ -s $out/$f ]] || fail "make-figures.sh --short did not write $f"; done
  grep -q 'generated by scripts/make-figures.sh, do not edit' "$out/RESULTS.md" ||
    fail "RESULTS.md has no 'generated' header"
  sed -n '/<!-- results:begin -->/,/<!-- results:end -->/p' "$out/README.md" |
    grep -q '^| \*\*volume (ours)\*\* | ' || fail "the README copy's results table was not filled in"
  [[ $(docs_sum) == "$before" ]] || fail "make-figures.sh --out changed docs/ or README.md"
fi
((failed)) && exit 1
echo "docs-check: ok"
