#!/usr/bin/env python3
"""Runs the commands of docs/guide.md (CTest: guide_commands), so that the guide cannot rot.

    scripts/run_guide.py GUIDE BIN_DIR [WORK_DIR]

Every fenced block tagged `sh` is run with bash, in order, in one scratch directory
(WORK_DIR, emptied first; a temporary one if not given), with BIN_DIR first on PATH and
OMP_NUM_THREADS=1. A block must exit with status 0, except a block containing the line
`# expect exit status 2`, which must exit with status 2 and print (stdout or stderr) every
non-empty line of the `text` block that follows it. Exit status 0 if every block behaved.
"""

import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

FENCE = re.compile(r"^```(\w*)\s*\n(.*?)^```\s*$", re.MULTILINE | re.DOTALL)
EXPECT_FAILURE = "# expect exit status 2"


def blocks(guide_text):
    """(language, body, line number) of every fenced block, in order."""
    for m in FENCE.finditer(guide_text):
        yield m.group(1), m.group(2), guide_text.count("\n", 0, m.start()) + 1


def main(argv):
    if len(argv) < 3:
        print(__doc__)
        return 2
    guide, bin_dir = os.path.abspath(argv[1]), os.path.abspath(argv[2])
    work = os.path.abspath(argv[3]) if len(argv) > 3 else tempfile.mkdtemp(prefix="softhd-guide-")
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    env = dict(os.environ, PATH=bin_dir + os.pathsep + os.environ.get("PATH", ""),
               OMP_NUM_THREADS="1", MPLBACKEND="Agg")
    with open(guide, encoding="utf-8") as f:
        items = list(blocks(f.read()))
    failures, ran = 0, 0
    start = time.time()
    for k, (lang, body, line) in enumerate(items):
        if lang != "sh":
            continue
        ran += 1
        expect_failure = EXPECT_FAILURE in body.splitlines()
        flags = ["-o", "pipefail"] if expect_failure else ["-e", "-o", "pipefail"]
        r = subprocess.run(["bash", *flags, "-c", body], cwd=work, env=env,
                           capture_output=True, text=True, timeout=300)
        output = r.stdout + r.stderr
        problem = None
        if expect_failure:
            if r.returncode != 2:
                problem = f"exit status {r.returncode}, expected 2"
            else:
                following = items[k + 1] if k + 1 < len(items) else None
                if following is None or following[0] != "text":
                    problem = "a failure block must be followed by a text block"
                else:
                    missing = [x.strip() for x in following[1].splitlines()
                               if x.strip() and x.strip() not in output]
                    if missing:
                        problem = f"output lacks {missing}"
        elif r.returncode != 0:
            problem = f"exit status {r.returncode}"
        if problem:
            failures += 1
            print(f"{guide}:{line}: FAILED ({problem})\n--- block ---\n{body}--- output ---\n"
                  f"{output}--- end ---")
        else:
            print(f"{guide}:{line}: ok")
    print(f"{ran} blocks run in {time.time() - start:.1f} s in {work}, {failures} failed")
    return 1 if failures or ran == 0 else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
