#!/usr/bin/env python3
"""Open every domain's `--view` page in headless Chromium and check what a person would see.

For each page (made here by the `liemid` binary given with --liemid):
- the page is self-contained: no `src`/`href`/`url(` outside the page itself in its markup;
- it made no network request while open: Chromium runs with a proxy on 127.0.0.1 (this
  script's own socket, loopback included) and every connection that reaches it is a
  request that left the page;
- the WebGL canvas is not blank: the 3-D area of a screenshot holds enough distinct
  colours;
- the scene moves: screenshots after 1.5 s and 4 s of virtual time differ (a still page gets one
  more look at 8 s, for a loaded machine, and then its first and middle frames are opened
  with `#frame=N` and compared, since SwiftShader may draw only one or two frames of a heavy
  scene and a scene that comes to rest may show its resting frames in both looks).

The checker is tested first on two pages that must fail: one with a deliberate
`<img src="http://example.invalid/x.png">` (a request) and one with nothing drawn (blank).
Without Chromium (`chromium` on PATH, or $CHROMIUM) the test is skipped with a message.
Needs numpy and Pillow. Exits 1 if any check fails.
"""

import argparse
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import threading
from pathlib import Path
from typing import List, Optional, Tuple

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent
WINDOW = (1000, 700)
# The 3-D stage: left of the side panel (340 px), above the controls (44 px).
STAGE = (0, 0, WINDOW[0] - 340, WINDOW[1] - 44)
# A blank stage (background, grid and anti-aliased edges only) shows 35 distinct colours;
# the pages measured here show 57 (a 4-body arm seen from afar) to 16,000, and the rigid
# box 63 to 75 depending on its attitude at the screenshot. The bar sits between the two.
MIN_COLOURS = 45
MIN_CHANGED = 0.002
# Chromium's own background requests (component updates, network time, sign-in) go through
# the proxy too; they are told apart by host: these, and whatever hosts Chromium asks for
# on an empty page at the start of the test. A page's request to any other host fails it.
BROWSER_HOSTS = {
    "clients2.google.com",
    "update.googleapis.com",
    "redirector.gvt1.com",
    "accounts.google.com",
    "optimizationguide-pa.googleapis.com",
    "safebrowsingohttpgateway.googleapis.com",
}


def host_of(request_line: str) -> str:
    """The host of a proxy request line (`CONNECT host:443 ...` or `GET http://host/...`)."""
    parts = request_line.split()
    target = parts[1] if len(parts) > 1 else ""
    if "://" in target:
        target = target.split("://", 1)[1]
    return target.split("/", 1)[0].rsplit(":", 1)[0].lower()


class Proxy:
    """A listening socket that counts (and refuses) every connection Chromium opens."""

    def __init__(self) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.listen(16)
        self.sock.settimeout(0.2)
        self.port = self.sock.getsockname()[1]
        self.requests: List[str] = []
        self.stop = False
        self.thread = threading.Thread(target=self.serve, daemon=True)
        self.thread.start()

    def serve(self) -> None:
        while not self.stop:
            try:
                conn, _ = self.sock.accept()
            except socket.timeout:
                continue
            except OSError:
                return
            with conn:
                conn.settimeout(2.0)
                try:
                    data = conn.recv(4096)
                    line = data.split(b"\r\n", 1)[0].decode("latin-1")
                except OSError:
                    line = "(no request line)"
                    data = b"(idle)"
                # A connection closed without a byte (Chromium's speculative preconnect,
                # dropped as the browser exits) fetches nothing. An idle one is still
                # counted: it holds this one-at-a-time proxy while a real request waits.
                if data or line:
                    self.requests.append(line)
                try:
                    conn.sendall(b"HTTP/1.1 403 Forbidden\r\nContent-Length: 0\r\nConnection: close\r\n\r\n")
                except OSError:
                    pass

    def take(self) -> List[str]:
        """The requests since the last call, less Chromium's own."""
        got, self.requests = self.requests, []
        return [r for r in got if host_of(r) not in BROWSER_HOSTS and not host_of(r).endswith(".gvt1.com")]

    def close(self) -> None:
        self.stop = True
        self.thread.join(timeout=2)
        self.sock.close()


def chromium() -> Optional[str]:
    for name in [os.environ.get("CHROMIUM", ""), "chromium", "chromium-browser", "google-chrome"]:
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def screenshot(browser: str, proxy: Proxy, page: Path, out: Path, budget_ms: int, profile: Path, fragment: str = "") -> List[str]:
    """A screenshot of `page` after `budget_ms` of virtual time; returns the requests seen."""
    cmd = [
        browser,
        "--headless",
        "--no-sandbox",
        "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader",
        f"--window-size={WINDOW[0]},{WINDOW[1]}",
        f"--virtual-time-budget={budget_ms}",
        f"--screenshot={out}",
        f"--proxy-server=http://127.0.0.1:{proxy.port}",
        "--proxy-bypass-list=<-loopback>",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        "--no-default-browser-check",
        "--hide-scrollbars",
        f"--user-data-dir={profile}",
        page.resolve().as_uri() + fragment,
    ]
    if out.exists():
        out.unlink()
    subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, timeout=180, check=False)
    if not out.exists():
        raise RuntimeError(f"Chromium wrote no screenshot of {page}")
    return proxy.take()


def stage(png: Path) -> "np.ndarray":
    img = np.asarray(Image.open(png).convert("RGB"))
    x0, y0, x1, y1 = STAGE
    return img[y0:y1, x0:x1]


def distinct_colours(a: "np.ndarray") -> int:
    flat = a.reshape(-1, 3).astype(np.uint32)
    return int(np.unique((flat[:, 0] << 16) | (flat[:, 1] << 8) | flat[:, 2]).size)


def changed(a: "np.ndarray", b: "np.ndarray") -> float:
    return float(np.mean(np.any(np.abs(a.astype(int) - b.astype(int)) > 8, axis=2)))


def markup_links(html: str) -> List[str]:
    """`src`, `href` and `url(` references in the page's markup (script bodies removed)
    that point outside the page (not data:, blob: or #)."""
    markup = re.sub(r"(?is)(<script\b[^>]*>).*?</script>", r"\1</script>", html)
    markup = re.sub(r"(?s)<!--.*?-->", "", markup)
    found = re.findall(r"""(?i)\b(?:src|href|srcset|poster|data)\s*=\s*["']?([^"'\s>]+)""", markup)
    found += re.findall(r"""(?i)url\(\s*["']?([^"')]+)""", markup)
    return [u for u in found if not u.startswith(("data:", "blob:", "#"))]


def check(browser: str, proxy: Proxy, page: Path, shots: Path, name: str) -> Tuple[List[str], dict]:
    """The failures of one page (empty when it passes) and its measurements."""
    failures = []
    html = page.read_text(encoding="utf-8", errors="replace")
    links = markup_links(html)
    if links:
        failures.append(f"references outside the page: {links[:3]}")
    frames = re.search(r"(\d+) frames of (\d+) steps", html)
    if not frames:
        failures.append("the page does not state how many frames it holds of how many steps")
    with tempfile.TemporaryDirectory() as profile:
        early, late = shots / f"{name}-1500.png", shots / f"{name}-4000.png"
        requests = screenshot(browser, proxy, page, early, 1500, Path(profile))
        requests += screenshot(browser, proxy, page, late, 4000, Path(profile))
        a, b = stage(early), stage(late)
        moved = changed(a, b)
        if moved < MIN_CHANGED:
            # Headless Chromium on a loaded machine sometimes spends the whole 4 s budget
            # decoding a large page; one later look tells a slow page from a still one.
            later = shots / f"{name}-8000.png"
            requests += screenshot(browser, proxy, page, later, 8000, Path(profile))
            b = stage(later)
            moved = changed(a, b)
        if moved < MIN_CHANGED and frames and int(frames.group(1)) > 1:
            # SwiftShader sometimes draws only one or two frames of a heavy scene within the
            # budget, and a scene that comes to rest (a dropped cube) can show its resting
            # frames in both looks; the slider's own path (`#frame=N`) opens the first and
            # the middle frame, which show whether two moments of the run look different.
            first, middle = shots / f"{name}-first.png", shots / f"{name}-middle.png"
            requests += screenshot(browser, proxy, page, first, 1500, Path(profile), "#frame=0")
            fragment = f"#frame={int(frames.group(1)) // 2}"
            requests += screenshot(browser, proxy, page, middle, 1500, Path(profile), fragment)
            a, b = stage(first), stage(middle)
            moved = changed(a, b)
    if requests:
        failures.append(f"{len(requests)} network request(s) left the page: {requests[:3]}")
    colours = distinct_colours(b)
    if colours < MIN_COLOURS:
        failures.append(f"the canvas is blank: {colours} distinct colours (at least {MIN_COLOURS} expected)")
    if moved < MIN_CHANGED:
        failures.append(f"nothing moved between 1.5 s and 4 s (nor 8 s, nor between the first and the middle frame): {100 * moved:.3f} % of the stage changed")
    measured = {
        "bytes": page.stat().st_size,
        "frames": frames.group(0) if frames else None,
        "colours": colours,
        "changed": moved,
    }
    return failures, measured


def make_pages(liemid: Path, work: Path) -> List[Tuple[str, Path]]:
    ex = ROOT / "examples"
    runs = {
        "rigid": ["run", str(ex / "tennis_racket_flip.toml"), "--no-output", "--step", "1e-2"],
        "many": ["many", "--scenario", str(ex / "dipolar_fluid.toml"), "--bodies", "125", "--t-end", "3", "--out", str(work / "totals.csv")],
        "spins": ["spins", str(ex / "spins_square.toml"), "--out", str(work / "spins.csv")],
        "beam": ["beam", "--t-end", "10"],
        "multibody": ["multibody", "--problem", "chain-10", "--t-end", "2", "--every", "20"],
        # The model's own shapes and a floor (MJCF geoms; the arm's visuals are meshes read
        # from examples/multibody/meshes/: STL and OBJ). The arm's actuators hold its
        # keyframe still, so a control away from it makes the page move (the servos swing
        # both links and the wrist's motor turns it).
        "multibody-humanoid": ["multibody", str(ex / "multibody" / "humanoid_scene.xml"), "--t-end", "1"],
        "multibody-arm": ["multibody", str(ex / "multibody" / "arm_scene.xml"), "--t-end", "1", "--ctrl", "1.5,-0.5,3"],
        # Contacts: a cube dropped tilted lands on an edge and falls onto a face; the page
        # draws its touching contacts and their forces.
        "multibody-contact": ["multibody", str(ROOT / "benchmarks" / "models" / "contact_tilted_cube.xml"), "--t-end", "1"],
    }
    pages = []
    for name, args in runs.items():
        page = work / f"view-{name}.html"
        done = subprocess.run([str(liemid), *args, "--view", str(page)], cwd=work, capture_output=True, text=True)
        if done.returncode != 0:
            raise RuntimeError(f"liemid {' '.join(args)} --view failed: {done.stderr.strip()}")
        pages.append((name, page))
    return pages


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--liemid", type=Path, required=True, help="the liemid binary")
    parser.add_argument("--shots", type=Path, help="keep the screenshots in this folder")
    parser.add_argument("pages", nargs="*", type=Path, help="check these pages instead of making one per domain")
    args = parser.parse_args()
    browser = chromium()
    if browser is None:
        print("browser test: SKIPPED: no Chromium on this machine (apt-get install chromium, or set $CHROMIUM)")
        return 0
    args.liemid = args.liemid.resolve()
    work = Path(tempfile.mkdtemp(prefix="liemid-view-"))
    shots = args.shots or work
    shots.mkdir(parents=True, exist_ok=True)
    proxy = Proxy()
    passed = failed = 0
    try:
        empty = work / "empty.html"
        empty.write_text("<!DOCTYPE html><html><body></body></html>")
        with tempfile.TemporaryDirectory() as profile:
            for _ in range(2):
                own = screenshot(browser, proxy, empty, work / "empty.png", 1500, Path(profile))
                BROWSER_HOSTS.update(host_of(r) for r in own)
        # The checker must catch a request and a blank canvas.
        leaky = work / "leaky.html"
        leaky.write_text('<!DOCTYPE html><html><body><img src="http://example.invalid/x.png"><p>x</p></body></html>')
        problems, _ = check(browser, proxy, leaky, shots, "selftest-leaky")
        caught = any("network request" in p for p in problems) and any("outside the page" in p for p in problems)
        print(f"{'ok  ' if caught else 'FAIL'} self-test: a page loading http://example.invalid is caught: {problems[:2]}")
        passed, failed = passed + caught, failed + (not caught)
        blank = work / "blank.html"
        blank.write_text("<!DOCTYPE html><html><body style='background:#222'>1 frames of 1 steps</body></html>")
        problems, _ = check(browser, proxy, blank, shots, "selftest-blank")
        caught = any("blank" in p for p in problems) and not any("network" in p for p in problems)
        print(f"{'ok  ' if caught else 'FAIL'} self-test: a blank page is caught: {problems[:2]}")
        passed, failed = passed + caught, failed + (not caught)
        pages = [(p.stem, p) for p in args.pages] or make_pages(args.liemid, work)
        for name, page in pages:
            problems, m = check(browser, proxy, page, shots, name)
            status = "FAIL" if problems else "ok  "
            print(
                f"{status} {name}: {m['bytes'] / 1e6:.2f} MB, {m['frames']}, {m['colours']} distinct colours, "
                f"{100 * m['changed']:.2f} % of the stage changed between 1.5 s and 4 s"
                + ("".join(f"\n       {p}" for p in problems))
            )
            passed, failed = passed + (not problems), failed + bool(problems)
    finally:
        proxy.close()
        if not args.shots:
            shutil.rmtree(work, ignore_errors=True)
    print(f"browser test: {passed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
