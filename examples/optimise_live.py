#!/usr/bin/env python3
"""An optimisation driven from Python with a live progress line.

    python3 examples/optimise_live.py [SCENE] [--cells 25 3 2] [--max-iter 30] [--stop-below K]

Loads a scene (default data/scenes/bending.json: the plate bent into a half circle), optionally
on a coarser mesh, and runs softhd.optimise with a callback that rewrites one status line per
iteration (iteration, J, rho, rho/floor, elapsed time) and ends the run early, by returning
False, once rho falls below K times the floor.
"""

import argparse
import json
import os
import sys
import tempfile

import softhd

HERE = os.path.dirname(os.path.abspath(__file__))


def scene_with_cells(path, cells, directory):
    """A copy of the scene file with other mesh cells (files it names stay relative to it)."""
    with open(path) as f:
        scene = json.load(f)
    scene["mesh"]["cells"] = cells
    target = scene.get("target", {})
    for key in ("file", "solved_on"):
        if key in target:
            target[key] = os.path.join(os.path.dirname(os.path.abspath(path)), target[key])
    out = os.path.join(directory, os.path.basename(path))
    with open(out, "w") as f:
        json.dump(scene, f)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene", nargs="?",
                    default=os.path.join(HERE, "..", "data", "scenes", "bending.json"))
    ap.add_argument("--cells", type=int, nargs="+", help="mesh cells per axis")
    ap.add_argument("--max-iter", type=int, default=30)
    ap.add_argument("--stop-below", type=float, default=0.0,
                    help="end the run once rho <= this times the floor (0: never)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = scene_with_cells(args.scene, args.cells, tmp) if args.cells else args.scene
        scene = softhd.Scene.load(path)
        print(f"{scene.name}: {len(scene.nodes)} nodes, {scene.num_controls} controls",
              flush=True)

        def progress(it):
            sys.stderr.write(f"\r  iteration {it.iteration:4d}  J {it.J:11.5g}  rho {it.rho:11.5g}"
                             f"  rho/floor {it.rho_over_floor:8.3g}  {it.seconds:7.1f} s")
            sys.stderr.flush()
            return not (args.stop_below > 0 and it.rho_over_floor <= args.stop_below)

        r = softhd.optimise(scene, max_iter=args.max_iter, callback=progress)
        sys.stderr.write("\n")
    print(f"{r.termination} after {r.iterations} iterations, {r.seconds:.1f} s")
    floor = r.floor_matched or r.floor_self
    print(f"rho {r.rho_start:.5g} -> {r.rho_final:.5g}"
          + (f" ({r.rho_final / floor:.3g} x floor)" if floor else ""))
    if r.shape_error_max is not None:
        print(f"shape error max {r.shape_error_max:.4g}, rms {r.shape_error_rms:.4g}")


if __name__ == "__main__":
    main()
