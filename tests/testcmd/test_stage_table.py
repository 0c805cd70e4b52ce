#!/usr/bin/env python3
"""The test command's verdict (scripts/stage_table.py) on made-up stage results: it must fail when a stage is removed
or left out, when a test is skipped (unless --allow-skips), when CTest did not run a test (a missing executable, a
failed fixture; --allow-skips or not), when a stage ran no test, and pass only when every stage ran every test.

  tests/testcmd/test_stage_table.py --script scripts/stage_table.py --test-sh scripts/test.sh

It also checks that scripts/test.sh runs the very stages this file and the table know.

Exit 0 when every case gave the verdict it must, 1 otherwise.
"""
import argparse
import os
import re
import subprocess
import sys
import tempfile

STAGES = ("pocl", "mpi", "oclgrind", "sanitizer", "fuzz", "tsan", "intel", "selftest", "browser")


def junit(path, cases):
    """A CTest-style JUnit file; each case is 'pass', 'fail', 'skip' (SKIP_RETURN_CODE), 'skip-regex'
    (SKIP_REGULAR_EXPRESSION), 'missing' (Unable to find
    executable), 'fixture' (Fixture dependency failed), 'disabled' or 'selftest-skip' (mipnerf-selftest's row)."""
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', f'<testsuite tests="{len(cases)}">']
    for i, case in enumerate(cases):
        name = f'name="t{i}"'
        if case == "pass":
            lines.append(f'<testcase {name} status="run"></testcase>')
        elif case == "fail":
            lines.append(f'<testcase {name} status="fail"><failure message=""/></testcase>')
        elif case == "skip":
            lines.append(f'<testcase {name} status="notrun"><skipped message="SKIP_RETURN_CODE=77"/></testcase>')
        elif case == "skip-regex":
            lines.append(f'<testcase {name} status="notrun"><skipped message="SKIP_REGULAR_EXPRESSION_MATCHED"/>'
                         '</testcase>')
        elif case == "missing":
            lines.append(f'<testcase {name} status="notrun"><skipped message="Unable to find executable"/></testcase>')
        elif case == "fixture":
            lines.append(f'<testcase {name} status="notrun"><skipped message="Fixture dependency failed"/></testcase>')
        elif case == "disabled":
            lines.append(f'<testcase {name} status="disabled"></testcase>')
        elif case == "selftest-skip":
            lines.append(f'<testcase {name}><skipped message="no other CPU device"/></testcase>')
    lines.append("</testsuite>")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(lines))


def verdict(script, folder, stage_cases, notes=None, allow_skips=False):
    """The exit status and output of stage_table.py for stages with these cases (None: no row for that stage)."""
    rows = []
    for stage, cases in stage_cases.items():
        if cases is None:
            continue
        note = (notes or {}).get(stage, "")
        if note.startswith("left out"):
            rows.append(f"{stage}\t-\t\t{note}\t0")
            continue
        path = os.path.join(folder, f"{stage}.xml")
        junit(path, cases)
        rows.append(f"{stage}\tplatform: device\t{path}\t{note}\t1")
    rows_path = os.path.join(folder, "rows.tsv")
    with open(rows_path, "w", encoding="utf-8") as f:
        f.write("\n".join(rows) + "\n")
    command = [sys.executable, script, rows_path] + (["--allow-skips"] if allow_skips else [])
    done = subprocess.run(command, capture_output=True, text=True)
    return done.returncode, done.stdout + done.stderr


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--script", required=True)
    parser.add_argument("--test-sh", required=True)
    args = parser.parse_args()
    failures = []
    with open(args.test_sh, encoding="utf-8") as f:
        listed = re.search(r'^stages="([^"]*)"', f.read(), re.MULTILINE)
    in_test_sh = tuple(listed.group(1).split()) if listed else ()
    same = sorted(in_test_sh) == sorted(STAGES)
    print(("ok:     " if same else "FAILED: ") + f"scripts/test.sh's stages {in_test_sh} are the table's {STAGES}")
    if not same:
        failures.append("stage lists")
    with tempfile.TemporaryDirectory() as folder:
        def expect(name, status, text, **kwargs):
            got, output = verdict(args.script, folder, **kwargs)
            ok = (got == 0) == (status == 0) and text in output
            print(("ok:     " if ok else "FAILED: ") + f"{name} (exit {got})", flush=True)
            if not ok:
                failures.append(name)
                print(output)

        every = {stage: ["pass", "pass"] for stage in STAGES}
        expect("every stage ran every test: passes", 0, "test: every stage passed", stage_cases=every)
        for stage in ("tsan", "intel", "browser"):
            removed = dict(every, **{stage: None})
            expect(f"stage '{stage}' removed from the command: fails", 1,
                   f"{stage}: the stage recorded no row", stage_cases=removed)
            expect(f"stage '{stage}' removed, even with --allow-skips: fails", 1,
                   f"{stage}: the stage recorded no row", stage_cases=removed, allow_skips=True)
        left_out = {"intel": "left out by request (MIPNERF_SKIP)"}
        expect("a stage left out by MIPNERF_SKIP: fails", 1, "only --allow-skips", stage_cases=every, notes=left_out)
        expect("a stage left out by MIPNERF_SKIP with --allow-skips: passes, saying so", 0,
               "passed with skips allowed", stage_cases=every, notes=left_out, allow_skips=True)
        skipped = dict(every, pocl=["pass", "skip"])
        expect("a skipped test: fails", 1, "1 tests skipped", stage_cases=skipped)
        expect("a skipped test with --allow-skips: passes, saying so", 0, "passed with skips allowed",
               stage_cases=skipped, allow_skips=True)
        expect("a test skipped by its output (SKIP_REGULAR_EXPRESSION): fails", 1, "1 tests skipped",
               stage_cases=dict(every, pocl=["pass", "skip-regex"]))
        expect("a skipped self-test check: fails", 1, "1 tests skipped",
               stage_cases=dict(every, selftest=["pass", "selftest-skip"]))
        for kind, text in (("missing", "Unable to find executable"), ("fixture", "Fixture dependency failed"),
                           ("disabled", "disabled")):
            expect(f"a test CTest did not run ({kind}): fails", 1, text, stage_cases=dict(every, pocl=["pass", kind]))
            expect(f"a test CTest did not run ({kind}), with --allow-skips: fails", 1, text,
                   stage_cases=dict(every, pocl=["pass", kind]), allow_skips=True)
        expect("a failed test: fails", 1, "1 of 2 tests failed", stage_cases=dict(every, oclgrind=["pass", "fail"]))
        expect("a stage that ran no test: fails", 1, "ran 0 tests", stage_cases=dict(every, mpi=[]))
        expect("a stage that exited non-zero with no failed test: fails", 1, "exit 1 although no test failed",
               stage_cases=every, notes={"selftest": "exit 1"})
    if failures:
        print(f"stage table: {len(failures)} cases gave the wrong verdict", file=sys.stderr)
        return 1
    print("stage table: every case gave its verdict")
    return 0


if __name__ == "__main__":
    sys.exit(main())
