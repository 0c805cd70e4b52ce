#!/usr/bin/env python3
"""`mipnerf-cl view` as a server, through its socket: what another web page, another process on the machine, or a
careless script can send it. Runs the real executable on a copy of a trained run and checks:

  forged    a DNS-rebinding Host, another origin, a cross-site fetch, a form or text/plain POST: 403 or 415, and
            nothing rendered or written into the run folder
  oversized a body, a request target, many headers: refused, and the viewer still answers
  idle      connections opened and left silent do not stop the viewer answering others
  at once   renders, path starts, cancels, status polls and file reads from many threads: every request answered
            with a status the route may give, exactly one path started per round of simultaneous starts, and the
            viewer still serves afterwards
  token     with --host 0.0.0.0 the token is required on every route (any Host name is accepted there, with it)
  Ctrl-C    stops the viewer with exit status 0

  tests/view/test_server.py --exe build/mipnerf-cl --run RUN [--work DIR]

Exit 0 when every check passed, 1 otherwise (each failure printed).
"""
import argparse
import gzip
import http.client
import json
import os
import pathlib
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time

CAMERA = {"frames": [{"transform_matrix": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 4], [0, 0, 0, 1]],
                      "fl_x": 20, "fl_y": 20, "cx": 8, "cy": 8, "w": 16, "h": 16}]}
KEYFRAMES = {"frames": [CAMERA["frames"][0],
                        dict(CAMERA["frames"][0], transform_matrix=[[1, 0, 0, 0.5], [0, 1, 0, 0], [0, 0, 1, 4],
                                                                    [0, 0, 0, 1]])]}
FAILURES = []


def check(condition, what):
    print(("ok:     " if condition else "FAILED: ") + what, flush=True)
    if not condition:
        FAILURES.append(what)


class Viewer:
    """A running `mipnerf-cl view`, its port and token."""

    def __init__(self, exe, run, *extra):
        self.process = subprocess.Popen([exe, "view", run, "--port", "0", *extra], stdout=subprocess.PIPE,
                                        stderr=subprocess.STDOUT, text=True)
        self.lines = []
        deadline = time.time() + 120
        while time.time() < deadline:
            line = self.process.stdout.readline()
            if not line:
                break
            self.lines.append(line)
            found = re.search(r"at http://([^/]+):(\d+)/(\?token=([0-9a-f]+))?", line)
            if found:
                self.port = int(found.group(2))
                self.token = found.group(4) or ""
                break
        else:
            raise RuntimeError("view printed no URL in 120 s")
        if not hasattr(self, "port"):
            raise RuntimeError("view ended before serving:\n" + "".join(self.lines))
        self.host = f"127.0.0.1:{self.port}"
        threading.Thread(target=self._drain, daemon=True).start()

    def _drain(self):
        for line in self.process.stdout:
            self.lines.append(line)

    def with_token(self, target):
        if not self.token:
            return target
        return target + ("&" if "?" in target else "?") + "token=" + self.token

    def request(self, method, target, body=None, headers=None, host=None, timeout=60):
        """(status, body bytes); the Host header is the viewer's own unless `host` is given."""
        connection = http.client.HTTPConnection("127.0.0.1", self.port, timeout=timeout)
        try:
            connection.putrequest(method, target, skip_host=True, skip_accept_encoding=True)
            connection.putheader("Host", host if host is not None else self.host)
            data = body.encode() if isinstance(body, str) else body
            for name, value in (headers or {}).items():
                connection.putheader(name, value)
            if data is not None:
                connection.putheader("Content-Length", str(len(data)))
            connection.endheaders(data)
            response = connection.getresponse()
            return response.status, response.read()
        finally:
            connection.close()

    def post_json(self, target, payload, **kwargs):
        headers = {"Content-Type": "application/json", "Origin": f"http://{self.host}",
                   "Sec-Fetch-Site": "same-origin"}
        headers.update(kwargs.pop("headers", {}))
        return self.request("POST", self.with_token(target), json.dumps(payload), headers, **kwargs)

    def peak_rss_kib(self):
        with open(f"/proc/{self.process.pid}/status") as f:
            return int(re.search(r"VmHWM:\s+(\d+)", f.read()).group(1))

    def stop(self):
        self.process.send_signal(signal.SIGINT)
        try:
            status = self.process.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.process.kill()
            status = "hung"
        return status


def path_request(frames=3):
    return {"keyframes": KEYFRAMES, "frames": frames, "divisor": 1, "fps": 24}


def wait_path(viewer, seconds=120):
    deadline = time.time() + seconds
    while time.time() < deadline:
        status, body = viewer.request("GET", viewer.with_token("/api/path"))
        if status == 200 and json.loads(body)["state"] != "rendering":
            return json.loads(body)["state"]
        time.sleep(0.05)
    return "still rendering"


def path_folders(run):
    folder = pathlib.Path(run) / "view_paths"
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def check_forged(viewer, run):
    for host in ("attacker.example:%d" % viewer.port, "attacker.example", "127.0.0.1:%d" % (viewer.port + 1),
                 "localhost.attacker.example:%d" % viewer.port, ""):
        for target in ("/", "/api/run", "/run/config.json", "/api/cameras"):
            status, body = viewer.request("GET", target, host=host)
            check(status == 403 and b"steps" not in body, f"GET {target} with Host '{host}': 403 ({status})")
    before = path_folders(run)
    for origin in ("http://attacker.example", "null", f"https://{viewer.host}"):
        status, _ = viewer.post_json("/api/path", path_request(), headers={"Origin": origin, "Sec-Fetch-Site": ""})
        check(status == 403, f"POST /api/path from Origin '{origin}': 403 ({status})")
        status, _ = viewer.post_json("/api/render", {"camera": CAMERA, "divisor": 1, "generation": 1},
                                     headers={"Origin": origin, "Sec-Fetch-Site": ""})
        check(status == 403, f"POST /api/render from Origin '{origin}': 403 ({status})")
    status, _ = viewer.post_json("/api/path", path_request(), headers={"Origin": "", "Sec-Fetch-Site": "cross-site"})
    check(status == 403, f"POST /api/path with Sec-Fetch-Site cross-site: 403 ({status})")
    for content_type in ("text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=b"):
        status, _ = viewer.request("POST", "/api/path", json.dumps(path_request()),
                                   {"Content-Type": content_type, "Origin": f"http://{viewer.host}"})
        check(status == 415, f"POST /api/path as {content_type}: 415 ({status})")
    status, _ = viewer.request("POST", "/api/path", json.dumps(path_request()),
                               {"Content-Type": "application/json"}, host=f"attacker.example:{viewer.port}")
    check(status == 403, f"POST /api/path with a rebinding Host: 403 ({status})")
    status, _ = viewer.request("GET", "/api/run", headers={"Host": f"attacker.example:{viewer.port}"})
    check(status == 403, f"GET /api/run with two Host headers, the second another's: 403 ({status})")
    check(path_folders(run) == before, "no forged request wrote a path into the run folder")


def check_oversized(viewer):
    status, _ = viewer.post_json("/api/render", {"camera": CAMERA, "pad": "x" * (1 << 20)})
    check(status == 413, f"a 1 MiB body: 413 ({status})")
    status, _ = viewer.request("GET", "/run/" + "a" * 20000)
    check(status in (414, 400), f"a 20 KB request target: 414 or 400 ({status})")
    many = {f"X-Filler-{i}": "y" * 100 for i in range(400)}
    status, _ = viewer.request("GET", "/api/run", headers=many)
    check(status == 431, f"400 headers of 100 bytes: 431 ({status})")
    # Decompression bombs as request bodies: 60 MiB of zeros in 60 KB of gzip (within the body limit as sent). The
    # server library would inflate it whole before the handler saw it; refused unread instead, memory unchanged.
    peak_before = viewer.peak_rss_kib()
    bomb = gzip.compress(b"\0" * (60 << 20), 9)
    status, _ = viewer.request("POST", "/api/render", bomb, {"Content-Type": "application/json",
                                                            "Content-Encoding": "gzip"})
    grown = viewer.peak_rss_kib() - peak_before
    check(status == 415 and grown < 16 << 10, f"a gzip bomb body ({len(bomb)} B -> 60 MiB): 415 ({status}), "
                                              f"peak memory grew {grown} KiB")
    # A chunked body declares no length: bounded as it arrives.
    with socket.create_connection(("127.0.0.1", viewer.port), timeout=30) as s:
        s.sendall(f"POST /api/render HTTP/1.1\r\nHost: {viewer.host}\r\nContent-Type: application/json\r\n"
                  "Transfer-Encoding: chunked\r\n\r\n".encode())
        chunk = b"x" * 8192
        try:
            for _ in range(200):  # 1.6 MB, far past the 64 KB limit
                s.sendall(b"2000\r\n" + chunk + b"\r\n")
        except OSError:
            pass  # the server answered and closed while we were still sending
        reply = s.recv(200)
    check(reply.startswith(b"HTTP/1.1 413"), f"a chunked body past the limit: 413 ({reply[:20]!r})")
    # Many byte ranges of one file: each a copy in the answer. Several ranges are ignored (the whole file, once).
    status, whole = viewer.request("GET", viewer.with_token("/run/config.json"))
    status, body = viewer.request("GET", viewer.with_token("/run/config.json"),
                                  headers={"Range": "bytes=" + ",".join(["0-"] * 1500)})
    check(status == 200 and len(body) == len(whole), f"1,500 byte ranges: the file once ({status}, {len(body)} "
                                                     f"bytes of a {len(whole)}-byte file)")
    status, body = viewer.request("GET", viewer.with_token("/run/config.json"), headers={"Range": "bytes=0-9"})
    check(status == 200 and body == whole, f"one byte range: the whole file with 200, never a part as 200 "
                                           f"({status}, {len(body)} bytes)")
    # A body that claims 1 GiB and sends nothing more: refused by its length, not read.
    with socket.create_connection(("127.0.0.1", viewer.port), timeout=30) as s:
        s.sendall(f"POST /api/render HTTP/1.1\r\nHost: {viewer.host}\r\nContent-Type: application/json\r\n"
                  f"Content-Length: {1 << 30}\r\n\r\n".encode())
        reply = s.recv(200)
    check(reply.startswith(b"HTTP/1.1 413"), f"a declared 1 GiB body: 413 without reading it ({reply[:20]!r})")
    status, _ = viewer.request("GET", viewer.with_token("/api/run"))
    check(status == 200, f"after the oversized requests the viewer still answers ({status})")


def check_idle(viewer):
    # Silent connections, more than the viewer's worker threads: each is dropped after the read timeout, and requests
    # on other connections are answered meanwhile (the threads are not all taken by silence for long).
    idle = [socket.create_connection(("127.0.0.1", viewer.port), timeout=30) for _ in range(12)]
    try:
        started = time.time()
        status, _ = viewer.request("GET", viewer.with_token("/api/run"), timeout=60)
        waited = time.time() - started
        check(status == 200 and waited < 30, f"12 silent connections open: a request answered in {waited:.1f} s")
    finally:
        for s in idle:
            s.close()


def check_at_once(viewer):
    # Rounds of simultaneous path starts (a double-click, a script): exactly one starts, the others get 409.
    for round_ in range(3):
        barrier = threading.Barrier(4)
        statuses = []

        def start():
            barrier.wait()
            statuses.append(viewer.post_json("/api/path", path_request(frames=400))[0])

        threads = [threading.Thread(target=start) for _ in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        check(sorted(statuses) == [202, 409, 409, 409], f"round {round_}: 4 path starts at once: {sorted(statuses)}")
        viewer.post_json("/api/path/cancel", {})
        check(wait_path(viewer) in ("cancelled", "done"), f"round {round_}: the path ends once cancelled")
    # Everything at once for a few seconds.
    allowed = {"render": {200, 409, 503}, "path": {202, 409}, "cancel": {200}, "poll": {200}, "file": {200},
               "run": {200}}
    bad = []
    counts = {k: 0 for k in allowed}
    stop = time.time() + 6
    generation = [0]
    lock = threading.Lock()

    def worker(kind):
        while time.time() < stop:
            try:
                if kind == "render":
                    with lock:
                        generation[0] += 1
                        g = generation[0]
                    status, _ = viewer.post_json("/api/render", {"camera": CAMERA, "divisor": 2, "generation": g})
                elif kind == "path":
                    status, _ = viewer.post_json("/api/path", path_request())
                elif kind == "cancel":
                    status, _ = viewer.post_json("/api/path/cancel", {})
                elif kind == "poll":
                    status, _ = viewer.request("GET", viewer.with_token("/api/path"))
                elif kind == "file":
                    status, _ = viewer.request("GET", viewer.with_token("/run/config.json"))
                else:
                    status, _ = viewer.request("GET", viewer.with_token("/api/run"))
            except (OSError, http.client.HTTPException) as e:
                status = f"{type(e).__name__}: {e}"
            with lock:
                counts[kind] += 1
                if status not in allowed[kind]:
                    bad.append((kind, status))
            if kind in ("path", "cancel"):
                time.sleep(0.05)

    kinds = ["render", "render", "path", "path", "cancel", "poll", "file", "run"]
    threads = [threading.Thread(target=worker, args=(k,)) for k in kinds]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    check(not bad, f"{sum(counts.values())} requests at once ({counts}): every status one its route may give "
                   f"(unexpected: {bad[:5]})")
    check(wait_path(viewer) in ("cancelled", "done", "idle"), "the last path ends")
    status, body = viewer.post_json("/api/render", {"camera": CAMERA, "divisor": 1, "generation": generation[0] + 1})
    check(status == 200 and body.startswith(b"\x89PNG"), f"afterwards a render answers a PNG ({status})")
    status, _ = viewer.post_json("/api/path", path_request())
    check(status == 202 and wait_path(viewer) == "done", f"afterwards a whole path renders ({status})")


def check_token(exe, run):
    viewer = Viewer(exe, run, "--host", "0.0.0.0")
    try:
        check(len(viewer.token) == 32, f"--host 0.0.0.0 prints a URL with a 128-bit token ({viewer.token!r})")
        for target in ("/", "/api/run", "/run/config.json", "/api/cameras", "/api/path"):
            status, _ = viewer.request("GET", target)
            check(status == 403, f"--host 0.0.0.0: GET {target} without the token: 403 ({status})")
            status, _ = viewer.request("GET", target + "?token=" + "0" * 32)
            check(status == 403, f"--host 0.0.0.0: GET {target} with a wrong token: 403 ({status})")
            status, _ = viewer.request("GET", viewer.with_token(target), host=f"my-laptop.lan:{viewer.port}")
            check(status == 200, f"--host 0.0.0.0: GET {target} with the token, by another name: 200 ({status})")
        status, _ = viewer.request("POST", "/api/render", json.dumps({"camera": CAMERA, "divisor": 1, "generation": 1}),
                                   {"Content-Type": "application/json"})
        check(status == 403, f"--host 0.0.0.0: POST /api/render without the token: 403 ({status})")
        status, _ = viewer.post_json("/api/render", {"camera": CAMERA, "divisor": 1, "generation": 1})
        check(status == 200, f"--host 0.0.0.0: POST /api/render with the token: 200 ({status})")
        status, _ = viewer.request("POST", viewer.with_token("/api/path"), json.dumps(path_request()),
                                   {"Content-Type": "text/plain"})
        check(status == 415, f"--host 0.0.0.0: a text/plain POST with the token: 415 ({status})")
    finally:
        status = viewer.stop()
    check(status == 0, f"--host 0.0.0.0: Ctrl-C stops the viewer with status 0 ({status})")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", required=True)
    parser.add_argument("--run", required=True, help="a trained run folder (train --out); copied, never written")
    parser.add_argument("--work", help="scratch folder (default: a temporary one)")
    args = parser.parse_args()
    work = pathlib.Path(args.work or tempfile.mkdtemp(prefix="mipnerf-view-server-"))
    run = work / "run"
    shutil.rmtree(run, ignore_errors=True)
    shutil.copytree(args.run, run)
    viewer = Viewer(args.exe, str(run))
    try:
        check(viewer.token == "", "on 127.0.0.1 no token is asked")
        check_forged(viewer, run)
        check_oversized(viewer)
        check_idle(viewer)
        check_at_once(viewer)
    finally:
        status = viewer.stop()
    check(status == 0, f"Ctrl-C stops the viewer with status 0 ({status})")
    check(any("stopped" in line for line in viewer.lines), "the viewer says it stopped")
    check_token(args.exe, str(run))
    if not args.work:
        shutil.rmtree(work, ignore_errors=True)
    if FAILURES:
        print(f"view server: {len(FAILURES)} checks failed", file=sys.stderr)
        print("".join(viewer.lines[-40:]), file=sys.stderr)
        return 1
    print("view server: every check passed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
