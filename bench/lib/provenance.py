"""Which tree, binary and machine a study measured: one rule for every study in bench/.

tree_state() is strict: a checkout differs from its commit when a tracked file differs or when an untracked file
that git does not ignore is present (it may be a source the build picked up), except under build*/ and runs/ (build
and run folders). Before this module, study_common.commit_of and from_photos.tree_state ignored untracked files while
vs_official.tree_state counted them, so one checkout was recorded clean by one study and dirty by another.
Standard library only (the device check runs it with whatever python3 is there).
"""

import hashlib
import os
import platform
import subprocess

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

DIFF_COVERS = ("git diff HEAD --binary, then each untracked file (not under build*/ or runs/): path, NUL, bytes, NUL, "
               "in sorted order")


def _git(repo, *args, binary=False):
    """git's output (read-only: no index refresh, no locks), or None when git fails or is not there."""
    try:
        r = subprocess.run(["git", "--no-optional-locks", "-C", repo, *args], capture_output=True, text=not binary)
    except OSError:
        return None
    return r.stdout if r.returncode == 0 else None


def ignored_untracked(path):
    """Untracked paths the tree check ignores: build folders (build*/) and run folders (runs/)."""
    top = path.split("/", 1)[0]
    return ("/" in path or path.endswith("/")) and (top.startswith("build") or top == "runs")


def _dirty_paths(repo):
    """`XY path` of each change `git status --porcelain` lists (untracked files one by one), but ignored_untracked."""
    status = _git(repo, "status", "--porcelain", "-z", "--untracked-files=all")
    if status is None:
        return None
    fields = status.split("\0")
    paths, i = [], 0
    while i < len(fields):
        entry = fields[i]
        i += 1
        if len(entry) < 4:
            continue
        code, path = entry[:2], entry[3:]
        if "R" in code or "C" in code:  # a rename or copy: the next field is the original path
            path = f"{fields[i]} -> {path}"
            i += 1
        if code == "??" and ignored_untracked(path):
            continue
        paths.append(f"{code} {path}")
    return paths


def tree_state(repo=REPO):
    """{"commit", "dirty", "dirty_paths"} and, when dirty, "diff_sha256" over what differs (DIFF_COVERS) and
    "diff_covers"; {"commit": "unknown", "dirty": None} outside a git checkout."""
    commit = _git(repo, "rev-parse", "HEAD")
    dirty_paths = _dirty_paths(repo)
    if commit is None or dirty_paths is None:
        return {"commit": "unknown", "dirty": None, "dirty_paths": []}
    state = {"commit": commit.strip(), "dirty": bool(dirty_paths), "dirty_paths": dirty_paths}
    if dirty_paths:
        h = hashlib.sha256(_git(repo, "diff", "HEAD", "--binary", binary=True) or b"")
        for line in sorted(dirty_paths):
            if line.startswith("?? "):
                path = line[3:]
                h.update(path.encode() + b"\0")
                with open(os.path.join(repo, path), "rb") as f:
                    h.update(f.read())
                h.update(b"\0")
        state["diff_sha256"] = h.hexdigest()
        state["diff_covers"] = DIFF_COVERS
    return state


def commit_of(repo=REPO):
    """The checkout's short commit, with -dirty when tree_state says it differs; "unknown" outside a checkout."""
    state = tree_state(repo)
    if state["commit"] == "unknown":
        return "unknown"
    return state["commit"][:7] + ("-dirty" if state["dirty"] else "")


def file_sha256(path):
    """The sha256 of a file (an executable, a dataset file), read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def cpu_model():
    """The CPU's model name from /proc/cpuinfo, or "unknown"."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"
