#!/usr/bin/env python3
"""Runs a command with its output passed through unchanged and writes, to the file named first, how many milliseconds
passed until the command's output first contained a given text (scripts/quickstart.sh: until training's first
progress line, i.e. its first step). Exits with the command's exit status.

Usage: time_to_output.py MILLISECONDS_FILE TEXT -- COMMAND [ARGS...]
Under a terminal the command runs on a pseudo-terminal, so it still sees one and keeps its live progress bar;
otherwise its stderr is read through a pipe, where it writes a line per update anyway."""
import os
import pty
import subprocess
import sys
import time


def main() -> int:
    if len(sys.argv) < 5 or sys.argv[3] != "--":
        sys.exit("usage: time_to_output.py MILLISECONDS_FILE TEXT -- COMMAND [ARGS...]")
    milliseconds_file, text, command = sys.argv[1], sys.argv[2].encode(), sys.argv[4:]
    start = time.monotonic()
    seen = b""  # the output so far, kept only until the text shows (a line may arrive in pieces)
    found = False

    def watch(chunk: bytes) -> bytes:
        nonlocal seen, found
        if not found:
            seen = (seen + chunk)[-4096:]
            if text in seen:
                found = True
                with open(milliseconds_file, "w") as out:
                    out.write(f"{round(1000 * (time.monotonic() - start))}\n")
        return chunk

    if sys.stderr.isatty():
        status = pty.spawn(command, lambda fd: watch(os.read(fd, 4096)))
        return os.waitstatus_to_exitcode(status)
    process = subprocess.Popen(command, stderr=subprocess.PIPE)
    for chunk in iter(lambda: os.read(process.stderr.fileno(), 4096), b""):
        sys.stderr.buffer.write(watch(chunk))
        sys.stderr.buffer.flush()
    return process.wait()


if __name__ == "__main__":
    sys.exit(main())
