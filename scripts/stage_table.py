#!/usr/bin/env python3
"""The closing table of scripts/test.sh, and its exit status.

Reads the rows test.sh recorded (stage, platform: device, JUnit file or "", note, seconds), counts each stage's tests
from its JUnit file (CTest's --output-junit, or mipnerf-selftest's --junit), prints one table, and exits 1 when any
stage failed, ran no test, could not run, did not record a row at all (every stage of STAGES must), was left out, or
skipped a test. A test CTest did not run (its executable missing, a fixture it needs failed, disabled) fails the
command always. With --allow-skips (local work only) skipped tests and stages left out by MIPNERF_SKIP are allowed,
and the table and the last line say so: a stage that did not do what it says never passes silently.
"""
import argparse
import os
import sys
import xml.etree.ElementTree as ElementTree

# Every stage of the test command (scripts/test.sh). A stage that records no row fails the command, so removing a
# stage from test.sh fails it too, until it is removed here (and from docs/testing.md) on purpose.
STAGES = ("pocl", "mpi", "oclgrind", "sanitizer", "fuzz", "tsan", "intel", "selftest", "browser")

# CTest's messages for a test that said it could not run here: it ended with its SKIP_RETURN_CODE
# (tests/support/skip.hpp), or printed its SKIP_REGULAR_EXPRESSION (the CLI's COLMAP tests in a build without COLMAP).
# Any other test CTest did not run ("Unable to find executable", "Fixture dependency failed", disabled) is a test
# that was meant to run and did not.
CTEST_SKIP_MESSAGES = ("SKIP_RETURN_CODE=", "SKIP_REGULAR_EXPRESSION_MATCHED")


def classify(case):
    """'failed', 'skipped', 'not run' or 'passed' for one <testcase>."""
    status = case.get("status")
    if case.find("failure") is not None or case.find("error") is not None or status == "fail":
        return "failed"
    if status == "disabled":
        return "not run"
    skipped = case.find("skipped")
    if status == "notrun":
        message = skipped.get("message", "") if skipped is not None else ""
        return "skipped" if message.startswith(CTEST_SKIP_MESSAGES) else "not run"
    if skipped is not None:  # mipnerf-selftest's JUnit: a check it could not run on this device or build
        return "skipped"
    return "passed"


def count(junit_path):
    """{'tests', 'passed', 'failed', 'skipped', 'not run', 'not run names'} of a JUnit file, or None when it is
    missing or unreadable."""
    if not junit_path or not os.path.exists(junit_path):
        return None
    try:
        root = ElementTree.parse(junit_path).getroot()
    except ElementTree.ParseError:
        return None
    counts = {"tests": 0, "passed": 0, "failed": 0, "skipped": 0, "not run": 0, "not run names": []}
    for case in root.iter("testcase"):
        counts["tests"] += 1
        kind = classify(case)
        counts[kind] += 1
        if kind == "not run":
            skipped = case.find("skipped")
            why = skipped.get("message", "") if skipped is not None else case.get("status", "")
            counts["not run names"].append(f"{case.get('name', '?')} ({why})")
    return counts


def judge(stage, where, junit, note, allow_skips, problems):
    """The verdict of one row and its counts; appends what is wrong to `problems`."""
    counts = count(junit) if junit else None
    if note.startswith("left out by request"):
        if not allow_skips:
            problems.append(f"{stage}: {note}; only --allow-skips (local work) may leave a stage out")
            return "FAILED: left out", counts
        return "left out (--allow-skips)", counts
    if note.startswith("could not run"):
        problems.append(f"{stage}: {note}")
        return "FAILED", counts
    if counts is None:
        problems.append(f"{stage} on {where}: no test results were written (the stage did not run)")
        return "FAILED", counts
    verdict = "ok"
    tests, failed, skipped, not_run = counts["tests"], counts["failed"], counts["skipped"], counts["not run"]
    if note.startswith("exit ") and note != "exit 0" and failed == 0:
        problems.append(f"{stage} on {where}: {note} although no test failed")
        verdict = "FAILED"
    if tests == 0:
        problems.append(f"{stage} on {where}: ran 0 tests")
        verdict = "FAILED"
    if failed:
        problems.append(f"{stage} on {where}: {failed} of {tests} tests failed")
        verdict = "FAILED"
    if not_run:
        names = "; ".join(counts["not run names"][:5]) + (" …" if not_run > 5 else "")
        problems.append(f"{stage} on {where}: {not_run} tests did not run: {names}")
        verdict = "FAILED"
    if skipped and not allow_skips:
        problems.append(f"{stage} on {where}: {skipped} tests skipped (a dependency missing here); every test must "
                        "run (--allow-skips for local work)")
        verdict = "FAILED"
    elif skipped and verdict == "ok":
        verdict = "ok, with skips (--allow-skips)"
    return verdict, counts


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows")
    parser.add_argument("--allow-skips", action="store_true",
                        help="local work: skipped tests and stages left out by MIPNERF_SKIP do not fail")
    parser.add_argument("--seconds", type=int, default=0)
    args = parser.parse_args()
    rows = []
    if os.path.exists(args.rows):
        with open(args.rows, encoding="utf-8") as f:
            rows = [line.rstrip("\n").split("\t") for line in f if line.strip()]
    problems = []
    table = []
    for stage, where, junit, note, seconds in rows:
        verdict, counts = judge(stage, where, junit, note, args.allow_skips, problems)
        shown = [str(counts[k]) for k in ("tests", "passed", "failed", "skipped", "not run")] if counts else ["-"] * 5
        shown_note = "" if note.startswith("exit ") or note.startswith("left out") else note
        table.append((stage, where, *shown, seconds, verdict + (f": {shown_note}" if shown_note else "")))
    recorded = {row[0] for row in rows}
    for stage in STAGES:
        if stage not in recorded:
            problems.append(f"{stage}: the stage recorded no row (removed from scripts/test.sh, or it ended early)")
            table.append((stage, "-", "-", "-", "-", "-", "-", "0", "FAILED: did not run"))
    header = ("stage", "platform: device", "tests", "passed", "failed", "skipped", "not run", "seconds", "verdict")
    print("\n| " + " | ".join(header) + " |")
    print("|" + "|".join("---" for _ in header) + "|")
    for row in table:
        print("| " + " | ".join(row) + " |")
    print(f"\ntest: {args.seconds} s in all" + (" (--allow-skips)" if args.allow_skips else ""))
    if problems:
        for problem in problems:
            print(f"test: FAILED: {problem}", file=sys.stderr)
        return 1
    skipped_any = any(r[5] not in ("0", "-") for r in table) or any(r[8].startswith("left out") for r in table)
    if skipped_any:
        print("test: passed with skips allowed (--allow-skips): some tests or stages did not run; the test command "
              "without it (and CI) fails on them")
    else:
        print("test: every stage passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
