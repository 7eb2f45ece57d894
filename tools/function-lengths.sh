#!/usr/bin/env bash
# The longest functions of the product code (not tests), measured with universal ctags:
#   bash tools/function-lengths.sh [COUNT]      (default 10)
# Lambdas count inside the function that holds them. The architecture keeps every function
# under 200 lines (docs/architecture.md).
set -euo pipefail
cd "$(dirname "$0")/.."
command -v ctags >/dev/null || { echo "function-lengths: needs universal-ctags (apt-get install universal-ctags)" >&2; exit 2; }
dirs=()
for d in core scene precompute inputs cover bakers bake distributed tools cuda bench; do [ -d "$d" ] && dirs+=("$d"); done
ctags -R --languages=C++ --langmap=C++:+.cu.cuh.inc --kinds-C++=f --fields=+ne -f - "${dirs[@]}" 2>/dev/null |
  awk -F'\t' '{s="";e="";for(i=4;i<=NF;i++){if($i~/^line:/)s=substr($i,6);if($i~/^end:/)e=substr($i,5)}
               if(e!="" && $1 !~ /^__anon/) print e-s+1, $2":"s, $1}' |
  sort -rn | head -n "${1:-10}"
