"""Headless Chromium driven from the command line (--dump-dom, --screenshot): the state a page
sets on <body> and its screenshots, for the checks of `pgvol view` and the scripts that reuse
them (tools/view_screenshot.py, tools/bench/bench_view.py).

Debian's `chromium` (tools/test.sh installs it with apt when missing), or PGVOL_CHROMIUM. As
root it needs --no-sandbox; WebGL runs on SwiftShader, Chromium's CPU renderer.
"""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

# Pages are drawn at this size unless told otherwise.
WINDOW = (800, 600)
# Virtual time the page may use before the DOM is dumped (its script runs on load and needs
# none; this covers a slow machine's first frame).
BUDGET_MS = 20_000


def chromium_path() -> str | None:
    """The Chromium to run, or None when there is none."""
    return os.environ.get("PGVOL_CHROMIUM") or shutil.which("chromium")


def _flags(profile: str, window: tuple[int, int], offline: bool) -> list[str]:
    flags = [
        "--headless=new",
        "--no-sandbox",
        "--enable-unsafe-swiftshader",
        "--use-angle=swiftshader",
        f"--user-data-dir={profile}",
        "--disable-background-networking",
        "--no-first-run",
        "--hide-scrollbars",
        f"--window-size={window[0]},{window[1]}",
        f"--virtual-time-budget={BUDGET_MS}",
    ]
    if offline:
        # No name resolves and no proxy answers: a page that loaded anything would fail.
        flags += ["--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9"]
    return flags


def _url(page: Path, fragment: str) -> str:
    url = page.resolve().as_uri()
    return f"{url}#{fragment}" if fragment else url


def _run(args: list[str], timeout: float) -> subprocess.CompletedProcess:
    exe = chromium_path()
    if exe is None:
        raise FileNotFoundError("chromium is not installed (apt install chromium)")
    with tempfile.TemporaryDirectory(prefix="pgvol-chromium-") as profile:
        argv = [exe, *_flags(profile, args[0], args[1]), *args[2:]]
        return subprocess.run(argv, stdin=subprocess.DEVNULL, capture_output=True, text=True,
                              errors="replace", timeout=timeout)


def dump_dom(page: Path, fragment: str = "", window=WINDOW, offline: bool = False,
             timeout: float = 180) -> str:
    """The page's DOM once loaded and its virtual time budget spent."""
    proc = _run([window, offline, "--dump-dom", _url(page, fragment)], timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"chromium failed ({proc.returncode}): {proc.stderr[-2000:]}")
    return proc.stdout


def body_state(dom: str) -> dict[str, str]:
    """The data-* attributes of <body> in a dumped DOM, without the prefix."""
    match = re.search(r"<body([^>]*)>", dom)
    if not match:
        return {}
    return {k: html.unescape(v) for k, v in re.findall(r'data-([\w-]+)="([^"]*)"', match.group(1))}


def page_state(page: Path, fragment: str = "", **kwargs) -> dict[str, str]:
    """body_state of the page as Chromium leaves it."""
    return body_state(dump_dom(page, fragment, **kwargs))


def screenshot(page: Path, png: Path, fragment: str = "", window=WINDOW, timeout: float = 180) -> Path:
    """A PNG screenshot of the page at `window` size."""
    png = png.resolve()
    proc = _run([window, False, f"--screenshot={png}", _url(page, fragment)], timeout)
    if proc.returncode != 0 or not png.is_file():
        raise RuntimeError(f"chromium made no screenshot ({proc.returncode}): {proc.stderr[-2000:]}")
    return png


def seconds_to_ready(page: Path, fragment: str = "", timeout: float = 300) -> tuple[float, dict[str, str]]:
    """Wall-clock seconds from starting Chromium to the dumped DOM of the ready page (an upper
    bound of the time to ready: it includes Chromium's start and exit), with its state."""
    start = time.perf_counter()
    state = page_state(page, fragment, timeout=timeout)
    return time.perf_counter() - start, state
