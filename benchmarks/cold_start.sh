#!/bin/sh
# Cold start of the first `solve --case random30` with an empty kernel cache, an older tree
# against a clone of this one, in the same venv; then `import subtask_opt` with a warm cache.
#   OLD_TREE=/path/to/old/checkout sh benchmarks/cold_start.sh   (RUNS="1 2" by default)
# The old tree's numba cache files (*.nbi, *.nbc next to its sources) are deleted first.
set -e
PY=${PY:-$(pwd)/.venv/bin/python}
OLD=${OLD_TREE:?set OLD_TREE to an older checkout}
NEW=$(mktemp -d)/new
CACHE=$(mktemp -d)
export MPLBACKEND=Agg
git clone -q "$(pwd)" "$NEW"
run() {  # $1 tree, $2 label
    start=$(date +%s.%N)
    (cd "$1" && PYTHONPATH="$1" SUBTASK_OPT_CACHE_DIR="$CACHE" "$PY" -c "import sys; from subtask_opt.cli import main; sys.exit(main(['solve', '--case', 'random30', '--seed', '1']))" >/dev/null 2>&1)
    echo "$2 $(echo "$(date +%s.%N) - $start" | bc) s"
}
for r in ${RUNS:-1 2}; do
    find "$OLD" \( -name "*.nbi" -o -name "*.nbc" \) -delete
    run "$OLD" "old cold solve"
    rm -rf "$CACHE" && mkdir -p "$CACHE"
    run "$NEW" "new cold solve"
done
for r in 1 2 3; do
    start=$(date +%s.%N)
    PYTHONPATH="$NEW" SUBTASK_OPT_CACHE_DIR="$CACHE" "$PY" -c "import subtask_opt"
    echo "new warm import $(echo "$(date +%s.%N) - $start" | bc) s"
done
