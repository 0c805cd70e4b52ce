#!/usr/bin/env python3
"""bench/lib/provenance.py, the one rule every study records its tree by (CTest: `bench: provenance ...`): on a
scratch git repository, a clean tree, a changed tracked file, an untracked source (dirty: the old commit_of of
study_common (now lib/cli_runs) and from_photos' tree_state said clean), untracked files under build*/ and runs/ (clean), and the
changes' hash following an untracked file's bytes.

Usage: test_provenance.py BENCH_DIR"""

import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, sys.argv.pop(1) if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "../../bench"))
from lib import provenance  # noqa: E402
from lib import cli_runs  # noqa: E402


def git(repo, *args):
    subprocess.run(["git", "-C", repo, *args], check=True, capture_output=True,
                   env={**os.environ, "GIT_AUTHOR_NAME": "t", "GIT_AUTHOR_EMAIL": "t@t", "GIT_COMMITTER_NAME": "t",
                        "GIT_COMMITTER_EMAIL": "t@t"})


def write(repo, path, text):
    full = os.path.join(repo, path)
    os.makedirs(os.path.dirname(full), exist_ok=True)
    with open(full, "w") as f:
        f.write(text)


class TreeState(unittest.TestCase):
    def setUp(self):
        self.scratch = tempfile.TemporaryDirectory()
        self.repo = self.scratch.name
        git(self.repo, "init", "-q")
        write(self.repo, "host/a.cpp", "int a;\n")
        write(self.repo, ".gitignore", "*.o\n")
        git(self.repo, "add", "-A")
        git(self.repo, "commit", "-q", "-m", "one")

    def tearDown(self):
        self.scratch.cleanup()

    def test_clean(self):
        state = provenance.tree_state(self.repo)
        self.assertEqual(len(state["commit"]), 40)
        self.assertIs(state["dirty"], False)
        self.assertNotIn("diff_sha256", state)
        self.assertEqual(provenance.commit_of(self.repo), state["commit"][:7])

    def test_changed_tracked_file(self):
        write(self.repo, "host/a.cpp", "int a = 1;\n")
        state = provenance.tree_state(self.repo)
        self.assertIs(state["dirty"], True)
        self.assertEqual(state["dirty_paths"], [" M host/a.cpp"])
        self.assertEqual(len(state["diff_sha256"]), 64)

    def test_untracked_source_is_dirty_for_every_study(self):
        write(self.repo, "host/b.cpp", "int b;\n")
        state = provenance.tree_state(self.repo)
        self.assertIs(state["dirty"], True)
        self.assertEqual(state["dirty_paths"], ["?? host/b.cpp"])
        self.assertTrue(provenance.commit_of(self.repo).endswith("-dirty"))
        self.assertTrue(cli_runs.commit_of(self.repo).endswith("-dirty"))  # the studies' name for it

    def test_hash_follows_untracked_bytes(self):
        write(self.repo, "host/b.cpp", "int b;\n")
        first = provenance.tree_state(self.repo)["diff_sha256"]
        write(self.repo, "host/b.cpp", "int b = 2;\n")
        self.assertNotEqual(provenance.tree_state(self.repo)["diff_sha256"], first)

    def test_build_and_run_folders_and_ignored_files_are_not_changes(self):
        write(self.repo, "build/CMakeCache.txt", "x\n")
        write(self.repo, "build-tsan/x", "x\n")
        write(self.repo, "runs/quick/summary.json", "{}\n")
        write(self.repo, "host/a.o", "object\n")
        self.assertIs(provenance.tree_state(self.repo)["dirty"], False)

    def test_outside_a_checkout(self):
        with tempfile.TemporaryDirectory() as plain:
            self.assertEqual(provenance.tree_state(plain)["commit"], "unknown")
            self.assertEqual(provenance.commit_of(plain), "unknown")

    def test_file_sha256(self):
        write(self.repo, "f", "abc")
        self.assertEqual(provenance.file_sha256(os.path.join(self.repo, "f")),
                         "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad")


if __name__ == "__main__":
    unittest.main(verbosity=2)
