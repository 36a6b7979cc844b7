#!/usr/bin/env python3
"""Checks the repository's citations of its own formulation (CTest: doc_references).

    scripts/check_doc_refs.py [ROOT]     exit 0 if clean, 1 with one line per problem
    scripts/check_doc_refs.py --self-test

Fails when
  * any text file cites the former outside specification by its old name (the word is
    spelled in two parts below so that this file does not match itself), or
  * a citation "formulation.md §N" / "formulation.md section N" (also every further §N
    of a list like "formulation.md §2, §5" or "§5.1/§6.2") names a section that is not
    a numbered heading of docs/formulation.md, or
  * docs/formulation.md refers to one of its own sections (§N) that does not exist.

Files: those git tracks plus untracked ones not ignored (so a new file is checked before
its commit); without git, every file under ROOT except build*/ results/ out/ .git/.
"""

import os
import re
import subprocess
import sys
import tempfile

OLD_NAME = re.compile(r"\b" + "S" "PEC" + r"\b")
HEADING = re.compile(r"^#{2,6}\s+(\d+(?:\.\d+)*)\.?\s", re.MULTILINE)
SECTION = r"\d+(?:\.\d+)*"
CITATION = re.compile(r"formulation\.md\)?\s*((?:§|section\s+)" + SECTION +
                      r"(?:\s*(?:,|/|and)\s*§" + SECTION + r")*)")
NUMBER = re.compile(SECTION)
SELF_REFERENCE = re.compile(r"(?<![\w.])§(" + SECTION + r")")
SKIP_DIRS = {".git", "results", "out", "__pycache__"}


def files_of(root):
    try:
        out = subprocess.run(
            ["git", "-C", root, "ls-files", "-z", "--cached", "--others", "--exclude-standard"],
            check=True, capture_output=True).stdout.decode()
        return sorted({p for p in out.split("\0") if p})
    except (OSError, subprocess.CalledProcessError):
        found = []
        for d, dirs, names in os.walk(root):
            dirs[:] = [x for x in dirs if x not in SKIP_DIRS and not x.startswith("build")]
            found += [os.path.relpath(os.path.join(d, n), root) for n in names]
        return sorted(found)


def read_text(path):
    try:
        with open(path, "rb") as f:
            data = f.read()
    except OSError:
        return None
    if b"\0" in data:
        return None  # binary (e.g. a PLY cloud)
    return data.decode("utf-8", errors="replace")


def sections_of(formulation_text):
    return set(HEADING.findall(formulation_text))


def check(root):
    problems = []
    formulation = read_text(os.path.join(root, "docs", "formulation.md"))
    if formulation is None:
        return ["docs/formulation.md: missing"]
    sections = sections_of(formulation)
    if not sections:
        return ["docs/formulation.md: no numbered headings ('## 1. ...')"]
    for rel in files_of(root):
        text = read_text(os.path.join(root, rel))
        if text is None:
            continue
        for lineno, line in enumerate(text.splitlines(), 1):
            if OLD_NAME.search(line):
                problems.append(f"{rel}:{lineno}: cites the old specification: {line.strip()}")
            for m in CITATION.finditer(line):
                for number in NUMBER.findall(m.group(1)):
                    if number not in sections:
                        problems.append(f"{rel}:{lineno}: formulation.md has no section "
                                        f"{number}: {line.strip()}")
            if rel == "docs/formulation.md" and not line.startswith("#"):
                for number in SELF_REFERENCE.findall(line):
                    if number not in sections:
                        problems.append(f"{rel}:{lineno}: no section {number}: {line.strip()}")
    return problems


def self_test():
    """The checker must find planted problems and accept a clean tree."""
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "docs"))
        with open(os.path.join(root, "docs", "formulation.md"), "w") as f:
            f.write("# T\n\n## 1. One\n\nSee §1.2 and §1.\n\n### 1.2 Two\n\n## 2. Three\n")
        with open(os.path.join(root, "good.cpp"), "w") as f:
            f.write("// docs/formulation" ".md §1.2, §2 and section 1\n")
        clean = check(root)
        assert clean == [], clean
        with open(os.path.join(root, "bad.cpp"), "w") as f:
            f.write("// " + "S" "PEC" + " §2\n// docs/formulation" ".md §1.2/§7.1\n"
                    "// docs/formulation" ".md section 3\n")
        with open(os.path.join(root, "docs", "formulation.md"), "a") as f:
            f.write("\nAs in §9.\n")
        found = check(root)
        expect = ["bad.cpp:1: cites the old", "bad.cpp:2: formulation.md has no section 7.1",
                  "bad.cpp:3: formulation.md has no section 3", "docs/formulation.md:11: no section 9"]
        for e in expect:
            assert any(p.startswith(e) for p in found), (e, found)
        assert len(found) == len(expect), found
    print("check_doc_refs self-test: planted problems found, clean tree accepted")
    return 0


def main(argv):
    if len(argv) > 1 and argv[1] == "--self-test":
        return self_test()
    root = argv[1] if len(argv) > 1 else os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    problems = check(root)
    for p in problems:
        print(p)
    if problems:
        print(f"{len(problems)} problem(s); scripts/replace_spec_refs.py rewrites old citations")
        return 1
    print(f"doc references: {len(sections_of(read_text(os.path.join(root, 'docs', 'formulation.md'))))}"
          " sections, no old citations, every formulation.md reference resolves")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
