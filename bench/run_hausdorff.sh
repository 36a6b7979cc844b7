#!/bin/sh
# Regenerates the CSVs, plots and tables of docs/benchmarks.md (run from the repository
# root after a Release build): bench/run_hausdorff.sh [BUILD_DIR]
set -e
BUILD=${1:-build}
B="$BUILD/bench/bench_hausdorff"
# All clouds, N = M = 1e3 … 1e6 in steps of √10; full exact reference up to 3.2e4, exact
# fields on 1000 random points above; a configuration predicted to need more than 25 s
# (three repeats) at the next size is not run.
"$B" --min-n 1e3 --max-n 1e6 --exact-max 3.2e4 --budget 25 --repeats 3 \
  --csv docs/bench_hausdorff_ladder.csv
# Goal 1: N = M = 1e5 uniform cube, value + gradient, exact against tree.
"$B" --shapes cube --min-n 1e5 --max-n 1e5 --modes value+grad --taus 1e-2,1e-4,1e-6 \
  --exact-max 1e5 --repeats 3 --budget 1e9 --csv docs/bench_hausdorff_goal1.csv

/usr/bin/python3 bench/plot_hausdorff.py docs/bench_hausdorff_ladder.csv \
  docs/bench_hausdorff_goal1.csv --out docs \
  > docs/bench_hausdorff_tables.md
