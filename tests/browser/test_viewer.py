#!/usr/bin/env python3
"""`mipnerf-cl view` in a real browser: Debian's Chromium, headless, driven through chromium-driver by selenium.

Trains a tiny run (a procedural scene, the tiny preset, a few steps, val scores), scores its val view with
ground truth and error images (`eval`), starts `view` on a free port, loads the page, checks that the curves and
the val images are shown, drags the camera, waits for the full-size frame and compares it with
`mipnerf-cl render --path` of the camera the page exposes (bit-equal, or at least 50 dB), saves a screenshot, and
stops the viewer with Ctrl-C (SIGINT), which must end it cleanly. Then a forward-facing capture (make-scene
--forward-facing), trained briefly: the page must open on its first training camera and its first full frame must
be >= 15 dB from that camera's photo.

  tests/browser/test_viewer.py --exe build/mipnerf-cl --work DIR [--junit FILE] [--screenshot FILE.png]
      [--steps 12] [--size 32]

Each check is one test case of the JUnit file. Exit 0: every check passed; 1: one failed; 77: could not run here
(no chromium, chromium-driver or selenium), every case reported skipped.
"""
import argparse
import base64
import json
import math
import os
import pathlib
import re
import shutil
import signal
import struct
import subprocess
import sys
import time
import xml.etree.ElementTree as ElementTree
import zlib

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
CHECKS = ["train a tiny run", "view serves the page", "curves are drawn", "val images are shown",
          "drag renders a full-size frame", "the frame equals mipnerf-cl render",
          "a recorded path renders as frames and a video, as render --frames does", "screenshot", "Ctrl-C stops view",
          "a forward-facing capture opens on its first training camera, a view like its photo"]


class Report:
    def __init__(self):
        self.cases = []  # (name, seconds, failure or None, skipped)

    def add(self, name, seconds, failure=None, skipped=False):
        self.cases.append((name, seconds, failure, skipped))
        state = "skipped" if skipped else ("FAILED: " + failure if failure else "passed")
        print(f"browser: {name}: {state} ({seconds:.1f} s)", flush=True)

    def write(self, path):
        if not path:
            return
        suite = ElementTree.Element("testsuite", name="browser", tests=str(len(self.cases)))
        for name, seconds, failure, skipped in self.cases:
            case = ElementTree.SubElement(suite, "testcase", name=name, classname="browser", time=f"{seconds:.3f}")
            if skipped:
                ElementTree.SubElement(case, "skipped", message=failure or "")
            elif failure:
                ElementTree.SubElement(case, "failure", message=failure)
        ElementTree.ElementTree(suite).write(path, encoding="utf-8", xml_declaration=True)


def decode_png_rgb8(data):
    """Pixels of an 8-bit RGB, non-interlaced PNG (what mipnerf-cl writes) as bytes, with width and height."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", None
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour == 2 and interlace == 0, "expected 8-bit RGB, not interlaced"
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw, stride, out, prev = zlib.decompress(idat), width * 3, bytearray(), bytearray(width * 3)
    for y in range(height):
        f, line = raw[y * (stride + 1)], bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - 3] if i >= 3 else 0
            b, c = prev[i], prev[i - 3] if i >= 3 else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        out += line
        prev = line
    return bytes(out), width, height


def psnr(a, b):
    mse = sum((x - y) ** 2 for x, y in zip(a, b)) / len(a) / 255.0 ** 2
    return math.inf if mse == 0 else -10 * math.log10(mse)


def run(cmd, **kw):
    result = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(map(str, cmd))} exited {result.returncode}: {result.stderr.strip()[-400:]}")
    return result.stdout


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--exe", required=True)
    parser.add_argument("--work", required=True)
    parser.add_argument("--junit")
    parser.add_argument("--screenshot")
    parser.add_argument("--steps", type=int, default=12, help="training steps of the tiny run (the README's: 600)")
    parser.add_argument("--size", type=int, default=32, help="the scene's image size")
    args = parser.parse_args()
    report = Report()
    missing = [p for p in (CHROMIUM, CHROMEDRIVER) if not os.path.exists(p)]
    try:
        from selenium import webdriver
        from selenium.webdriver.common.action_chains import ActionChains
        from selenium.webdriver.common.by import By
    except ImportError:
        missing.append("selenium (scripts/test-browser.sh installs it into a venv)")
    if missing:
        for name in CHECKS:
            report.add(name, 0.0, "cannot run: missing " + ", ".join(missing), skipped=True)
        report.write(args.junit)
        return 77

    exe, work = os.path.abspath(args.exe), pathlib.Path(args.work)
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    run_dir = work / "run"
    viewer = driver = None
    failed = False

    def check(name, body):
        nonlocal failed
        started = time.monotonic()
        if failed:
            report.add(name, 0.0, "not run: an earlier check failed")
            return None
        try:
            value = body()
            report.add(name, time.monotonic() - started)
            return value
        except Exception as e:  # a check's failure, reported with what was seen
            failed = True
            report.add(name, time.monotonic() - started, f"{type(e).__name__}: {e}")
            return None

    def train():
        run([exe, "make-scene", str(work / "scene"), "--size", str(args.size), "--views", "8"])
        run([exe, "train", "--data", str(work / "scene"), "--out", str(run_dir), "--preset", "tiny", "--steps",
             str(args.steps), "--set", f"val_every={max(args.steps // 2, 1)}", "--set", "val_views=1", "--set",
             "batch_size=256", "--set", f"log_every={max(args.steps // 6, 1)}"])
        run([exe, "eval", "--checkpoint", str(run_dir), "--views", "1", "--split", "val"])

    def start_view():
        nonlocal viewer, driver
        viewer = subprocess.Popen([exe, "view", str(run_dir), "--port", "0"], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        line = viewer.stdout.readline()
        match = re.search(r"at (http://127\.0\.0\.1:\d+/)", line)
        if not match:
            raise RuntimeError(f"view printed {line!r}; stderr: {viewer.stderr.read()[-400:] if viewer.poll() is not None else ''}")
        options = webdriver.ChromeOptions()
        options.binary_location = CHROMIUM
        for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--window-size=1400,1000",
                     "--disable-dev-shm-usage"):
            options.add_argument(flag)
        driver = webdriver.Chrome(service=webdriver.ChromeService(executable_path=CHROMEDRIVER), options=options)
        driver.set_script_timeout(60)
        driver.get(match.group(1))
        wait_for(lambda: driver.execute_script("return window.viewer && window.viewer.fullFrames >= 1"), 30,
                 "the first full-size frame")

    def wait_for(condition, seconds, what):
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            if condition():
                return
            time.sleep(0.1)
        raise TimeoutError(f"no {what} after {seconds} s")

    def curves():
        wait_for(lambda: driver.execute_script("return !!(window.viewer.curvePoints)"), 10, "curves")
        points = driver.execute_script("return window.viewer.curvePoints")
        if points["train"] < 2 or points["val"] < 2:
            raise AssertionError(f"curve points {points}: expected >= 2 train and >= 2 val points")
        # The canvas holds drawn pixels of both curves' colours (train #4aa3ff, val #ffb347).
        colours = driver.execute_script("""
            const c = document.getElementById('curve'), d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
            let train = 0, val = 0;
            for (let i = 0; i < d.length; i += 4) {
              if (d[i] === 0x4a && d[i + 1] === 0xa3 && d[i + 2] === 0xff) train++;
              if (d[i] === 0xff && d[i + 1] === 0xb3 && d[i + 2] === 0x47) val++;
            }
            return [train, val];""")
        if colours[0] < 20 or colours[1] < 20:
            raise AssertionError(f"curve pixels (train, val) = {colours}")

    def images():
        wait_for(lambda: driver.execute_script(
            "const im = document.querySelectorAll('#images img'); return im.length >= 4 && "
            "Array.from(im).every((i) => i.complete && i.naturalWidth > 0)"), 15, "loaded val images")
        alts = driver.execute_script("return Array.from(document.querySelectorAll('#images img')).map((i) => i.alt)")
        for needed in ("render", "ground truth", "error"):
            if not any(a.endswith(needed) for a in alts):
                raise AssertionError(f"no '{needed}' image among {alts}")

    def drag():
        before = driver.execute_script("return window.viewer.fullFrames")
        canvas = driver.find_element(By.ID, "view")
        ActionChains(driver).move_to_element(canvas).click_and_hold().move_by_offset(60, 15) \
            .move_by_offset(40, 10).release().perform()
        wait_for(lambda: driver.execute_script(
            "const v = window.viewer; return v.fullFrames > arguments[0] && v.lastFullDone === v.generation", before),
            30, "full-size frame after the drag")
        return driver.execute_script("return [window.viewer.lastFullCamera, window.viewer.lastFullPng]")

    def compare(dragged):
        camera, data_url = dragged
        page_png = base64.b64decode(data_url.split(",", 1)[1])
        (work / "camera.json").write_text(json.dumps(camera))
        run([exe, "render", "--checkpoint", str(run_dir), "--path", str(work / "camera.json"), "--out",
             str(work / "render")])
        cli_png = (work / "render" / "frame_0000.png").read_bytes()
        a, wa, ha = decode_png_rgb8(page_png)
        b, wb, hb = decode_png_rgb8(cli_png)
        if (wa, ha) != (wb, hb):
            raise AssertionError(f"the page's frame is {wa}x{ha}, render's {wb}x{hb}")
        db = psnr(a, b)
        print(f"browser: the page's {wa}x{ha} frame against render's: "
              f"{'bit-equal' if a == b else f'{db:.2f} dB'}", flush=True)
        if a != b and db < 50:
            raise AssertionError(f"the page's frame differs from render's: {db:.2f} dB < 50 dB")

    def record_path():
        # Two keyframes (the dragged view, then one more drag), rendered by the server from the page's button.
        driver.find_element(By.ID, "add-key").click()
        canvas = driver.find_element(By.ID, "view")
        ActionChains(driver).move_to_element(canvas).click_and_hold().move_by_offset(-80, -20).release().perform()
        driver.find_element(By.ID, "add-key").click()
        frames = driver.find_element(By.ID, "path-frames")
        frames.clear()
        frames.send_keys("6")
        driver.find_element(By.ID, "render-path").click()
        wait_for(lambda: driver.execute_script(
            "return window.viewer.path && ['done', 'failed', 'cancelled'].includes(window.viewer.path.state)"), 60,
            "the end of the path render")
        status = driver.execute_script("return window.viewer.path")
        if status["state"] != "done" or status["frames_done"] != 6:
            raise AssertionError(f"path render ended {status}")
        shown = driver.find_element(By.ID, "path-state").text
        if "done: 6/6" not in shown:
            raise AssertionError(f"the page shows {shown!r}")
        folder = run_dir / status["folder"]
        pngs = sorted(p.name for p in folder.glob("frame_*.png"))
        if pngs != [f"frame_{i:04d}.png" for i in range(6)]:
            raise AssertionError(f"{folder} holds {pngs}")
        if status["video"] and (run_dir / status["video"]).stat().st_size == 0:
            raise AssertionError(f"empty video {status['video']}")
        keyframes = driver.execute_script("return window.viewer.keyframes")
        (work / "keys.json").write_text(json.dumps({"frames": keyframes}))
        run([exe, "render", "--checkpoint", str(run_dir), "--path", str(work / "keys.json"), "--frames", "6",
             "--out", str(work / "render_keys")])
        for i in (0, 3, 5):  # the keyframes' ends and a frame between them
            a, wa, ha = decode_png_rgb8((folder / f"frame_{i:04d}.png").read_bytes())
            b, wb, hb = decode_png_rgb8((work / "render_keys" / f"frame_{i:04d}.png").read_bytes())
            if (wa, ha) != (wb, hb) or (a != b and psnr(a, b) < 50):
                raise AssertionError(f"path frame {i} differs from render --frames 6's")
        print(f"browser: path of 2 keyframes, 6 frames in {status['seconds']:.1f} s, video "
              f"{status['video'] or '(none: no video in this build)'}", flush=True)

    def screenshot():
        path = pathlib.Path(args.screenshot) if args.screenshot else work / "viewer.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        if not driver.save_screenshot(str(path)):
            raise RuntimeError("chromium saved no screenshot")

    def stop():
        viewer.send_signal(signal.SIGINT)
        out, err = viewer.communicate(timeout=15)
        if viewer.returncode != 0 or "stopped" not in out:
            raise AssertionError(f"view exited {viewer.returncode} after Ctrl-C; stdout {out[-200:]!r} stderr {err[-200:]!r}")

    def forward_facing():
        # A forward-facing capture (make-scene --forward-facing: an LLFF capture), trained briefly: the page must open
        # on its first training camera, say why, and its first full-size frame must look like that camera's photo
        # (>= 15 dB against the ground truth `eval --split train` writes); an orbit looks from behind the cameras.
        nonlocal viewer
        capture, ff_run = work / "ff-capture", work / "ff-run"
        run([exe, "make-scene", str(capture), "--forward-facing", "--size", "48", "--samples", "1"])
        run([exe, "train", "--data", str(capture), "--out", str(ff_run), "--preset", "tiny", "--steps", "300",
             "--set", "batch_size=256", "--set", "val_views=1"])
        run([exe, "eval", "--checkpoint", str(ff_run), "--split", "train", "--views", "1"])
        viewer = subprocess.Popen([exe, "view", str(ff_run), "--port", "0"], stdout=subprocess.PIPE,
                                  stderr=subprocess.PIPE, text=True)
        match = re.search(r"at (http://127\.0\.0\.1:\d+/)", viewer.stdout.readline())
        if not match:
            raise RuntimeError("view of the forward-facing run printed no URL")
        driver.get(match.group(1))
        wait_for(lambda: driver.execute_script("return window.viewer && window.viewer.fullFrames >= 1"), 60,
                 "the forward-facing run's first full-size frame")
        why = driver.find_element(By.ID, "start-why").text
        if "train camera 0" not in why or "forward-facing" not in why:
            raise AssertionError(f"the page says {why!r}, not that it starts from train camera 0 of a forward-facing capture")
        page_png = base64.b64decode(driver.execute_script("return window.viewer.lastFullPng").split(",", 1)[1])
        a, wa, ha = decode_png_rgb8(page_png)
        b, wb, hb = decode_png_rgb8((ff_run / "eval_train" / "images" / "000_gt.png").read_bytes())
        if (wa, ha) != (wb, hb):
            raise AssertionError(f"the first frame is {wa}x{ha}, the photo {wb}x{hb}")
        db = psnr(a, b)
        print(f"browser: forward-facing capture: the first full frame against train camera 0's photo: {db:.2f} dB",
              flush=True)
        if db < 15:
            raise AssertionError(f"the first frame is {db:.2f} dB from the first training photo (< 15 dB)")
        viewer.send_signal(signal.SIGINT)
        viewer.communicate(timeout=15)

    try:
        check(CHECKS[0], train)
        check(CHECKS[1], start_view)
        check(CHECKS[2], curves)
        check(CHECKS[3], images)
        dragged = check(CHECKS[4], drag)
        check(CHECKS[5], lambda: compare(dragged))
        check(CHECKS[6], record_path)
        check(CHECKS[7], screenshot)
        check(CHECKS[8], stop)
        check(CHECKS[9], forward_facing)
    finally:
        if driver:
            driver.quit()
        if viewer and viewer.poll() is None:
            viewer.kill()
            viewer.wait()
    report.write(args.junit)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
