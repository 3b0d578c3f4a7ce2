#!/bin/sh
# Lists C++ functions longer than N lines (default 80), longest first: "lines file:line name".
# Uses universal-ctags' end lines; lambdas count towards the function that holds them.
# Usage: scripts/long_functions.sh [N] [paths...]   (default: the tracked .cpp/.h files)
set -eu
limit=${1:-80}
[ $# -gt 0 ] && shift
cd "$(git rev-parse --show-toplevel)"
if [ $# -eq 0 ]; then
  set -- $(git ls-files '*.cpp' '*.h' | grep -v '^third_party/')
fi
ctags -x --c++-kinds=f --fields=+ne --_xformat='%F %n %e %N' --language-force=C++ "$@" 2>/dev/null |
  awk -v limit="$limit" '$3 ~ /^[0-9]+$/ { n = $3 - $2 + 1; name = $4; for (i = 5; i <= NF; i++) name = name " " $i
    if (n > limit) printf "%4d %s:%s %s\n", n, $1, $2, name }' |
  sort -rn
