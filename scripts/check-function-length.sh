#!/usr/bin/env bash
# check-function-length.sh [MAX_LINES] [DIR...]: fails when a function definition in DIRs (default
# baker/src baker/cli runtime/src) spans more than MAX_LINES lines (default 150), the bar the style
# guide sets so that long routines read as named steps. Prints "lines name file:line" for each.
# Needs Universal Ctags (Debian: universal-ctags), which gives each definition its end line.
set -euo pipefail
cd "$(dirname "$0")/.."
max=${1:-150}
shift $(($# > 0 ? 1 : 0))
dirs=("$@")
((${#dirs[@]})) || dirs=(baker/src baker/cli runtime/src)

if ! ctags --version 2>/dev/null | grep -q 'Universal Ctags'; then
    echo "check-function-length: Universal Ctags is required (apt-get install universal-ctags)" >&2
    exit 2
fi
over=$(ctags -x --_xformat='%{line} %{end} %N %F' --kinds-c++=f --fields=+ne -R "${dirs[@]}" |
    awk -v max="$max" '$2 != "" { n = $2 - $1 + 1; if (n > max) print n, $3, $4 ":" $1 }' | sort -rn)
if [ -n "$over" ]; then
    echo "check-function-length: functions over $max lines (split them into named steps):"
    echo "$over"
    exit 1
fi
echo "check-function-length: no function over $max lines in ${dirs[*]}"
