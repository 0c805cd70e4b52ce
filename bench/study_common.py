"""Helpers shared by the study scripts in bench/: running the CLI with a log, and reading its outputs."""

import json
import os
import subprocess


def run(command, log_path):
    """Runs a command, its output appended to log_path; raises with the log's tail on failure."""
    os.makedirs(os.path.dirname(os.path.abspath(log_path)), exist_ok=True)
    with open(log_path, "a") as log:
        log.write("$ " + " ".join(command) + "\n")
        log.flush()
        result = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT)
    if result.returncode != 0:
        with open(log_path) as log:
            tail = log.read()[-2000:]
        raise RuntimeError(f"{' '.join(command)} failed ({result.returncode}):\n{tail}")


def read_json(path):
    with open(path) as f:
        return json.load(f)


def procedural_scene(exe, work):
    """Makes the built-in procedural scene (64x64, with its multiscale copy) in work/procedural once."""
    folder = os.path.join(work, "procedural")
    if not os.path.exists(os.path.join(folder, "multiscale", "metadata.json")):
        run([exe, "make-scene", folder, "--size", "64"], os.path.join(work, "make-scene.log"))
    return folder


def device_line(device):
    return f"{device.get('name')} ({device.get('platform')}, driver {device.get('driver_version')})"
