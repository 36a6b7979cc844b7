#!/bin/sh
# Peak memory of one forward solve of the bending scene refined r times along every axis
# (cells 50r x 5r x 2r, Q2), per state backend: the numbers of docs/scaling.md §4-§8.
#   scripts/measure_state_memory.sh BUILD_DIR "R..." "BACKEND[:RANKS]..."
# e.g. scripts/measure_state_memory.sh build-mpi "1 2" "cholmod petsc-gamg:1 petsc-gamg:2"
# Prints one row per run: backend ranks r cells dofs peak_rss_MiB(max over ranks) seconds
# converged ("failed" when the run stopped early, e.g. on purpose with PETSC_OPTIONS=
# "-softhd_state_ksp_error_if_not_converged": it stops at the first CG solve that does not
# converge, on the bending plate the second Newton direction (negative curvature), after two
# assemblies and GAMG set-ups; -softhd_state_ksp_max_it has no effect, the solver sets its
# own limit per solve). Peak RSS is GNU time's maximum resident set size of the process (with mpiexec:
# of the largest of its children, i.e. per rank). OMP_NUM_THREADS=1 for every run.
set -eu
build=$1
sizes=$2
backends=$3
here=$(cd "$(dirname "$0")/.." && pwd)
work=${TMPDIR:-/tmp}/softhd_state_memory.$$
mkdir -p "$work"
export OMP_NUM_THREADS=1 OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
printf "%-12s %5s %3s %-12s %9s %12s %9s %s\n" backend ranks r cells dofs peak_MiB seconds converged
for r in $sizes; do
  scene=$work/bending_r$r.json
  sed -e "s/\"cells\": \[50, 5, 2\]/\"cells\": [$((50 * r)), $((5 * r)), $((2 * r))]/" \
    "$here/data/scenes/bending.json" > "$scene"
  for spec in $backends; do
    backend=${spec%%:*}
    ranks=1
    [ "$spec" != "$backend" ] && ranks=${spec#*:}
    launch=""
    [ "$backend" != cholmod ] && launch="mpiexec -n $ranks --oversubscribe"
    out=$work/out_${backend}_${ranks}_$r
    /usr/bin/time -f "%M %e" -o "$work/time" $launch "$build/apps/softhd" forward "$scene" \
      --control-uniform -3000 --coarse-levels 0 --max-memory 1000 --json --out "$out" \
      --state-backend "$backend" > "$work/json" 2> "$work/err" || true
    dofs=$((100 * r * (10 * r + 1) * (4 * r + 1) * 3))  # free dofs: the clamped plane x = 0 is fixed
    conv=$(python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['converged'])" "$work/json" 2>/dev/null || echo failed)
    read -r kib secs <<EOT
$(tail -n 1 "$work/time")
EOT
    printf "%-12s %5s %3s %-12s %9s %12.1f %9s %s\n" "$backend" "$ranks" "$r" \
      "$((50 * r))x$((5 * r))x$((2 * r))" "$dofs" "$(echo "$kib / 1024" | bc -l)" "$secs" "$conv"
  done
done
rm -rf "$work"
