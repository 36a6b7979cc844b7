#!/usr/bin/env bash
# The main job (make demo): run the bending demo and say where the results are.
set -euo pipefail
build=${1:-build}
cd "$(dirname "$0")/.."
"$build/apps/softhd_demo" --out results/demo
