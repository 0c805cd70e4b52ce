#!/usr/bin/env python3
"""The closing table of scripts/test.sh, and its exit status.

Reads the rows test.sh recorded (stage, platform: device, JUnit file or "", note, seconds), counts each stage's tests
from its JUnit file (CTest's --output-junit, or mipnerf-selftest's --junit), prints one table, and exits 1 when any
stage failed, ran no test, could not run, or (with --ci true) skipped a test: a stage that did not do what it says
never passes silently.
"""
import argparse
import os
import sys
import xml.etree.ElementTree as ElementTree


def count(junit_path):
    """(tests, passed, failed, skipped) of a JUnit file, or None when it is missing or unreadable."""
    if not junit_path or not os.path.exists(junit_path):
        return None
    try:
        root = ElementTree.parse(junit_path).getroot()
    except ElementTree.ParseError:
        return None
    cases = root.iter("testcase")
    tests = passed = failed = skipped = 0
    for case in cases:
        tests += 1
        status = case.get("status", "run")
        if case.find("failure") is not None or case.find("error") is not None or status == "fail":
            failed += 1
        elif case.find("skipped") is not None or status in ("notrun", "disabled"):
            skipped += 1
        else:
            passed += 1
    return tests, passed, failed, skipped


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("rows")
    parser.add_argument("--ci", default="false")
    parser.add_argument("--seconds", type=int, default=0)
    args = parser.parse_args()
    ci = args.ci == "true"
    rows = []
    if os.path.exists(args.rows):
        with open(args.rows, encoding="utf-8") as f:
            rows = [line.rstrip("\n").split("\t") for line in f if line.strip()]
    problems = []
    table = []
    for stage, where, junit, note, seconds in rows:
        counts = count(junit) if junit else None
        verdict = "ok"
        if note.startswith("left out by request"):
            verdict = "left out"
        elif note.startswith("could not run"):
            verdict = "FAILED"
            problems.append(f"{stage}: {note}")
        elif counts is None:
            verdict = "FAILED"
            problems.append(f"{stage} on {where}: no test results were written (the stage did not run)")
        else:
            tests, passed, failed, skipped = counts
            if note.startswith("exit ") and note != "exit 0" and failed == 0:
                problems.append(f"{stage} on {where}: {note} although no test failed")
                verdict = "FAILED"
            if tests == 0:
                problems.append(f"{stage} on {where}: ran 0 tests")
                verdict = "FAILED"
            if failed:
                problems.append(f"{stage} on {where}: {failed} of {tests} tests failed")
                verdict = "FAILED"
            if skipped and ci:
                problems.append(f"{stage} on {where}: {skipped} tests skipped, and in CI every test must run")
                verdict = "FAILED"
            elif skipped and verdict == "ok":
                verdict = "ok, with skips"
        c = counts or ("-", "-", "-", "-")
        shown_note = "" if note.startswith("exit ") else note
        table.append((stage, where, *[str(x) for x in c], seconds, verdict + (f": {shown_note}" if shown_note else "")))
    if not table:
        problems.append("no stage ran")
    header = ("stage", "platform: device", "tests", "passed", "failed", "skipped", "seconds", "verdict")
    print("\n| " + " | ".join(header) + " |")
    print("|" + "|".join("---" for _ in header) + "|")
    for row in table:
        print("| " + " | ".join(row) + " |")
    print(f"\ntest: {args.seconds} s in all" + (" (CI)" if ci else ""))
    if problems:
        for problem in problems:
            print(f"test: FAILED: {problem}", file=sys.stderr)
        return 1
    print("test: every stage passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
