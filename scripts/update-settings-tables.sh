#!/usr/bin/env bash
# Rewrites the text generated from the settings schema (lighting/SettingsSchema.h) where it is
# kept: the key tables of docs/TUNING.md and the settings names of the fuzz dictionary
# tests/fuzz/json.dict, each between its marker lines. The tests SettingsSchema.* fail while
# either differs from what the schema generates.
#
#   scripts/update-settings-tables.sh [ambience executable, default build/bin/ambience]
set -euo pipefail
cd "$(dirname "$0")/.."
ambience="${1:-build/bin/ambience}"
[[ -x "$ambience" ]] || { echo "update-settings-tables: no $ambience (build first)" >&2; exit 2; }
tmp="$(mktemp -d "${TMPDIR:-/tmp}/ambience-settings.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
"$ambience" settings --markdown >"$tmp/tables.md"
"$ambience" settings --fuzz-dictionary >"$tmp/names.dict"
python3 - "$tmp" <<'PY'
import sys
tmp = sys.argv[1]
def replace(path, begin, end, text):
    lines = open(path).read().split('\n')
    b = next(i for i, l in enumerate(lines) if l.startswith(begin))
    e = next(i for i, l in enumerate(lines) if i > b and l.startswith(end))
    body = text.rstrip('\n').split('\n')
    lines[b + 1:e] = [''] + body + [''] if path.endswith('.md') else body
    open(path, 'w').write('\n'.join(lines))
replace('docs/TUNING.md', '<!-- settings-schema: begin', '<!-- settings-schema: end',
        open(tmp + '/tables.md').read())
replace('tests/fuzz/json.dict', '# settings-schema: begin', '# settings-schema: end',
        open(tmp + '/names.dict').read())
PY
echo "update-settings-tables: docs/TUNING.md and tests/fuzz/json.dict rewritten"
