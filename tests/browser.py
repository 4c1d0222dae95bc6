"""A headless Chromium driven through the DevTools protocol over a pipe, with the standard library alone.

``chromium --remote-debugging-pipe`` reads protocol commands from its file descriptor 3 and writes answers and
events to 4, each a JSON text ended by a NUL byte. :class:`Browser` starts it with two pipes on those numbers
(moved there in the child, before the browser starts; every other descriptor of this process is closed on exec),
opens one page, and collects what a page test needs: the console's errors, uncaught exceptions, failed loads and
every URL the page requested; :meth:`Browser.evaluate` runs JavaScript in the page, :meth:`Browser.screenshot`
takes a PNG (of the whole page, or of a part of it).

The timeouts only keep a broken browser from hanging the suite; nothing here measures speed.
"""

from __future__ import annotations

import base64
import fcntl
import json
import os
import queue
import shutil
import subprocess
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")
FLAGS = ("--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--disable-default-apps", "--mute-audio", "--hide-scrollbars", "--remote-debugging-pipe")
WAIT_S = 120.0
"""How long to wait for an answer before calling the browser broken (on a loaded machine starting it takes
seconds; this is no performance bound)."""


def find_chromium() -> str | None:
    """The path of a Chromium (or Chrome) on ``PATH``, or None."""
    return next((path for path in map(shutil.which, NAMES) if path), None)


SOCKET_ROOM = 50
"""The longest folder for the browser's profile and temporary files: it makes a Unix socket in a folder of its own
in there, and a socket's path has at most 107 characters."""


def _short_folder() -> Path:
    """A new folder for the browser's profile and temporary files (removed by :meth:`Browser.close`): in this
    process's temporary folder, or in /tmp where that one's path is too long for the browser's socket."""
    folder = Path(tempfile.mkdtemp(prefix="cdp-"))
    if len(str(folder)) <= SOCKET_ROOM:
        return folder
    folder.rmdir()
    return Path(tempfile.mkdtemp(prefix="cdp-", dir="/tmp"))


def _above(fd: int, lowest: int = 10) -> int:
    """``fd`` moved to a number of at least ``lowest`` (were it 3 or 4, putting the pipes on 3 and 4 would mix them
    up)."""
    moved = fcntl.fcntl(fd, fcntl.F_DUPFD, lowest)
    os.close(fd)
    return moved


class BrowserError(RuntimeError):
    """The browser did not answer, or answered a command with an error."""


class Browser:
    """One headless browser with one page (use as a context manager)."""

    def __init__(self, executable: str, width: int = 1200, height: int = 900) -> None:
        self.profile = _short_folder()
        to_browser, self._write = os.pipe()
        self._read, from_browser = os.pipe()
        to_browser, from_browser = _above(to_browser), _above(from_browser)  # not 3 or 4 themselves
        command = [executable, *FLAGS, f"--user-data-dir={self.profile}", f"--window-size={width},{height}",
                   "about:blank"]

        def on_3_and_4() -> None:  # in the child, before the browser starts: dup2 leaves the copies inheritable
            os.dup2(to_browser, 3)
            os.dup2(from_browser, 4)

        self.process = subprocess.Popen(command, close_fds=False, preexec_fn=on_3_and_4, stdin=subprocess.DEVNULL,
                                        stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                        env={**os.environ, "TMPDIR": str(self.profile), "HOME": str(self.profile),
                                             "XDG_CONFIG_HOME": str(self.profile / "config"),
                                             "XDG_CACHE_HOME": str(self.profile / "cache")})  # fmt: skip
        os.close(to_browser)
        os.close(from_browser)
        self._messages: queue.Queue[dict] = queue.Queue()
        self._reader = threading.Thread(target=self._receive, daemon=True)
        self._reader.start()
        self._next_id = 0
        self.events: list[dict] = []
        self.session: str | None = None
        self.width, self.height = width, height

    def _receive(self) -> None:
        buffer = b""
        with os.fdopen(self._read, "rb", buffering=0) as pipe:
            while chunk := pipe.read(65536):
                buffer += chunk
                *messages, buffer = buffer.split(b"\0")
                for message in messages:
                    self._messages.put(json.loads(message))

    def _wait(self, test: Any, what: str) -> dict:
        """The first message that passes ``test`` (events before it are kept in :attr:`events`)."""
        deadline = time.monotonic() + WAIT_S
        while True:
            try:
                message = self._messages.get(timeout=max(0.0, deadline - time.monotonic()))
            except queue.Empty:
                raise BrowserError(f"no {what} from the browser within {WAIT_S:g} s") from None
            if test(message):
                return message
            if "method" in message:
                self.events.append(message)

    def send(self, method: str, session: bool = True, **params: Any) -> dict:
        """Send a command (to the page's session unless ``session`` is False) and return its result."""
        self._next_id += 1
        message: dict[str, Any] = {"id": self._next_id, "method": method, "params": params}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self._write, json.dumps(message).encode() + b"\0")
        answer = self._wait(lambda m, i=self._next_id: m.get("id") == i, f"answer to {method}")
        if "error" in answer:
            raise BrowserError(f"{method}: {answer['error']}")
        return answer.get("result", {})

    def open(self, url: str) -> None:
        """Open ``url`` in a new page and wait until it has loaded (images included)."""
        target = self.send("Target.createTarget", session=False, url="about:blank")["targetId"]
        self.session = self.send("Target.attachToTarget", session=False, targetId=target, flatten=True)["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.send(f"{domain}.enable")
        self.send("Page.navigate", url=url)
        self.events.append(self._wait(lambda m: m.get("method") == "Page.loadEventFired", "load event"))

    def emulate(self, width: int, height: int, mobile: bool = True) -> None:
        """Lay the open page out in a viewport of ``width`` x ``height`` CSS pixels, as a phone (``mobile``: the
        page's viewport meta tag applies) or a desktop window; a window narrower than Chromium's own least width
        (some 500 px) can only be had so."""
        self.send("Emulation.setDeviceMetricsOverride", width=width, height=height, deviceScaleFactor=1,
                  mobile=mobile)

    def evaluate(self, expression: str) -> Any:
        """The value of a JavaScript ``expression`` in the page."""
        result = self.send("Runtime.evaluate", expression=expression, returnByValue=True, awaitPromise=True)
        if "exceptionDetails" in result:
            raise BrowserError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def wait_for(self, expression: str, timeout: float = WAIT_S, interval: float = 0.1) -> Any:
        """The first truthy value of ``expression``, asked every ``interval`` seconds (BrowserError after
        ``timeout``: a guard against a hang, no measure of speed)."""
        deadline = time.monotonic() + timeout
        while not (value := self.evaluate(expression)):
            if time.monotonic() > deadline:
                raise BrowserError(f"{expression} stayed false for {timeout:g} s")
            time.sleep(interval)
        return value

    def click(self, selector: str) -> None:
        """Click the element ``selector`` (a CSS selector) finds, once it is there."""
        self.wait_for(f"document.querySelector({json.dumps(selector)}) !== null")
        self.evaluate(f"document.querySelector({json.dumps(selector)}).click()")

    def type_into(self, selector: str, text: str) -> None:
        """Replace the text of the input field ``selector`` by ``text``, typed as a user types it."""
        self.wait_for(f"document.querySelector({json.dumps(selector)}) !== null")
        found = f"document.querySelector({json.dumps(selector)})"
        self.evaluate(f"(() => {{ const e = {found}; e.focus(); e.select(); }})()")
        self.send("Input.insertText", text=text)

    def drain(self) -> list[dict]:
        """Every event received so far."""
        while True:
            try:
                message = self._messages.get_nowait()
            except queue.Empty:
                return self.events
            if "method" in message:
                self.events.append(message)

    def errors(self) -> list[str]:
        """The console's errors, uncaught exceptions and failed loads so far, one line each."""
        lines = []
        for event in self.drain():
            method, params = event["method"], event.get("params", {})
            if method == "Runtime.exceptionThrown":
                lines.append(f"exception: {params['exceptionDetails'].get('text')}")
            elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
                lines.append(f"console.{params['type']}: {[a.get('value') for a in params.get('args', [])]}")
            elif method == "Log.entryAdded" and params["entry"].get("level") == "error":
                lines.append(f"log: {params['entry'].get('text')} {params['entry'].get('url', '')}")
            elif method == "Network.loadingFailed":
                lines.append(f"failed load: {params.get('errorText')} (request {params.get('requestId')})")
        return lines

    def requested_urls(self) -> list[str]:
        """Every URL the page requested so far."""
        return [e["params"]["request"]["url"] for e in self.drain() if e["method"] == "Network.requestWillBeSent"]

    def screenshot(self, path: Path, clip: dict[str, float] | None = None) -> Path:
        """A PNG of the whole page (its full height), or of ``clip`` (x, y, width, height in CSS pixels)."""
        options: dict[str, Any] = {"format": "png", "captureBeyondViewport": True}
        if clip is not None:
            options["clip"] = {**clip, "scale": 1}
        else:
            size = self.send("Page.getLayoutMetrics")["cssContentSize"]
            options["clip"] = {"x": 0, "y": 0, "width": size["width"], "height": size["height"], "scale": 1}
        path.write_bytes(base64.b64decode(self.send("Page.captureScreenshot", **options)["data"]))
        return path

    def close(self) -> None:
        """End the browser and remove its profile."""
        try:
            self.send("Browser.close", session=False)
        except (BrowserError, OSError):
            pass
        try:
            self.process.wait(timeout=WAIT_S)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()
        os.close(self._write)
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self) -> Browser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
