"""The one way the studies run a command: its output to a log (appended) or captured, a timeout, and on failure an
exception that names the command, its exit status and the output's tail. Standard library only."""

import os
import subprocess


class RunError(RuntimeError):
    """A command that failed or ran past its timeout; the message holds the command and the output's tail."""


def run(command, log_path=None, env=None, timeout=None):
    """Runs `command` (a list). With log_path: its output (stdout and stderr) appended there after a `$ command`
    line, and "" returned; without: its stdout returned (stderr kept for the error). Raises RunError when it exits
    non-zero or runs past `timeout` seconds."""
    shown = " ".join(map(str, command))
    try:
        if log_path is None:
            result = subprocess.run(command, capture_output=True, text=True, env=env, timeout=timeout)
            if result.returncode != 0:
                raise RunError(f"{shown} failed ({result.returncode}):\n{(result.stderr or result.stdout)[-2000:]}")
            return result.stdout
        os.makedirs(os.path.dirname(os.path.abspath(log_path)), exist_ok=True)
        with open(log_path, "a") as log:
            log.write("$ " + shown + "\n")
            log.flush()
            result = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        raise RunError(f"{shown}: still running after {timeout} s; stopped" +
                       (f" (its output: {log_path})" if log_path else "")) from None
    if result.returncode != 0:
        with open(log_path) as log:
            tail = log.read()[-2000:]
        raise RunError(f"{shown} failed ({result.returncode}); the end of {log_path}:\n{tail}")
    return ""
