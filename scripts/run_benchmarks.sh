#!/usr/bin/env bash
# Runs the benchmarks and regenerates their report (issue 6): `make bench` and `make bench-quick`.
#
#   scripts/run_benchmarks.sh [--quick] [--only a,b,...] BUILD_DIR OUT_DIR REPORT
#
# Benchmarks: kernel, hausdorff, resolution, control, stability, time_to_floor, forward_fenics, finger,
# align, python, cells (--only picks some; the report then also uses the CSVs already in OUT_DIR for the
# others; finger has no smoke variant and runs only without --quick). Each writes
# OUT_DIR/<name>.csv, its log OUT_DIR/<name>.log and OUT_DIR/<name>.meta (command, date,
# commit, machine, load before and after); then bench/make_report.py writes REPORT and the
# PNG plots into OUT_DIR. --quick runs the smoke variants (a couple of minutes; the test
# suite runs it). Exit code: non-zero if any benchmark or the report failed.
set -euo pipefail
quick=0
only="kernel,hausdorff,resolution,control,stability,time_to_floor,forward_fenics,finger,align,python,cells"
# The goal cases of issue 13 (value + gradient, methods interleaved, medians of 3): the
# exact sums of the large cases are timed on a sample of target points and scaled.
goals() {  # bench_dir csv
  local b=$1 csv=$2
  rm -f "$csv"
  "$b/bench_hausdorff" --goal asym --m 1e6 --tau 1e-4 --exact-sample 20000 --repeats 3 --csv "$csv"
  "$b/bench_hausdorff" --goal room --n 46021 --m 460400 --tau 1e-4 --exact-sample 46040 \
    --repeats 3 --csv "$csv"
  "$b/bench_hausdorff" --goal cube --n 1e5 --m 1e5 --tau 1e-6 --repeats 3 --csv "$csv"
  "$b/bench_hausdorff" --goal cube --n 1e6 --m 1e6 --alpha 64 --tau 1e-6 \
    --methods nearest,tree --repeats 3 --csv "$csv"
}
while [ $# -gt 0 ]; do
  case "$1" in
    --goals-only) goals "$2" "$3"; exit 0 ;;
    --quick) quick=1; shift ;;
    --only) only="$2"; shift 2 ;;
    -h|--help) sed -n '2,12p' "$0"; exit 0 ;;
    *) break ;;
  esac
done
[ $# -eq 3 ] || { echo "usage: $0 [--quick] [--only LIST] BUILD_DIR OUT_DIR REPORT" >&2; exit 2; }
build=$1 out=$2 report=$3
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"

meta() {  # name command...
  local name=$1; shift
  {
    echo "command: $*"
    echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
    echo "commit: $(git -C "$here" rev-parse --short HEAD 2>/dev/null || echo unknown)$(git -C "$here" diff --quiet -- . ':!docs/bench' ':!docs/benchmarks.md' 2>/dev/null || echo ' (with uncommitted changes)')"
    echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
    echo "load before: $(cut -d' ' -f1-3 /proc/loadavg)"
  } >"$out/$name.meta"
}

run() {  # name command...
  local name=$1; shift
  case ",$only," in *",$name,"*) ;; *) return 0 ;; esac
  echo "== $name: $*" >&2
  meta "$name" "$@"
  local start=$SECONDS
  if ! "$@" >"$out/$name.log" 2>&1; then
    echo "benchmark $name failed; its log: $out/$name.log" >&2
    tail -20 "$out/$name.log" >&2
    exit 1
  fi
  echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$out/$name.meta"
  echo "wall seconds: $((SECONDS - start))" >>"$out/$name.meta"
}

b="$build/bench"
align_bench() {  # bench/bench_align.py (issue 32), when the Python module is built
  if [ ! -d "$build/python/softhd" ]; then
    echo "== align: skipped (the Python module is not built: pybind11-dev, python3-dev)" >&2
    return 0
  fi
  run align /usr/bin/python3 "$here/bench/bench_align.py" "$build" --csv "$out/align.csv" "$@"
}
python_bench() {  # bench/bench_python.py, when the Python module is built
  if [ ! -d "$build/python/softhd" ]; then
    echo "== python: skipped (the Python module is not built: pybind11-dev, python3-dev)" >&2
    return 0
  fi
  run python env PYTHONPATH="$build/python" /usr/bin/python3 "$here/bench/bench_python.py" \
    --build "$build" --csv "$out/python.csv" "$@"
}
if [ $quick -eq 1 ]; then
  run kernel "$b/bench_kernel" --n 4000 --repeats 1 --csv "$out/kernel.csv"
  run hausdorff "$b/bench_hausdorff" --quick --csv "$out/hausdorff_ladder.csv"
  run resolution "$b/bench_resolution" --quick --csv "$out/resolution.csv"
  run control "$b/bench_control" --quick --csv "$out/control.csv"
  run stability "$b/bench_stability" --quick --csv "$out/stability.csv"
  run time_to_floor /usr/bin/python3 "$here/bench/bench_time_to_floor.py" "$build" --quick \
    --csv "$out/time_to_floor.csv"
  align_bench --poses 2
  python_bench --n 2000 --torch-n 1000 --repeats 2
  run cells "$b/bench_cells" --quick --csv "$out/cells.csv"
else
  run kernel "$b/bench_kernel" --n 20000 --repeats 5 --csv "$out/kernel.csv"
  # The Hausdorff ladder (one run per size; a (method, tau, mode) stops growing when its next
  # size is predicted over 6 s) and the goal cases of issue 13 (goals() above).
  run hausdorff sh -c "'$b/bench_hausdorff' --min-n 1e3 --max-n 1e6 --exact-max 3.2e4 \
    --budget 6 --repeats 1 --csv '$out/hausdorff_ladder.csv' && '$here/scripts/run_benchmarks.sh' \
    --goals-only '$b' '$out/hausdorff_goals.csv'"
  run resolution "$b/bench_resolution" --csv "$out/resolution.csv"
  run control "$b/bench_control" --csv "$out/control.csv"
  run stability "$b/bench_stability" --max-iter 25 --csv "$out/stability.csv"
  # softhd optimise on bending, torsion and the finger with MMA and newton, one run at a time,
  # each from its own clock (about 12 minutes on 2 cores; --mesh-independence adds 12 more).
  run time_to_floor /usr/bin/python3 "$here/bench/bench_time_to_floor.py" "$build" \
    --csv "$out/time_to_floor.csv"
  # softhd forward against FEniCS (skipped, with a line, without python3-dolfin).
  run forward_fenics /usr/bin/python3 "$here/bench/bench_forward_fenics.py" "$build" \
    --repeats 3 --csv "$out/forward_fenics.csv"
  # The Gmsh finger's state solve against FEniCS on the same tetrahedra (FEniCS skipped, with a
  # line, without python3-dolfin); its optimisation is in time_to_floor.
  run finger /usr/bin/python3 "$here/bench/bench_finger.py" "$build" --repeats 1 \
    --csv "$out/finger.csv"
  # softhd align against Open3D's FPFH + RANSAC + ICP (issue 32; Open3D skipped, with a
  # line, without python3-open3d): 30 poses x 2 views (100 took 21 minutes, a third of the
  # hour make bench may take; its wall time in docs/bench/align.meta).
  align_bench --poses 30 --distance scan_to_body
  # The Python module: overhead over C++ and HausdorffLoss against plain PyTorch (issue 14).
  python_bench --n 10000 --torch-n 10000 --repeats 5
  # The distance integrated over cells against collocation: the cubes and the plate against
  # their continuum values, and the bending loop's cost (about 10 minutes on 2 cores).
  run cells "$b/bench_cells" --csv "$out/cells.csv"
fi
/usr/bin/python3 "$here/bench/make_report.py" "$out" --report "$report" $([ $quick -eq 1 ] && echo --quick)
echo "report: $report" >&2
